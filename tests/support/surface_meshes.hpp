#pragma once
// Surface meshes made in code for the tests: a torus of triangles, made poorer along itself, and
// tangled tori (vertices slid along it past their neighbours).
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "paloverde/mesh/cell_types.hpp"
#include "paloverde/mesh/mesh.hpp"

namespace paloverde::test {

// A number in [-1, 1] from the generator, the same on every standard library.
inline double jitter(std::mt19937& random) { return 2.0 * (random() / 4294967295.0) - 1.0; }

// The torus's radii: of the centre circle and of the tube.
inline constexpr double kTorusR = 1.0, kTorusTube = 0.4;

// The torus's point at cell coordinates (i, j) of an nu x nv grid.
inline std::array<double, 3> torus_point(double i, double j, int nu, int nv) {
    constexpr double R = kTorusR, r = kTorusTube, pi = std::numbers::pi;
    const double u = 2 * pi * i / nu, v = 2 * pi * j / nv;
    return {(R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v)};
}

// The torus's outward normal (not of unit length) at p, a point on it or near it.
inline std::array<double, 3> torus_normal(const std::array<double, 3>& p) {
    const double around = std::hypot(p[0], p[1]);
    return {p[0] - kTorusR * p[0] / around, p[1] - kTorusR * p[1] / around, p[2]};
}

// Cells (i, j) of an nu x nv torus grid as quadrilaterals, counterclockwise seen from outside.
inline std::vector<VertexId> torus_quads(int nu, int nv) {
    std::vector<VertexId> quads;
    auto id = [&](int i, int j) { return static_cast<VertexId>((i % nu) * nv + j % nv); };
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) quads.insert(quads.end(), {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
    return quads;
}

// A torus of nu x nv quads cut into triangles, facing outward; with `amount` > 0 each vertex is
// moved in the torus's parameters by up to that fraction of a cell, and so stays on the torus.
inline Mesh torus(int nu, int nv, double amount) {
    std::mt19937 random(7);
    std::vector<double> xyz;
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            const double di = amount * jitter(random), dj = amount * jitter(random);
            const auto p = torus_point(i + di, j + dj, nu, nv);
            xyz.insert(xyz.end(), p.begin(), p.end());
        }
    std::vector<VertexId> triangles;
    const std::vector<VertexId> quads = torus_quads(nu, nv);
    for (std::size_t q = 0; q < quads.size(); q += 4)
        triangles.insert(triangles.end(), {quads[q], quads[q + 1], quads[q + 2], quads[q], quads[q + 2], quads[q + 3]});
    return Mesh(ElementKind::Triangle, std::move(xyz), std::move(triangles));
}

// Vertices (i, j) of the nu x nv torus grid that the tangled tori slide: apart, so that each
// tangle is its own.
inline std::vector<std::array<int, 2>> torus_slides(int nu, int nv) {
    return {{nu / 8, nv / 5}, {3 * nu / 8, nv / 2}, {5 * nu / 8, 4 * nv / 5}, {7 * nu / 8, nv / 3}};
}

// The regular torus's points with each vertex of torus_slides() moved along the torus by 1.5
// cells in i, past its neighbour (i + 1, j): a tangle of the input whose points are all on the
// torus. As triangles (torus()'s cut), two triangles at each such vertex turn over; as
// quadrilaterals (`quads`), the two cells at the edge it crossed.
inline Mesh tangled_torus(int nu, int nv, bool quads = false) {
    std::vector<double> xyz;
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            const auto slid = torus_slides(nu, nv);
            const bool moves = std::find(slid.begin(), slid.end(), std::array<int, 2>{i, j}) != slid.end();
            const auto p = torus_point(i + (moves ? 1.5 : 0.0), j, nu, nv);
            xyz.insert(xyz.end(), p.begin(), p.end());
        }
    if (!quads) {
        Mesh mesh = torus(nu, nv, 0.0);
        return Mesh(ElementKind::Triangle, std::move(xyz), {mesh.connectivity().begin(), mesh.connectivity().end()});
    }
    std::vector<VertexId> cells = torus_quads(nu, nv);
    std::vector<CellType> types(cells.size() / 4, CellType::Quadrilateral);
    return Mesh::from_cells(std::move(xyz), types, std::move(cells));
}

// Elements of a mesh on the torus (its cells' corner elements too) whose normal faces into the
// torus: turned over.
inline int turned_over_on_torus(const Mesh& mesh) {
    int count = 0;
    for (ElementId e = 0; e < mesh.num_elements(); ++e) {
        const auto c = mesh.element(e);
        const auto a = mesh.point(c[0]), b = mesh.point(c[1]), d = mesh.point(c[2]);
        const std::array<double, 3> u{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w{d[0] - a[0], d[1] - a[1], d[2] - a[2]};
        const std::array<double, 3> n{u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
        const auto out = torus_normal({(a[0] + b[0] + d[0]) / 3, (a[1] + b[1] + d[1]) / 3, (a[2] + b[2] + d[2]) / 3});
        count += n[0] * out[0] + n[1] * out[1] + n[2] * out[2] <= 0.0;
    }
    return count;
}

}  // namespace paloverde::test
