#pragma once
// Small fixed-size vector algebra and the per-element quantities every metric is built from:
// signed volume (area) and the sum of squared edge lengths, each with its corner gradients.
#include <cmath>

#include "paloverde/metrics/quality_metric.hpp"

namespace paloverde::metrics {

struct P {
    double x, y, z;
};
inline P operator+(P a, P b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline P operator-(P a, P b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline P operator-(P a) { return {-a.x, -a.y, -a.z}; }
inline P operator*(double s, P a) { return {s * a.x, s * a.y, s * a.z}; }
inline double dot(P a, P b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline P cross(P a, P b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline double norm(P a) { return std::sqrt(dot(a, a)); }
// c ? a : b, coordinate by coordinate: a select the vectorizer takes, where a whole struct's is a branch.
inline P select(bool c, P a, P b) { return {c ? a.x : b.x, c ? a.y : b.y, c ? a.z : b.z}; }
inline P load(const double* x, int corner) { return {x[3 * corner], x[3 * corner + 1], x[3 * corner + 2]}; }
inline void store(double* g, int corner, P v) {
    g[3 * corner] = v.x;
    g[3 * corner + 1] = v.y;
    g[3 * corner + 2] = v.z;
}

// An orthonormal basis (a, b) of the plane of unit normal n, with a x b = n: a is the coordinate
// axis e_k least aligned with n (the smallest |n_k|, the first on ties) projected into the plane,
// so that it is never short (|e_k - n_k n|^2 = 1 - n_k^2 >= 2/3). For n = (0, 0, 1) it is the
// x and y axes, so a planar mesh in the xy plane keeps its own coordinates.
inline int plane_basis_axis(const P& n) {
    const double ax = std::abs(n.x), ay = std::abs(n.y), az = std::abs(n.z);
    return ax <= ay && ax <= az ? 0 : (ay <= az ? 1 : 2);
}
inline void plane_basis(const P& n, P& a, P& b) {
    const int k = plane_basis_axis(n);
    const double nk = k == 0 ? n.x : (k == 1 ? n.y : n.z);
    const P axis{k == 0 ? 1.0 : 0.0, k == 1 ? 1.0 : 0.0, k == 2 ? 1.0 : 0.0};
    const P w = axis - nk * n;
    a = (1.0 / norm(w)) * w;
    b = cross(n, a);
}

// Corner pairs of the edges.
inline constexpr int kTetEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
inline constexpr int kTriEdges[3][2] = {{0, 1}, {0, 2}, {1, 2}};
// The corners of a tetrahedron, each with its three neighbours in an order that keeps the
// orientation (even permutations): where the scaled Jacobian is taken.
inline constexpr int kTetJacobianCorners[4][4] = {{0, 1, 2, 3}, {1, 2, 0, 3}, {2, 0, 1, 3}, {3, 0, 2, 1}};

// Tetrahedron (a, b, c, d), positive when d lies on the side of abc that (b-a)x(c-a) points to
// (the VTK, Gmsh and CGAL convention).
struct TetGeometry {
    P corner[4];
    double volume;      // signed
    double edge_sum;    // sum of the six squared edge lengths
    P dvolume[4];       // d volume / d corner
    P dedge_sum[4];     // d edge_sum / d corner

    explicit TetGeometry(const double* x) {
        for (int i = 0; i < 4; ++i) corner[i] = load(x, i);
        volume = tet_volume(corner, dvolume);
        edge_sum = tet_edge_sum(corner);
        tet_dedge_sum(corner, dedge_sum);
    }

    // The pieces, also used one by one by the block kernels (tet_blocks.cpp), inlined there: as
    // calls they cost a tenth of a shape_size pass.
    [[gnu::always_inline]] static double tet_volume(const P* corner, P* dvolume) {
        const P e1 = corner[1] - corner[0], e2 = corner[2] - corner[0], e3 = corner[3] - corner[0];
        const P c23 = cross(e2, e3), c31 = cross(e3, e1), c12 = cross(e1, e2);
        dvolume[1] = (1.0 / 6.0) * c23;
        dvolume[2] = (1.0 / 6.0) * c31;
        dvolume[3] = (1.0 / 6.0) * c12;
        dvolume[0] = -(dvolume[1] + dvolume[2] + dvolume[3]);
        return dot(e1, c23) / 6.0;
    }
    [[gnu::always_inline]] static double tet_edge_sum(const P* corner) {
        const P e1 = corner[1] - corner[0], e2 = corner[2] - corner[0], e3 = corner[3] - corner[0];
        const P e4 = corner[2] - corner[1], e5 = corner[3] - corner[1], e6 = corner[3] - corner[2];
        return dot(e1, e1) + dot(e2, e2) + dot(e3, e3) + dot(e4, e4) + dot(e5, e5) + dot(e6, e6);
    }
    [[gnu::always_inline]] static void tet_dedge_sum(const P* corner, P* dedge_sum) {
        // d/dp of sum over the edges at p of |p - q|^2 is 2 * (4p - (a + b + c + d)).
        const P sum = corner[0] + corner[1] + corner[2] + corner[3];
        for (int i = 0; i < 4; ++i) dedge_sum[i] = 2.0 * (4.0 * corner[i] - sum);
    }
};

// Triangle (a, b, c) with its area signed by the plane normal of an oriented (planar) mesh, or
// unsigned in a surface mesh.
struct TriGeometry {
    P corner[3];
    double area;
    double edge_sum;
    P darea[3];
    P dedge_sum[3];

    TriGeometry(const double* x, const MetricScale& scale) {
        for (int i = 0; i < 3; ++i) corner[i] = load(x, i);
        const P e1 = corner[1] - corner[0], e2 = corner[2] - corner[0];
        const P c = cross(e1, e2);
        P n{scale.plane_normal[0], scale.plane_normal[1], scale.plane_normal[2]};
        if (!scale.oriented_triangles) {
            const double length = norm(c);
            n = length > 0.0 ? (1.0 / length) * c : P{0.0, 0.0, 0.0};
        }
        area = 0.5 * dot(n, c);
        darea[1] = 0.5 * cross(e2, n);
        darea[2] = 0.5 * cross(n, e1);
        darea[0] = -(darea[1] + darea[2]);
        const P e3 = corner[2] - corner[1];
        edge_sum = dot(e1, e1) + dot(e2, e2) + dot(e3, e3);
        const P sum = corner[0] + corner[1] + corner[2];
        for (int i = 0; i < 3; ++i) dedge_sum[i] = 2.0 * (3.0 * corner[i] - sum);
    }
};

}  // namespace paloverde::metrics
