#pragma once
// Example 3's metric (ex3.cpp), in a header of its own so that the tests can check its gradient
// against finite differences as they check every built-in metric's (tests/metrics).
#include <algorithm>
#include <array>
#include <cmath>
#include <string_view>

#include <paloverde/metrics/quality_metric.hpp>

namespace example {

// [ex3-metric]
// An ElementMetric rates one element at a time; the solvers call it from several threads at once,
// so it keeps no state but its scale (the mesh's reference volume, set by the solvers).
class SizedAspect final : public paloverde::ElementMetric {
public:
    std::string_view name() const override { return "sized_aspect"; }
    bool supports(paloverde::ElementKind kind) const override { return kind == paloverde::ElementKind::Tetrahedron; }
    double value(paloverde::ElementKind, const double* corners) const override { return rate(corners, nullptr); }
    double value_and_gradient(paloverde::ElementKind, const double* corners, double* gradient) const override {
        return rate(corners, gradient);
    }

private:
    // q = r s with r = 72 sqrt(3) V / L^(3/2) (L: the sum of squared edge lengths) and
    // s = 2 / (v + 1/v), v = |V| / V_ref. Gradient: dq = s dr + r ds.
    double rate(const double* x, double* g) const {
        using V3 = std::array<double, 3>;
        const auto corner = [&](int i) { return V3{x[3 * i], x[3 * i + 1], x[3 * i + 2]}; };
        const auto minus = [](V3 a, V3 b) { return V3{a[0] - b[0], a[1] - b[1], a[2] - b[2]}; };
        const auto cross = [](V3 a, V3 b) {
            return V3{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
        };
        const auto dot = [](V3 a, V3 b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
        const V3 e1 = minus(corner(1), corner(0)), e2 = minus(corner(2), corner(0)), e3 = minus(corner(3), corner(0));
        const double volume = dot(e1, cross(e2, e3)) / 6.0;
        double edges = 0.0;  // L
        for (int i = 0; i < 4; ++i)
            for (int j = i + 1; j < 4; ++j) {
                const V3 d = minus(corner(i), corner(j));
                edges += dot(d, d);
            }
        const double c = 72.0 * std::sqrt(3.0);
        if (!(edges > 0.0)) {  // all four corners in one point
            if (g) std::fill(g, g + 12, 0.0);
            return 0.0;
        }
        const double r = c * volume / std::pow(edges, 1.5);
        const double v = std::abs(volume) / scale().reference_volume;
        const double s = v > 0.0 ? 2.0 / (v + 1.0 / v) : 0.0;
        if (g) {
            // dV/dx and dL/dx per corner.
            V3 dv[4];
            dv[1] = cross(e2, e3), dv[2] = cross(e3, e1), dv[3] = cross(e1, e2);
            for (int k = 1; k < 4; ++k)
                for (int d = 0; d < 3; ++d) dv[k][d] /= 6.0;
            for (int d = 0; d < 3; ++d) dv[0][d] = -(dv[1][d] + dv[2][d] + dv[3][d]);
            const double dr_dv = c / std::pow(edges, 1.5), dr_dl = -1.5 * r / edges;
            // ds/dV = ds/dv * sign(V) / V_ref
            const double ds_dvolume = v > 0.0 ? -2.0 * (1.0 - 1.0 / (v * v)) / ((v + 1.0 / v) * (v + 1.0 / v)) *
                                                    (volume < 0.0 ? -1.0 : 1.0) / scale().reference_volume
                                              : 0.0;
            for (int i = 0; i < 4; ++i) {
                V3 dl{0.0, 0.0, 0.0};
                for (int j = 0; j < 4; ++j)
                    if (j != i) {
                        const V3 d = minus(corner(i), corner(j));
                        for (int k = 0; k < 3; ++k) dl[k] += 2.0 * d[k];
                    }
                for (int k = 0; k < 3; ++k)
                    g[3 * i + k] = s * (dr_dv * dv[i][k] + dr_dl * dl[k]) + r * ds_dvolume * dv[i][k];
            }
        }
        return r * s;
    }
};
// [ex3-metric]

}  // namespace example
