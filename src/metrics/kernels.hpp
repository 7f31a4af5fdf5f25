#pragma once
// The metric formulas, one struct each. tet()/tri() return the value and, when `g` is not null,
// write the gradient with respect to the corners (3 doubles per corner). Inlined into the batch
// loops of KernelMetric, so a pass over the mesh makes no call per element. The metrics the
// solvers use most also have tet_block(), the same formula over a block of tetrahedra
// (tet_blocks.hpp), which the batch passes prefer; the quality report's other metrics have
// tet_values_block(), the same without gradients, which value-only passes prefer.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string_view>
#include <utility>

#include "geometry.hpp"
#include "tet_blocks.hpp"

namespace paloverde::metrics {

inline constexpr double kTetAspectScale = 72.0 * std::numbers::sqrt3;  // 1 for the regular tet
inline constexpr double kTriAspectScale = 4.0 * std::numbers::sqrt3;   // 1 for the equilateral triangle

inline double sign_of(double v) { return v > 0.0 ? 1.0 : (v < 0.0 ? -1.0 : 0.0); }

// A tet's signed volume alone, for passes that need no gradient (TetGeometry computes them all).
inline double tet_signed_volume(const double* x) {
    const P a = load(x, 0), e1 = load(x, 1) - a, e2 = load(x, 2) - a, e3 = load(x, 3) - a;
    return dot(e1, cross(e2, e3)) / 6.0;
}

// Triangles: the aspect ratio, mean ratio and inverse condition number all equal
// 4*sqrt(3)*area / (sum of squared edges).
inline double triangle_shape(const TriGeometry& t, double* g) {
    if (!(t.edge_sum > 0.0)) {
        if (g) std::fill(g, g + 9, 0.0);
        return 0.0;
    }
    const double q = kTriAspectScale * t.area / t.edge_sum;
    if (g)
        for (int i = 0; i < 3; ++i)
            store(g, i, (kTriAspectScale / t.edge_sum) * t.darea[i] - (q / t.edge_sum) * t.dedge_sum[i]);
    return q;
}

inline double tet_aspect(const TetGeometry& t, double* g) {
    if (!(t.edge_sum > 0.0)) {
        if (g) std::fill(g, g + 12, 0.0);
        return 0.0;
    }
    const double inv = 1.0 / (t.edge_sum * std::sqrt(t.edge_sum));
    const double q = kTetAspectScale * t.volume * inv;
    if (g)
        for (int i = 0; i < 4; ++i)
            store(g, i, (kTetAspectScale * inv) * t.dvolume[i] - (1.5 * q / t.edge_sum) * t.dedge_sum[i]);
    return q;
}

// The paper's aspect ratio: 72*sqrt(3)*V / (sum l^2)^(3/2), the mean ratio to the power 3/2.
struct AspectRatio {
    static constexpr std::string_view name = "aspect_ratio";
    double tet(const double* x, double* g, const MetricScale&) const { return tet_aspect(TetGeometry(x), g); }
    double tri(const double* x, double* g, const MetricScale& s) const { return triangle_shape(TriGeometry(x, s), g); }
    void tet_block(BlockPath path, const TetBlock& x, const double* /*reference_volume*/, double* q, TetBlock* g) const {
        tet_aspect_block(path, x, q, g);
    }
};

// Mean ratio: 12 * (3|V|)^(2/3) / (sum l^2), signed by V. Its gradient is unbounded as V -> 0;
// the cube root is floored at a tiny fraction of the element's size to stay finite there.
struct MeanRatio {
    static constexpr std::string_view name = "mean_ratio";
    // The formula in the three steps the block kernel takes apart (its square and cube roots go
    // through loops of their own): the floored 3|V| from the root of the edge sum, then the
    // quality from the cube root of that.
    static double floored_volume(double volume, double edge_sum, double edge_root) {
        return std::max(3.0 * std::abs(volume), 1e-30 * edge_sum * edge_root);
    }
    static double rated(double volume, double edge_sum, double root) {
        return sign_of(volume) * 12.0 * root * root / edge_sum;
    }
    // From a tet's geometry, for the metrics that rate its shape by the mean ratio (ShapeSize).
    static double of(const TetGeometry& t, double* g) {
        if (!(t.edge_sum > 0.0)) {
            if (g) std::fill(g, g + 12, 0.0);
            return 0.0;
        }
        const double root = std::cbrt(floored_volume(t.volume, t.edge_sum, std::sqrt(t.edge_sum)));
        const double q = rated(t.volume, t.edge_sum, root);
        if (g) {
            const double dq_dv = 12.0 * 2.0 / root / t.edge_sum;  // d/dV of 12 (3|V|)^(2/3) / L
            for (int i = 0; i < 4; ++i) store(g, i, dq_dv * t.dvolume[i] - (q / t.edge_sum) * t.dedge_sum[i]);
        }
        return q;
    }
    double tet(const double* x, double* g, const MetricScale&) const { return of(TetGeometry(x), g); }
    void tet_block(BlockPath path, const TetBlock& x, const double* /*reference_volume*/, double* q, TetBlock* g) const {
        tet_mean_ratio_block(path, x, q, g);
    }
    double tri(const double* x, double* g, const MetricScale& s) const { return triangle_shape(TriGeometry(x, s), g); }
};

// Inverse condition number of S = E W^-1 (E: edge vectors from corner 0, W: those of the unit
// regular tet): 3 det S / (|S|_F |adj S|_F), signed by det S.
struct InverseCondition {
    static constexpr std::string_view name = "inverse_condition";
    static constexpr double r3 = std::numbers::sqrt3, r6 = 2.449489742783178098;
    // S's columns and their pairwise cross products (adj S's rows), shared with the block kernel.
    struct Frame {
        P s1, s2, s3, c23, c31, c12;
        explicit Frame(const P* corner) {
            columns(corner, s1, s2, s3);
            c23 = cross(s2, s3), c31 = cross(s3, s1), c12 = cross(s1, s2);
        }
        // S's columns alone (ShapeSizeOrient needs no adjugate).
        static void columns(const P* corner, P& s1, P& s2, P& s3) {
            const P a = corner[0];
            const P e1 = corner[1] - a, e2 = corner[2] - a, e3 = corner[3] - a;
            s1 = e1, s2 = (1.0 / r3) * (2.0 * e2 - e1), s3 = (1.0 / r6) * (3.0 * e3 - e1 - e2);
        }
        double det() const { return dot(s1, c23); }
        double norm_squared() const { return dot(s1, s1) + dot(s2, s2) + dot(s3, s3); }
        double adjugate_norm_squared() const { return dot(c23, c23) + dot(c31, c31) + dot(c12, c12); }
    };
    double tet(const double* x, double* g, const MetricScale&) const {
        P corner[4];
        for (int i = 0; i < 4; ++i) corner[i] = load(x, i);
        const Frame f(corner);
        const P &s1 = f.s1, &s2 = f.s2, &s3 = f.s3, &c23 = f.c23, &c31 = f.c31, &c12 = f.c12;
        const double det = f.det();
        const double n = std::sqrt(f.norm_squared());
        const double c = std::sqrt(f.adjugate_norm_squared());
        if (!(n * c > 0.0)) {
            if (g) std::fill(g, g + 12, 0.0);
            return 0.0;
        }
        const double q = 3.0 * det / (n * c);
        if (g) {
            const double s11 = dot(s1, s1), s22 = dot(s2, s2), s33 = dot(s3, s3);
            const double s12 = dot(s1, s2), s13 = dot(s1, s3), s23 = dot(s2, s3);
            // d|adj S|^2 / d s_j, from |a x b|^2 = |a|^2 |b|^2 - (a.b)^2.
            const P dc1 = 2.0 * ((s22 + s33) * s1 - s12 * s2 - s13 * s3);
            const P dc2 = 2.0 * ((s11 + s33) * s2 - s12 * s1 - s23 * s3);
            const P dc3 = 2.0 * ((s11 + s22) * s3 - s13 * s1 - s23 * s2);
            const double k = 3.0 / (n * c), kn = q / (n * n), kc = q / (2.0 * c * c);
            const P g1 = k * c23 - kn * s1 - kc * dc1;
            const P g2 = k * c31 - kn * s2 - kc * dc2;
            const P g3 = k * c12 - kn * s3 - kc * dc3;
            store_corner_gradient(g1, g2, g3, g);
        }
        return q;
    }
    // The corner gradient from g_j = d/d s_j (S's columns): back from S to E (dS = dE W^-1, so
    // d/dE = d/dS W^-T), then from the edges to the corners.
    static void store_corner_gradient(const P& g1, const P& g2, const P& g3, double* g) {
        const P ge1 = g1 - (1.0 / r3) * g2 - (1.0 / r6) * g3;
        const P ge2 = (2.0 / r3) * g2 - (1.0 / r6) * g3;
        const P ge3 = (3.0 / r6) * g3;
        store(g, 1, ge1);
        store(g, 2, ge2);
        store(g, 3, ge3);
        store(g, 0, -(ge1 + ge2 + ge3));
    }
    void tet_values_block(BlockPath path, const TetBlock& x, const double* /*reference_volume*/, double* q) const {
        metrics::tet_values_block(path, TetValueMetric::inverse_condition, x, nullptr, q);
    }
    double tri(const double* x, double* g, const MetricScale& s) const { return triangle_shape(TriGeometry(x, s), g); }
};

// Shortest over longest edge, signed by the orientation. Not smooth where two edges tie.
struct EdgeRatio {
    static constexpr std::string_view name = "edge_ratio";
    template <int K, int E>
    static double ratio(const double* x, double* g, double orientation, const int (&edges)[E][2]) {
        double shortest = INFINITY, longest = 0.0;
        int imin = 0, imax = 0;
        for (int i = 0; i < E; ++i) {
            const P d = load(x, edges[i][1]) - load(x, edges[i][0]);
            const double l = norm(d);
            if (l < shortest) shortest = l, imin = i;
            if (l > longest) longest = l, imax = i;
        }
        if (g) std::fill(g, g + 3 * K, 0.0);
        if (!(longest > 0.0) || orientation == 0.0) return 0.0;
        const double r = shortest / longest;
        if (g) {
            auto add = [&](int edge, double scale) {
                const int p = edges[edge][0], q = edges[edge][1];
                const P d = load(x, q) - load(x, p);
                const P dl = (scale / norm(d)) * d;  // d length / d corner q
                store(g, q, load(g, q) + dl);
                store(g, p, load(g, p) - dl);
            };
            add(imin, orientation / longest);
            add(imax, -orientation * r / longest);
        }
        return orientation * r;
    }
    double tet(const double* x, double* g, const MetricScale&) const {
        return ratio<4>(x, g, sign_of(tet_signed_volume(x)), kTetEdges);  // the sign only: no gradients
    }
    void tet_values_block(BlockPath path, const TetBlock& x, const double* /*reference_volume*/, double* q) const {
        metrics::tet_values_block(path, TetValueMetric::edge_ratio, x, nullptr, q);
    }
    double tri(const double* x, double* g, const MetricScale& s) const {
        return ratio<3>(x, g, sign_of(TriGeometry(x, s).area), kTriEdges);
    }
};

// Signed volume (area) over the mesh's reference volume: scale-free, 1 for an average element.
struct ScaledVolume {
    static constexpr std::string_view name = "scaled_volume";
    double tet(const double* x, double* g, const MetricScale& s) const {
        if (!g) return tet_signed_volume(x) / s.reference_volume;
        const TetGeometry t(x);
        const double inv = 1.0 / s.reference_volume;
        if (g)
            for (int i = 0; i < 4; ++i) store(g, i, inv * t.dvolume[i]);
        return t.volume * inv;
    }
    void tet_values_block(BlockPath path, const TetBlock& x, const double* reference_volume, double* q) const {
        metrics::tet_values_block(path, TetValueMetric::scaled_volume, x, reference_volume, q);
    }
    double tri(const double* x, double* g, const MetricScale& s) const {
        const TriGeometry t(x, s);
        const double inv = 1.0 / s.reference_volume;
        if (g)
            for (int i = 0; i < 3; ++i) store(g, i, inv * t.darea[i]);
        return t.area * inv;
    }
};

// The untangling metric: a logistic blend of the scale-free volume v and the aspect ratio q,
//   Q = w v + (1 - w) q,   w = 1 / (1 + exp(alpha v)).
// Inverted elements are rated by their volume (Q ~ v < 0), valid ones by their shape (Q ~ q);
// Q > 0 exactly when the element is positively oriented.
struct UntangleHybrid {
    static constexpr std::string_view name = "untangle_hybrid";
    double alpha = 10.0;

    double blend(double volume, double q, const P* dvolume, const double* qgrad, int corners, double* g,
                 const MetricScale& s) const {
        const double v = volume / s.reference_volume;
        const double w = 1.0 / (1.0 + std::exp(alpha * v));
        if (g) {
            // dw/dv = -alpha w (1 - w)
            const double dq_dvolume = (w - alpha * w * (1.0 - w) * (v - q)) / s.reference_volume;
            for (int i = 0; i < corners; ++i) store(g, i, dq_dvolume * dvolume[i] + (1.0 - w) * load(qgrad, i));
        }
        return w * v + (1.0 - w) * q;
    }
    double tet(const double* x, double* g, const MetricScale& s) const {
        const TetGeometry t(x);
        double qgrad[12];
        const double q = tet_aspect(t, g ? qgrad : nullptr);
        return blend(t.volume, q, t.dvolume, qgrad, 4, g, s);
    }
    void tet_block(BlockPath path, const TetBlock& x, const double* reference_volume, double* q, TetBlock* g) const {
        tet_hybrid_block(path, x, reference_volume, alpha, q, g);
    }
    double tri(const double* x, double* g, const MetricScale& s) const {
        const TriGeometry t(x, s);
        double qgrad[9];
        const double q = triangle_shape(t, g ? qgrad : nullptr);
        return blend(t.area, q, t.darea, qgrad, 3, g, s);
    }
};

// The target-matrix metrics of Knupp (Mesquite's TShapeSize and TShapeSizeOrient) as qualities
// in [-1, 1] that a log-barrier can raise. A cell corner or an element with a target comes here
// mapped (cell_types.hpp), so "the regular simplex" is its target's shape, and the reference
// volume its target's volume: tau = V / V_ref is 1 at the target's size.
//
// The size term s(tau) = 2|tau| / (1 + tau^2): 1 at tau = 1 only, the same for tau and 1/tau (an
// element twice too large rates as one twice too small), 0 at tau = 0. Past |tau| = 1 it is
// written in r = 1/|tau|, so that neither it nor its derivative overflows for huge elements.
struct SizeTerm {
    double value, derivative;  // s and ds/dtau
    explicit SizeTerm(double tau) {
        const double t = std::abs(tau), r = t > 1.0 ? 1.0 / t : t, d = 1.0 + r * r;
        value = 2.0 * r / d;
        const double ds_dr = 2.0 * (1.0 - r * r) / (d * d);
        derivative = sign_of(tau) * (t > 1.0 ? -ds_dr * r * r : ds_dr);  // dr/dt = -r^2 past 1
    }
};

// q = m h s(tau) and its gradient g = h s dm + m s dh + m h s'(tau) dV / V_ref, from the shape m,
// the orientation factor h (1 and dh = null for ShapeSize) and the volume; K corners.
template <int K>
double shape_orientation_size(double m, const double* dm, double h, const double* dh, double volume,
                              const P* dvolume, double* g, double reference_volume) {
    const SizeTerm size(volume / reference_volume);
    const double q = m * h * size.value;
    if (g) {
        const double by_volume = m * h * size.derivative / reference_volume;
        for (int i = 0; i < K; ++i) {
            P gi = (h * size.value) * load(dm, i) + by_volume * dvolume[i];
            if (dh) gi = gi + (m * size.value) * load(dh, i);
            store(g, i, gi);
        }
    }
    return q;
}

// Shape and size: the mean ratio times s(tau). 1 exactly for the regular simplex of the
// reference volume; <= 0 exactly when inverted (the mean ratio carries the sign).
struct ShapeSize {
    static constexpr std::string_view name = "shape_size";
    static constexpr bool rates_size = true;
    double tet(const double* x, double* g, const MetricScale& s) const {
        const TetGeometry t(x);
        double dm[12] = {};
        const double m = MeanRatio::of(t, g ? dm : nullptr);
        return shape_orientation_size<4>(m, dm, 1.0, nullptr, t.volume, t.dvolume, g, s.reference_volume);
    }
    void tet_block(BlockPath path, const TetBlock& x, const double* reference_volume, double* q, TetBlock* g) const {
        tet_shape_size_block(path, x, reference_volume, q, g);
    }
    double tri(const double* x, double* g, const MetricScale& s) const {
        const TriGeometry t(x, s);
        double dm[9] = {};
        const double m = triangle_shape(t, g ? dm : nullptr);
        return shape_orientation_size<3>(m, dm, 1.0, nullptr, t.area, t.darea, g, s.reference_volume);
    }
};

// Shape, size and orientation: the mean ratio times h = (1 + o) / 2 times s(tau), where
// o = tr S / (sqrt(d) |S|_F) is the cosine between S = Y W^-1 (the map from the regular simplex
// to this one) and the identity: 1 exactly when S is a positive multiple of a rotation-free
// identity, i.e. the element has its target's orientation. In 3D o = -1 needs S = -c I, which is
// inverted, so a valid tet rates > 0. A triangle's S is the 2 x 2 map in the plane's basis
// (plane_basis): P^T Y W2^-1 with P = [a b]; there S = -c I is a valid triangle turned half a
// turn, which rates 0. Triangles of a surface (non-oriented) mesh use their own normal's basis,
// which follows no target: orientation there means little, and the basis jumps where the
// normal's two smallest coordinates tie.
struct ShapeSizeOrient {
    static constexpr std::string_view name = "shape_size_orient";
    static constexpr bool rates_size = true;
    static constexpr bool rotation_invariant = false;
    static constexpr double r2 = std::numbers::sqrt2, r3 = std::numbers::sqrt3;

    // h = (1 + o) / 2 and dh / d corner; false (h undefined) when S vanishes.
    static bool tet_orientation(const P* corner, double& h, double* dh) {
        P s1, s2, s3;
        InverseCondition::Frame::columns(corner, s1, s2, s3);
        const double n2 = dot(s1, s1) + dot(s2, s2) + dot(s3, s3), n = std::sqrt(n2);
        if (!(n > 0.0)) return false;
        const double o = (s1.x + s2.y + s3.z) / (r3 * n);
        h = 0.5 * (1.0 + o);
        if (dh) {
            // do/ds_j = e_j / (sqrt3 |S|) - o s_j / |S|^2: d tr S / d s_j is the j-th axis.
            const double k = 0.5 / (r3 * n), ko = 0.5 * o / n2;
            InverseCondition::store_corner_gradient(P{k, 0.0, 0.0} - ko * s1, P{0.0, k, 0.0} - ko * s2,
                                                    P{0.0, 0.0, k} - ko * s3, dh);
        }
        return true;
    }

    // The same for a triangle, S = P^T Y W2^-1 with the columns s1 = e1, s2 = (2 e2 - e1) / sqrt3
    // of Y W2^-1 seen in the plane's basis: u_j = (a.s_j, b.s_j), o = (u1_a + u2_b) / (sqrt2 |u|).
    static bool tri_orientation(const TriGeometry& t, const MetricScale& s, double& h, double* dh) {
        const P e1 = t.corner[1] - t.corner[0], e2 = t.corner[2] - t.corner[0];
        const P c = cross(e1, e2);
        const double c_length = norm(c);
        P n{s.plane_normal[0], s.plane_normal[1], s.plane_normal[2]};
        if (!s.oriented_triangles) {
            if (!(c_length > 0.0)) return false;
            n = (1.0 / c_length) * c;
        }
        P a, b;
        plane_basis(n, a, b);
        const P s1 = e1, s2 = (1.0 / r3) * (2.0 * e2 - e1);
        const double u1a = dot(a, s1), u1b = dot(b, s1), u2a = dot(a, s2), u2b = dot(b, s2);
        const double n2 = u1a * u1a + u1b * u1b + u2a * u2a + u2b * u2b, un = std::sqrt(n2);
        if (!(un > 0.0)) return false;
        const double o = (u1a + u2b) / (r2 * un);
        h = 0.5 * (1.0 + o);
        if (dh) {
            // With the basis held: do/ds_j = (a or b) / (sqrt2 |u|) - o P u_j / |u|^2.
            const double k = 0.5 / (r2 * un), ko = 0.5 * o / n2;
            const P g1 = k * a - ko * (u1a * a + u1b * b), g2 = k * b - ko * (u2a * a + u2b * b);
            P ge1 = g1 - (1.0 / r3) * g2, ge2 = (2.0 / r3) * g2;
            if (!s.oriented_triangles) {
                // The basis turns with the triangle's normal. Only its twist about n (the rate
                // w = da.b) moves o: a tilt moves the in-plane s_j out of the plane only to second
                // order, and |u| is the same in any basis of the plane. d(tr) = w (b.s1 - a.s2), and
                // with a = (e_k - n_k n) / |e_k - n_k n|: w = -n_k b.dn / |e_k - n_k n|, where
                // b.dn = b.dc / |c| = de1.(e2 x b) + de2.(b x e1), over |c|.
                const int axis = plane_basis_axis(n);
                const double nk = axis == 0 ? n.x : (axis == 1 ? n.y : n.z);
                const double kappa = -k * nk * (u1b - u2a) / (std::sqrt(1.0 - nk * nk) * c_length);
                ge1 = ge1 + kappa * cross(e2, b);
                ge2 = ge2 + kappa * cross(b, e1);
            }
            store(dh, 1, ge1);
            store(dh, 2, ge2);
            store(dh, 0, -(ge1 + ge2));
        }
        return true;
    }

    double tet(const double* x, double* g, const MetricScale& s) const {
        const TetGeometry t(x);
        double dm[12], dh[12], h = 0.0;
        if (!tet_orientation(t.corner, h, g ? dh : nullptr)) {
            if (g) std::fill(g, g + 12, 0.0);
            return 0.0;
        }
        const double m = MeanRatio::of(t, g ? dm : nullptr);
        return shape_orientation_size<4>(m, dm, h, dh, t.volume, t.dvolume, g, s.reference_volume);
    }
    double tri(const double* x, double* g, const MetricScale& s) const {
        const TriGeometry t(x, s);
        double dm[9], dh[9], h = 0.0;
        if (!tri_orientation(t, s, h, g ? dh : nullptr)) {
            if (g) std::fill(g, g + 9, 0.0);
            return 0.0;
        }
        const double m = triangle_shape(t, g ? dm : nullptr);
        return shape_orientation_size<3>(m, dm, h, dh, t.area, t.darea, g, s.reference_volume);
    }
};

// The regularized untangling energy of Garanzha, Kaporin, Kudryavtseva, Protais, Ray & Sokolov
// (foldover-free maps, 2021), negated so that larger is better. With J the Jacobian of the map
// from the regular element of the element's reference volume to the element, d its dimension,
// v = det J (the scale-free signed volume) and chi(v, eps) = (v + sqrt(eps^2 + v^2)) / 2 > 0,
//   f = (1 - theta) (|J|^2 / d) / chi^(2/d) + theta (v^2 + 1) / (2 chi),
// which is 1 for the reference element as eps -> 0. chi is positive for every v, so the energy is
// finite on tangled meshes too; as eps shrinks it becomes a barrier against inversion. |J|^2
// comes from the squared edge lengths L: L / (4 (3 V0)^(2/3)) for a tet, L / (2 sqrt(3) A0) for
// a triangle.
struct RegularizedEnergy {
    static constexpr std::string_view name = "untangle_energy";
    static constexpr double ideal = -1.0;
    double epsilon = 1.0;
    double theta = 1.0 / 128.0;

    // -f and its gradient from the volume and the squared edge sum (and their corner gradients).
    template <int D>
    double energy(double volume, double edge_sum, const P* dvolume, const P* dedge_sum, double* g,
                  const MetricScale& s) const {
        constexpr int corners = D + 1;
        const double v0 = s.reference_volume;
        const double v = volume / v0;
        const double r = std::sqrt(epsilon * epsilon + v * v);
        // (v + r)(r - v) = eps^2: the second form keeps its digits where v is very negative.
        const double chi = v >= 0.0 ? 0.5 * (v + r) : 0.5 * epsilon * epsilon / (r - v);
        // f1 = (|J|^2 / d) / chi^(2/d) = edge_sum * per_edge_sum, with one cube root for tets.
        const double per_edge_sum = D == 3 ? 1.0 / (12.0 * std::cbrt(9.0 * (v0 * chi) * (v0 * chi)))
                                           : 1.0 / (4.0 * std::numbers::sqrt3 * v0 * chi);
        const double f1 = edge_sum * per_edge_sum;
        const double f2 = 0.5 * (v * v + 1.0) / chi;
        if (g) {
            // d chi / dv = chi / r.
            const double df_dv = -(1.0 - theta) * (2.0 / D) * f1 / r + theta * (v / chi - f2 / r);
            for (int i = 0; i < corners; ++i)
                store(g, i, (-df_dv / v0) * dvolume[i] - ((1.0 - theta) * per_edge_sum) * dedge_sum[i]);
        }
        return -((1.0 - theta) * f1 + theta * f2);
    }
    double tet(const double* x, double* g, const MetricScale& s) const {
        if (!g) {  // the line search's passes need no corner gradients
            P corner[4];
            for (int i = 0; i < 4; ++i) corner[i] = load(x, i);
            return energy<3>(tet_signed_volume(x), TetGeometry::tet_edge_sum(corner), nullptr, nullptr, nullptr, s);
        }
        const TetGeometry t(x);
        return energy<3>(t.volume, t.edge_sum, t.dvolume, t.dedge_sum, g, s);
    }
    void tet_block(BlockPath path, const TetBlock& x, const double* reference_volume, double* q, TetBlock* g) const {
        tet_energy_block(path, x, reference_volume, epsilon, theta, q, g);
    }
    double tri(const double* x, double* g, const MetricScale& s) const {
        const TriGeometry t(x, s);
        return energy<2>(t.area, t.edge_sum, t.darea, t.dedge_sum, g, s);
    }
};

// The smallest sine of an element's angles over the regular element's: the six dihedral angles
// of a tetrahedron (sin at edge ij = 3 V l_ij / (2 A_k A_l), A_k and A_l the areas of the two
// faces that meet there, those opposite the other corners k and l; regular: 2 sqrt(2) / 3), the
// three corner angles of a triangle (sin at corner i = 2 A / (l l'), the two edges at i;
// regular: sqrt(3) / 2). Signed by the volume (area), so inverted elements rate below 0 (the
// most negative term: minus the largest sine, -1 for a mirrored regular element). A sine
// is small for angles near 0 and near 180 degrees alike: the slivers and caps that stall a
// simulation. The element's value is its smallest term; the gradient is that term's (where two
// tie, one of them: a subgradient of the minimum).
struct DihedralSine {
    static constexpr std::string_view name = "dihedral_sine";
    // 1 / (2 sqrt(2) / 3) times the 3/2 of the formula; 1 / (sqrt(3) / 2) times its 2.
    static constexpr double kTet = 9.0 / (4.0 * std::numbers::sqrt2), kTri = 4.0 / std::numbers::sqrt3;

    double tet(const double* x, double* g, const MetricScale&) const {
        static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};  // opposite corner k
        P c[4];
        for (int i = 0; i < 4; ++i) c[i] = load(x, i);
        double area[4];
        P normal[4];  // unit normals of the faces (any orientation: only |n| and its gradient are used)
        for (int k = 0; k < 4; ++k) {
            const P a = c[kFace[k][0]], n = cross(c[kFace[k][1]] - a, c[kFace[k][2]] - a);
            const double length = norm(n);
            area[k] = 0.5 * length;
            normal[k] = length > 0.0 ? (1.0 / length) * n : P{0.0, 0.0, 0.0};
        }
        const P e1 = c[1] - c[0], e2 = c[2] - c[0], e3 = c[3] - c[0];
        const double volume = dot(e1, cross(e2, e3)) / 6.0;
        double smallest = INFINITY;
        int at = 0;
        for (int m = 0; m < 6; ++m) {
            const auto [i, j] = kTetEdges[m];
            const auto [k, l] = other_two(i, j);
            const double faces = area[k] * area[l];
            const double term = faces > 0.0 ? kTet * volume * norm(c[i] - c[j]) / faces : 0.0;
            if (term < smallest) smallest = term, at = m;
        }
        if (!g) return smallest;
        std::fill(g, g + 12, 0.0);
        const auto [i, j] = kTetEdges[at];
        const auto [k, l] = other_two(i, j);
        const double faces = area[k] * area[l], length = norm(c[i] - c[j]);
        if (!(faces > 0.0) || !(length > 0.0)) return smallest;
        // d term = kTet (L dV + V dL) / (A_k A_l) - term (dA_k / A_k + dA_l / A_l)
        P grad[4] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
        const P dvolume[4] = {-(1.0 / 6.0) * (cross(e2, e3) + cross(e3, e1) + cross(e1, e2)), (1.0 / 6.0) * cross(e2, e3),
                              (1.0 / 6.0) * cross(e3, e1), (1.0 / 6.0) * cross(e1, e2)};
        for (int v = 0; v < 4; ++v) grad[v] = (kTet * length / faces) * dvolume[v];
        const P dl = (kTet * volume / faces / length) * (c[i] - c[j]);
        grad[i] = grad[i] + dl;
        grad[j] = grad[j] - dl;
        for (int face : {k, l}) {
            // dA = (1/2) d|n|, n = (q - p) x (r - p): d|n|/dq = (r - p) x n^, d|n|/dr = n^ x (q - p).
            const int p0 = kFace[face][0], q0 = kFace[face][1], r0 = kFace[face][2];
            const P u = normal[face];
            const double w = -smallest / area[face] * 0.5;
            const P dq = cross(c[r0] - c[p0], u), dr = cross(u, c[q0] - c[p0]);
            grad[q0] = grad[q0] + w * dq;
            grad[r0] = grad[r0] + w * dr;
            grad[p0] = grad[p0] - w * (dq + dr);
        }
        for (int v = 0; v < 4; ++v) store(g, v, grad[v]);
        return smallest;
    }

    double tri(const double* x, double* g, const MetricScale& s) const {
        const TriGeometry t(x, s);
        double smallest = INFINITY;
        int at = 0;
        for (int i = 0; i < 3; ++i) {
            const double lengths = norm(t.corner[(i + 1) % 3] - t.corner[i]) * norm(t.corner[(i + 2) % 3] - t.corner[i]);
            const double term = lengths > 0.0 ? kTri * t.area / lengths : 0.0;
            if (term < smallest) smallest = term, at = i;
        }
        if (!g) return smallest;
        std::fill(g, g + 9, 0.0);
        const int a = at, b = (at + 1) % 3, c = (at + 2) % 3;
        const P u = t.corner[b] - t.corner[a], v = t.corner[c] - t.corner[a];
        const double lu = norm(u), lv = norm(v);
        if (!(lu > 0.0) || !(lv > 0.0)) return smallest;
        // d term = kTri dA / (lu lv) - term (dlu / lu + dlv / lv)
        P grad[3];
        for (int i = 0; i < 3; ++i) grad[i] = (kTri / (lu * lv)) * t.darea[i];
        const P du = (smallest / (lu * lu)) * u, dv = (smallest / (lv * lv)) * v;
        grad[b] = grad[b] - du;
        grad[c] = grad[c] - dv;
        grad[a] = grad[a] + du + dv;
        for (int i = 0; i < 3; ++i) store(g, i, grad[i]);
        return smallest;
    }

private:
    // The two corners of a tetrahedron other than i and j.
    static std::pair<int, int> other_two(int i, int j) {
        int out[2], n = 0;
        for (int k = 0; k < 4; ++k)
            if (k != i && k != j) out[n++] = k;
        return {out[0], out[1]};
    }
};

// One term of dihedral_sine: the sine of the dihedral angle at the edge of corners 0 and 1 alone,
// over the regular tetrahedron's, signed by the volume. The global solver rates each angle of a
// tetrahedron as a term of its own by rating six copies of it, corners permuted so that each edge
// comes first once (docs/metrics.md, "Six terms per tetrahedron"): the barrier then weighs every
// small angle, not only the smallest, and ties between two angles are no kinks.
struct DihedralSineTerm {
    static constexpr std::string_view name = "dihedral_sine_term";
    static constexpr ElementKind only_kind = ElementKind::Tetrahedron;

    double tet(const double* x, double* g, const MetricScale&) const {
        P c[4];
        for (int i = 0; i < 4; ++i) c[i] = load(x, i);
        // The faces at the edge: opposite corner 2 (corners 0, 1, 3) and opposite corner 3 (0, 1, 2).
        const P edge = c[1] - c[0], n2 = cross(edge, c[3] - c[0]), n3 = cross(edge, c[2] - c[0]);
        const double a2 = 0.5 * norm(n2), a3 = 0.5 * norm(n3), length = norm(edge);
        const P e1 = c[1] - c[0], e2 = c[2] - c[0], e3 = c[3] - c[0];
        const double volume = dot(e1, cross(e2, e3)) / 6.0;
        const double faces = a2 * a3;
        const double term = faces > 0.0 ? DihedralSine::kTet * volume * length / faces : 0.0;
        if (!g) return term;
        std::fill(g, g + 12, 0.0);
        if (!(faces > 0.0) || !(length > 0.0)) return term;
        // d term = kTet (L dV + V dL) / (A_2 A_3) - term (dA_2 / A_2 + dA_3 / A_3)
        const P dvolume[4] = {-(1.0 / 6.0) * (cross(e2, e3) + cross(e3, e1) + cross(e1, e2)), (1.0 / 6.0) * cross(e2, e3),
                              (1.0 / 6.0) * cross(e3, e1), (1.0 / 6.0) * cross(e1, e2)};
        P grad[4];
        for (int v = 0; v < 4; ++v) grad[v] = (DihedralSine::kTet * length / faces) * dvolume[v];
        const P dl = (DihedralSine::kTet * volume / faces / length) * edge;
        grad[1] = grad[1] + dl;
        grad[0] = grad[0] - dl;
        // A face (0, 1, r) of normal n = (c1 - c0) x (cr - c0): d|n|/dc1 = (cr - c0) x n^,
        // d|n|/dcr = n^ x (c1 - c0), d|n|/dc0 = -(both).
        auto add_face = [&](int r, const P& n, double area) {
            const P u = (1.0 / (2.0 * area)) * n;
            const double w = -term / area * 0.5;
            const P d1 = cross(c[r] - c[0], u), dr = cross(u, edge);
            grad[1] = grad[1] + w * d1;
            grad[r] = grad[r] + w * dr;
            grad[0] = grad[0] - w * (d1 + dr);
        };
        add_face(3, n2, a2);
        add_face(2, n3, a3);
        for (int v = 0; v < 4; ++v) store(g, v, grad[v]);
        return term;
    }
    double tri(const double*, double*, const MetricScale&) const { return 0.0; }
};

// Smallest dihedral angle of a tetrahedron in degrees (70.53 for the regular tet), negative for
// an inverted one. Assessment only.
struct MinDihedralAngle {
    static constexpr std::string_view name = "min_dihedral_deg";
    static constexpr bool assessment_only = true;
    static constexpr ElementKind only_kind = ElementKind::Tetrahedron;
    static constexpr double ideal = 70.528779365509308631;  // acos(1/3) in degrees
    // dvolume[k] is the inward normal of the face opposite corner k; the dihedral angle at the
    // edge those faces share has cosine -n_k . n_l / (|n_k| |n_l|). The smallest angle has the
    // largest cosine: one atan2 for it rather than one per edge. (A face of no area makes the
    // volume 0, and with it the result.) The pair's normals go to u and w, chosen by selects
    // rather than by index so that the block kernel's loop, which shares this, vectorizes.
    static void widest_pair(const P* dvolume, const double* length, P& u, P& w) {
        u = dvolume[0], w = dvolume[1];
        double largest = -INFINITY;
        // The pairs k < l of faces in the order of kTetEdges' pairs of corners; one flat loop,
        // which the compiler unrolls before it vectorizes the block's loop around it.
#pragma GCC unroll 6
        for (const auto& [k, l] : kTetEdges) {
            const double cosine = -dot(dvolume[k], dvolume[l]) / (length[k] * length[l]);
            const bool wider = cosine > largest;
            largest = wider ? cosine : largest;
            u = select(wider, dvolume[k], u);
            w = select(wider, dvolume[l], w);
        }
    }
    static double degrees(double volume, double angle) { return sign_of(volume) * angle * (180.0 / std::numbers::pi); }
    double tet(const double* x, double* g, const MetricScale&) const {
        // The volume and its gradient only (not the edge sums a full TetGeometry adds).
        P corner[4], dvolume[4];
        for (int i = 0; i < 4; ++i) corner[i] = load(x, i);
        const double volume = TetGeometry::tet_volume(corner, dvolume);
        double length[4];
        for (int k = 0; k < 4; ++k) length[k] = norm(dvolume[k]);
        P u, w;
        widest_pair(dvolume, length, u, w);
        const double smallest = std::atan2(norm(cross(u, w)), -dot(u, w));
        if (g) std::fill(g, g + 12, 0.0);
        return degrees(volume, smallest);
    }
    void tet_values_block(BlockPath path, const TetBlock& x, const double* /*reference_volume*/, double* q) const {
        metrics::tet_values_block(path, TetValueMetric::min_dihedral, x, nullptr, q);
    }
    double tri(const double*, double*, const MetricScale&) const { return 0.0; }
};

// Smallest corner angle of a triangle in degrees (60 for the equilateral one), negative for an
// inverted one. Assessment only.
struct MinCornerAngle {
    static constexpr std::string_view name = "min_angle_deg";
    static constexpr bool assessment_only = true;
    static constexpr ElementKind only_kind = ElementKind::Triangle;
    static constexpr double ideal = 60.0;
    double tet(const double*, double*, const MetricScale&) const { return 0.0; }
    double tri(const double* x, double* g, const MetricScale& s) const {
        const TriGeometry t(x, s);
        double smallest = INFINITY;
        for (int i = 0; i < 3; ++i) {
            const P u = t.corner[(i + 1) % 3] - t.corner[i], v = t.corner[(i + 2) % 3] - t.corner[i];
            smallest = std::min(smallest, std::atan2(norm(cross(u, v)), dot(u, v)));
        }
        if (g) std::fill(g, g + 9, 0.0);
        return sign_of(t.area) * smallest * (180.0 / std::numbers::pi);
    }
};

}  // namespace paloverde::metrics
