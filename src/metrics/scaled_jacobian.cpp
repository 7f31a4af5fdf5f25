// The scaled Jacobian, the measure users of hexahedral and quadrilateral meshes read: at a corner,
// the determinant of its three (two) edges divided by their lengths, the sine-like measure of how
// far its angles are from right ones, whatever the edges' lengths. It is taken on the element's
// own corners, not on the simplex a corner map or a target carries them to: it judges the mesh as
// its user sees it, whatever the targets ask for.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "evaluate_together.hpp"
#include "geometry.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/mesh/cell_types.hpp"
#include "paloverde/mesh/mesh.hpp"
#include "scaled_jacobian.hpp"
#include "tet_blocks.hpp"

namespace paloverde::metrics {

namespace {

// The corners of a triangle, each with its two neighbours in an order that keeps the orientation
// (a tetrahedron's: kTetJacobianCorners).
constexpr int kTriCorners[3][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}};

// det(e1, e2, e3) / (|e1| |e2| |e3|) at corner c of x; 0 where an edge has no length.
double corner_jacobian(const double* x, const int (&c)[4]) {
    const P o = load(x, c[0]);
    const P e1 = load(x, c[1]) - o, e2 = load(x, c[2]) - o, e3 = load(x, c[3]) - o;
    const double lengths = norm(e1) * norm(e2) * norm(e3);
    return lengths > 0.0 ? dot(e1, cross(e2, e3)) / lengths : 0.0;
}
// In 2D: the sine of the corner's angle, signed by the normal `n`.
double corner_jacobian(const double* x, const int (&c)[3], const P& n) {
    const P o = load(x, c[0]);
    const P e1 = load(x, c[1]) - o, e2 = load(x, c[2]) - o;
    const double lengths = norm(e1) * norm(e2);
    return lengths > 0.0 ? dot(n, cross(e1, e2)) / lengths : 0.0;
}

// The ideal cell's corner scaled Jacobian for each corner map: a cell's corners are divided by
// it, so that the ideal cell of every type rates 1 (a hexahedron's and a quadrilateral's ideal
// corners are right angles, 1 already; a wedge's triangle corners are not).
const std::vector<double>& ideal_corner_jacobians() {
    static const std::vector<double> table = [] {
        std::vector<double> out(static_cast<std::size_t>(corner_map_count()), 1.0);
        const auto regular = ideal_cell(CellType::Tetrahedron);
        for (int id = 1; id < corner_map_count(); ++id) {
            const CornerMap& m = corner_map(static_cast<std::uint8_t>(id));
            const int d = cell_info(corner_map_cell(static_cast<std::uint8_t>(id))).dimension;
            // The ideal corner W = W_regular M^-1: its edges are the columns of W_regular times
            // M's inverse; its scaled Jacobian is that of M^-1's columns mapped by W_regular.
            double w[3][3] = {};  // w[i] = edge i
            const double det = d == 2 ? m[0][0] * m[1][1] - m[0][1] * m[1][0]
                                      : m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                                            m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                                            m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
            double inverse[3][3] = {};
            if (d == 2) {
                inverse[0][0] = m[1][1] / det, inverse[0][1] = -m[0][1] / det;
                inverse[1][0] = -m[1][0] / det, inverse[1][1] = m[0][0] / det;
            } else {
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j) {
                        const int r0 = (j + 1) % 3, r1 = (j + 2) % 3, c0 = (i + 1) % 3, c1 = (i + 2) % 3;
                        inverse[i][j] = (m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0]) / det;
                    }
            }
            for (int i = 0; i < d; ++i)      // edge i of the ideal corner
                for (int k = 0; k < d; ++k)  // = sum_k (regular edge k) inverse[k][i]
                    for (int r = 0; r < 3; ++r) w[i][r] += (regular[k + 1][r] - regular[0][r]) * inverse[k][i];
            const P e1{w[0][0], w[0][1], w[0][2]}, e2{w[1][0], w[1][1], w[1][2]}, e3{w[2][0], w[2][1], w[2][2]};
            out[static_cast<std::size_t>(id)] = d == 2 ? cross(e1, e2).z / (norm(e1) * norm(e2))
                                                       : dot(e1, cross(e2, e3)) / (norm(e1) * norm(e2) * norm(e3));
        }
        return out;
    }();
    return table;
}

class ScaledJacobian final : public QualityMetric, public BlockRater {
public:
    std::string_view name() const override { return "scaled_jacobian"; }
    bool has_gradient() const override { return false; }

    // A simplex alone: the worst of its corners, over the regular simplex's.
    double value(ElementKind kind, const double* x) const override {
        if (kind == ElementKind::Tetrahedron) {
            // Each of the six edges is measured once: seen from either end its length has the same
            // bits, so the corners' values are corner_jacobian's at half the square roots.
            double length[4][4];
            for (int i = 0; i < 4; ++i)
                for (int j = i + 1; j < 4; ++j) length[i][j] = length[j][i] = norm(load(x, j) - load(x, i));
            double worst = INFINITY;
            for (const auto& c : kTetJacobianCorners) {
                const P o = load(x, c[0]);
                const P e1 = load(x, c[1]) - o, e2 = load(x, c[2]) - o, e3 = load(x, c[3]) - o;
                const double lengths = length[c[0]][c[1]] * length[c[0]][c[2]] * length[c[0]][c[3]];
                worst = std::min(worst, lengths > 0.0 ? dot(e1, cross(e2, e3)) / lengths : 0.0);
            }
            return std::numbers::sqrt2 * worst;
        }
        return triangle(x, normal(x));
    }
    double value_and_gradient(ElementKind, const double*, double*) const override {
        throw OptionError("metric 'scaled_jacobian' is for assessment only and has no gradient");
    }

    void evaluate(const Mesh& mesh, std::span<const double> xyz, ElementId first, ElementId last,
                  double* quality) const override {
        const int k = mesh.corners();
        const auto maps = mesh.corner_maps();
        if (k == 4 && maps.empty()) return evaluate_tet_blocks(mesh, xyz, first, last, quality);
        const auto& ideal = ideal_corner_jacobians();
        double x[12];
        for (ElementId e = first; e < last; ++e) {
            const auto corners = mesh.element(e);
            for (int i = 0; i < k; ++i)
                for (int d = 0; d < 3; ++d) x[3 * i + d] = xyz[3 * static_cast<std::size_t>(corners[i]) + d];
            const std::uint8_t map = maps.empty() ? 0 : maps[e];
            if (k == 4) {
                quality[e - first] = map == 0 ? value(mesh.kind(), x) : corner_jacobian(x, kTetJacobianCorners[0]) / ideal[map];
                continue;
            }
            // A surface mesh's triangle turns about its own input normal.
            P n;
            if (mesh.has_surface_normals()) {
                const Vec3& s = mesh.surface_normals()[static_cast<std::size_t>(e)];
                n = {s[0], s[1], s[2]};
            } else {
                n = normal(x);
            }
            if (map == 0) {
                quality[e - first] = triangle(x, n);
                continue;
            }
            // A cell's corner: its own frame only (the cell's minimum is taken over its corners).
            const double raw = corner_jacobian(x, kTriCorners[0], n);
            quality[e - first] = raw / ideal[map];
        }
    }
    void accumulate_gradient(const Mesh&, std::span<const double>, ElementId, ElementId, const GradientTarget&) const override {
        throw OptionError("metric 'scaled_jacobian' is for assessment only and has no gradient");
    }

    // A report's blocks (evaluate_together), for a mesh of tetrahedra alone without targets: a
    // block carries each element mapped by its corner map or its target, and the scaled Jacobian
    // rates the corners as they are (evaluate()).
    bool rates_blocks(const Mesh& mesh) const override {
        return mesh.corners() == 4 && mesh.corner_maps().empty() && !mesh.has_targets();
    }
    void rate_block(const TetBlock& x, ElementId, int count, double* quality) const override {
        alignas(64) double q[kTetBlock];
        tet_values_block(best_block_path(), TetValueMetric::scaled_jacobian, x, nullptr, q);
        std::copy(q, q + count, quality);
    }

private:
    // A mesh of tetrahedra alone: kTetBlock at a time, bit for bit value()'s.
    static void evaluate_tet_blocks(const Mesh& mesh, std::span<const double> xyz, ElementId first, ElementId last,
                                    double* quality) {
        const BlockPath path = best_block_path();
        const VertexId* conn = mesh.connectivity().data();
        TetBlock x;
        double q[kTetBlock];
        for (ElementId b = first; b < last; b += kTetBlock) {
            const int count = static_cast<int>(std::min<ElementId>(kTetBlock, last - b));
            gather_tets(conn + 4 * static_cast<std::size_t>(b), xyz.data(), count, x);
            tet_values_block(path, TetValueMetric::scaled_jacobian, x, nullptr, q);
            std::copy(q, q + count, quality + (b - first));
        }
    }

    double triangle(const double* x, const P& n) const {
        double worst = INFINITY;
        for (const auto& c : kTriCorners) worst = std::min(worst, corner_jacobian(x, c, n));
        return 2.0 / std::numbers::sqrt3 * worst;
    }
    // The normal that orients a 2D element: the plane's for an oriented mesh, else its own.
    P normal(const double* x) const {
        if (scale_.oriented_triangles) return {scale_.plane_normal[0], scale_.plane_normal[1], scale_.plane_normal[2]};
        const P c = cross(load(x, 1) - load(x, 0), load(x, 2) - load(x, 0));
        const double length = norm(c);
        return length > 0.0 ? (1.0 / length) * c : P{0.0, 0.0, 1.0};
    }
};

}  // namespace

std::unique_ptr<QualityMetric> make_scaled_jacobian() { return std::make_unique<ScaledJacobian>(); }

}  // namespace paloverde::metrics
