#pragma once
// Structured meshes of cells for tests and benchmarks: quadrilaterals, hexahedra, and the
// hexahedra cut into wedges, pyramids or a mix, each cell turned to positive orientation.
#include <array>
#include <cstdint>
#include <vector>

#include "paloverde/mesh/cell_types.hpp"
#include "paloverde/mesh/perturb.hpp"
#include "paloverde/mesh/mesh.hpp"

namespace paloverde::test {

struct CellSoup {
    std::vector<double> xyz;
    std::vector<CellType> types;
    std::vector<VertexId> cells;

    // Adds a cell, mirrored if its first corner frame is negative.
    void add(CellType type, std::vector<VertexId> v) {
        const CellInfo& info = cell_info(type);
        const auto& f = info.frames[0];
        auto p = [&](int i, int d) { return xyz[3 * static_cast<std::size_t>(v[f[i]]) + d] - xyz[3 * static_cast<std::size_t>(v[f[0]]) + d]; };
        double det;
        if (info.dimension == 2) det = p(1, 0) * p(2, 1) - p(1, 1) * p(2, 0);
        else
            det = p(1, 0) * (p(2, 1) * p(3, 2) - p(2, 2) * p(3, 1)) - p(1, 1) * (p(2, 0) * p(3, 2) - p(2, 2) * p(3, 0)) +
                  p(1, 2) * (p(2, 0) * p(3, 1) - p(2, 1) * p(3, 0));
        if (det < 0) {
            std::vector<VertexId> m(v.size());
            for (std::size_t i = 0; i < v.size(); ++i) m[i] = v[static_cast<std::size_t>(info.mirror[i])];
            v = m;
        }
        types.push_back(type);
        cells.insert(cells.end(), v.begin(), v.end());
    }
    VertexId point(double x, double y, double z) {
        xyz.insert(xyz.end(), {x, y, z});
        return static_cast<VertexId>(xyz.size() / 3 - 1);
    }
    Mesh mesh() const {
        Mesh m = Mesh::from_cells(xyz, types, cells);
        m.fix_boundary();
        return m;
    }
};

// A unit square of n x n quadrilaterals.
inline Mesh quad_grid(int n) {
    CellSoup s;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) s.point(double(i) / n, double(j) / n, 0.0);
    auto id = [&](int i, int j) { return static_cast<VertexId>(j * (n + 1) + i); };
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) s.add(CellType::Quadrilateral, {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
    return s.mesh();
}

// What each cube of a grid is cut into.
enum class Fill { Hexahedra, Wedges, Pyramids, Mixed, Tetrahedra };

// A unit cube of n^3 cubes: hexahedra, two wedges each, six pyramids each (about the cube's
// centre), a conforming mix (wedges in every third column along z, whose triangles then meet
// triangles; elsewhere hexahedra and pyramids in a checkerboard), or six tetrahedra each (Kuhn's
// split: one per path from corner 000 to 111 along the axes), the simplex mesh of the same
// vertices to compare with.
inline Mesh cube_grid(int n, Fill fill = Fill::Hexahedra) {
    CellSoup s;
    for (int k = 0; k <= n; ++k)
        for (int j = 0; j <= n; ++j)
            for (int i = 0; i <= n; ++i) s.point(double(i) / n, double(j) / n, double(k) / n);
    auto id = [&](int i, int j, int k) { return static_cast<VertexId>((k * (n + 1) + j) * (n + 1) + i); };
    for (int k = 0; k < n; ++k)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const std::array<VertexId, 8> h = {id(i, j, k),         id(i + 1, j, k),         id(i + 1, j + 1, k),
                                                   id(i, j + 1, k),     id(i, j, k + 1),         id(i + 1, j, k + 1),
                                                   id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1)};
                Fill here = fill;
                if (fill == Fill::Mixed)
                    here = (i + j) % 3 == 0 ? Fill::Wedges : (i + j + k) % 2 ? Fill::Pyramids : Fill::Hexahedra;
                if (here == Fill::Tetrahedra) {
                    const int axes[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
                    for (const auto& order : axes) {
                        int at[3] = {0, 0, 0};
                        std::vector<VertexId> tet{id(i, j, k)};
                        for (int axis : order) {
                            at[axis] = 1;
                            tet.push_back(id(i + at[0], j + at[1], k + at[2]));
                        }
                        s.add(CellType::Tetrahedron, tet);
                    }
                } else if (here == Fill::Hexahedra) {
                    s.add(CellType::Hexahedron, {h.begin(), h.end()});
                } else if (here == Fill::Wedges) {
                    s.add(CellType::Wedge, {h[0], h[1], h[2], h[4], h[5], h[6]});
                    s.add(CellType::Wedge, {h[0], h[2], h[3], h[4], h[6], h[7]});
                } else {
                    const VertexId c = s.point((i + 0.5) / n, (j + 0.5) / n, (k + 0.5) / n);
                    for (const auto& face : cell_info(CellType::Hexahedron).faces)
                        s.add(CellType::Pyramid, {h[face[0]], h[face[1]], h[face[2]], h[face[3]], c});
                }
            }
    return s.mesh();
}

// A grid tangled as the tests of cells tangle it: 30% of its free vertices moved by up to 0.8
// local edge lengths.
inline Mesh tangled(Mesh mesh, int seed) {
    PerturbOptions perturb;
    perturb.fraction = 0.3;
    perturb.amount = 0.8;
    perturb.seed = static_cast<std::uint64_t>(seed);
    paloverde::perturb(mesh, perturb);
    return mesh;
}

}  // namespace paloverde::test
