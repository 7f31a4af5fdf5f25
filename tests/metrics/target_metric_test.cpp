// The target-matrix metrics, shape_size and shape_size_orient (docs/metrics.md), against their
// formulas computed here the long way (a general 3x3 inverse for S), on the triangles the
// generic tester does not meet: a plane that is not the xy plane, and surface triangles whose
// basis turns with their own normal (a gradient term of its own).
#include <boost/test/unit_test.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "metrics/geometry.hpp"
#include "paloverde/metrics/quality_metric.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;
namespace pm = paloverde::metrics;

namespace {

using Corners = std::vector<double>;
using Matrix = std::array<std::array<double, 3>, 3>;  // m[row][column]

double size_term(double tau) { return 2.0 * std::abs(tau) / (1.0 + tau * tau); }

Matrix inverse(const Matrix& m) {
    const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                       m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                       m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    Matrix out{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            const int r0 = (j + 1) % 3, r1 = (j + 2) % 3, c0 = (i + 1) % 3, c1 = (i + 2) % 3;
            out[i][j] = (m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0]) / det;
        }
    return out;
}

// o = tr S / (sqrt(3) |S|_F), S = E W^-1 with W the regular tet's edge matrix.
double tet_orientation(const Corners& x) {
    const Corners w = pv::test::regular_simplex(pv::ElementKind::Tetrahedron);
    Matrix e{}, wm{};
    for (int r = 0; r < 3; ++r)
        for (int j = 0; j < 3; ++j) {
            e[r][j] = x[3 * (j + 1) + r] - x[r];
            wm[r][j] = w[3 * (j + 1) + r];
        }
    const Matrix wi = inverse(wm);
    double trace = 0.0, frobenius = 0.0;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
            double s = 0.0;
            for (int k = 0; k < 3; ++k) s += e[r][k] * wi[k][c];
            frobenius += s * s;
            if (r == c) trace += s;
        }
    return trace / (std::sqrt(3.0) * std::sqrt(frobenius));
}

// The 2D version in the xy plane: W2 = [(1, 0), (1/2, sqrt3/2)], W2^-1 = [[1, -1/sqrt3], [0, 2/sqrt3]].
double xy_triangle_orientation(const Corners& x) {
    const double e[2][2] = {{x[3] - x[0], x[6] - x[0]}, {x[4] - x[1], x[7] - x[1]}};
    const double wi[2][2] = {{1.0, -1.0 / std::sqrt(3.0)}, {0.0, 2.0 / std::sqrt(3.0)}};
    double trace = 0.0, frobenius = 0.0;
    for (int r = 0; r < 2; ++r)
        for (int c = 0; c < 2; ++c) {
            const double s = e[r][0] * wi[0][c] + e[r][1] * wi[1][c];
            frobenius += s * s;
            if (r == c) trace += s;
        }
    return trace / (std::sqrt(2.0) * std::sqrt(frobenius));
}

std::unique_ptr<pv::QualityMetric> metric(const char* name, const pv::MetricScale& scale) {
    auto m = pv::make_metric(name);
    m->set_scale(scale);
    return m;
}

pv::MetricScale reference(double volume) {
    pv::MetricScale s;
    s.reference_volume = volume;
    return s;
}

// Central differences against the analytic gradient, relative to the gradient's largest entry.
void check_gradient(const pv::QualityMetric& m, pv::ElementKind kind, const Corners& x, const std::string& what) {
    std::vector<double> g(x.size());
    const double v = m.value_and_gradient(kind, x.data(), g.data());
    BOOST_TEST(v == m.value(kind, x.data()), boost::test_tools::tolerance(1e-14));
    double largest = 0.0;
    for (double gi : g) largest = std::max(largest, std::abs(gi));
    const double h = 1e-6;
    for (std::size_t i = 0; i < x.size(); ++i) {
        Corners plus = x, minus = x;
        plus[i] += h, minus[i] -= h;
        const double fd = (m.value(kind, plus.data()) - m.value(kind, minus.data())) / (2 * h);
        BOOST_TEST_CONTEXT(what << ", coordinate " << i << ": analytic " << g[i] << ", finite difference " << fd) {
            BOOST_TEST(std::abs(g[i] - fd) <= 1e-6 * std::max(1.0, largest));
        }
    }
}

// A triangle in the plane of unit normal n: the 2D points (p, q) at p a + q b.
Corners in_plane(const pm::P& n, const std::array<double, 6>& pq) {
    pm::P a, b;
    pm::plane_basis(n, a, b);
    Corners x;
    for (int c = 0; c < 3; ++c) {
        const pm::P p = pq[2 * c] * a + pq[2 * c + 1] * b + pm::P{0.3, -0.2, 0.1};
        x.insert(x.end(), {p.x, p.y, p.z});
    }
    return x;
}

pm::P unit(pm::P v) { return (1.0 / pm::norm(v)) * v; }

}  // namespace

BOOST_AUTO_TEST_SUITE(target_metrics)

BOOST_AUTO_TEST_CASE(the_plane_basis_is_right_handed_and_keeps_the_xy_axes) {
    pm::P a, b;
    pm::plane_basis({0.0, 0.0, 1.0}, a, b);
    BOOST_TEST(a.x == 1.0);
    BOOST_TEST(a.y == 0.0);
    BOOST_TEST(a.z == 0.0);
    BOOST_TEST(b.x == 0.0);
    BOOST_TEST(b.y == 1.0);
    BOOST_TEST(b.z == 0.0);
    std::mt19937 rng(1);
    std::normal_distribution<double> gauss;
    for (int trial = 0; trial < 50; ++trial) {
        const pm::P n = unit({gauss(rng), gauss(rng), gauss(rng)});
        pm::plane_basis(n, a, b);
        const pm::P c = pm::cross(a, b);
        BOOST_TEST(pm::norm(a) == 1.0, boost::test_tools::tolerance(1e-14));
        BOOST_TEST(std::abs(pm::dot(a, n)) < 1e-14);
        BOOST_TEST(std::abs(pm::dot(a, b)) < 1e-14);
        BOOST_TEST(pm::norm(c - n) < 1e-14);
    }
}

BOOST_AUTO_TEST_CASE(values_follow_the_formulas) {
    std::mt19937 rng(2);
    std::uniform_real_distribution<double> jitter(-0.3, 0.3), grow(0.4, 2.5);
    for (auto kind : {pv::ElementKind::Triangle, pv::ElementKind::Tetrahedron}) {
        const double v0 = pv::test::regular_simplex_volume(kind);
        const auto scale = reference(v0);
        auto shape = metric("mean_ratio", scale), size = metric("scaled_volume", scale);
        auto ss = metric("shape_size", scale), sso = metric("shape_size_orient", scale);
        for (int trial = 0; trial < 40; ++trial) {
            Corners x = pv::test::regular_simplex(kind);
            const double factor = grow(rng);
            for (std::size_t i = 0; i < x.size(); ++i)
                if (kind == pv::ElementKind::Tetrahedron || i % 3 != 2) x[i] = factor * (x[i] + jitter(rng));
            if (trial % 2)
                for (std::size_t i = 0; i < x.size(); i += 3) x[i] = -x[i];  // inverted
            const double m = shape->value(kind, x.data()), tau = size->value(kind, x.data());
            const double o = kind == pv::ElementKind::Tetrahedron ? tet_orientation(x) : xy_triangle_orientation(x);
            BOOST_TEST_CONTEXT(pv::to_string(kind) << ", trial " << trial) {
                BOOST_TEST(ss->value(kind, x.data()) == m * size_term(tau), boost::test_tools::tolerance(1e-12));
                BOOST_TEST(sso->value(kind, x.data()) == m * 0.5 * (1.0 + o) * size_term(tau),
                           boost::test_tools::tolerance(1e-12));
                BOOST_TEST((sso->value(kind, x.data()) <= 0.0) == (trial % 2 == 1));
            }
        }
    }
}

BOOST_AUTO_TEST_CASE(size_rates_too_large_as_too_small) {
    for (auto kind : {pv::ElementKind::Triangle, pv::ElementKind::Tetrahedron}) {
        const int d = kind == pv::ElementKind::Tetrahedron ? 3 : 2;
        const auto scale = reference(pv::test::regular_simplex_volume(kind));
        for (const char* name : {"shape_size", "shape_size_orient"}) {
            auto m = metric(name, scale);
            for (double tau : {2.0, 10.0, 1e6}) {
                Corners big = pv::test::regular_simplex(kind), small = big;
                for (double& c : big) c *= std::pow(tau, 1.0 / d);
                for (double& c : small) c *= std::pow(tau, -1.0 / d);
                BOOST_TEST_CONTEXT(name << " on a " << pv::to_string(kind) << ", tau " << tau) {
                    const double q = m->value(kind, big.data());
                    BOOST_TEST(q == size_term(tau), boost::test_tools::tolerance(1e-9));
                    BOOST_TEST(m->value(kind, small.data()) == q, boost::test_tools::tolerance(1e-9));
                    std::vector<double> g(big.size());
                    m->value_and_gradient(kind, big.data(), g.data());
                    for (double gi : g) BOOST_TEST(std::isfinite(gi));
                }
            }
        }
    }
}

// A triangle turned half a turn in its plane has S = -I: valid (positive area) but o = -1, so
// shape_size_orient rates it 0, the edge of the barrier. (A tetrahedron cannot: -I is a mirror.)
BOOST_AUTO_TEST_CASE(a_triangle_turned_half_a_turn_rates_zero) {
    const auto kind = pv::ElementKind::Triangle;
    auto m = metric("shape_size_orient", reference(pv::test::regular_simplex_volume(kind)));
    Corners x = pv::test::regular_simplex(kind);
    for (std::size_t i = 0; i < x.size(); i += 3) x[i] = -x[i], x[i + 1] = -x[i + 1];
    BOOST_TEST(std::abs(m->value(kind, x.data())) < 1e-15);
    BOOST_TEST(metric("shape_size", m->scale())->value(kind, x.data()) == 1.0, boost::test_tools::tolerance(1e-12));
}

// A planar mesh whose plane is not the xy plane: the element laid out in the plane's basis is
// ideal; gradients (with components along the normal) match finite differences.
BOOST_AUTO_TEST_CASE(triangles_of_a_tilted_plane) {
    const auto kind = pv::ElementKind::Triangle;
    const pm::P n = unit({1.0, 2.0, 3.0});
    pv::MetricScale scale = reference(pv::test::regular_simplex_volume(kind));
    scale.plane_normal = {n.x, n.y, n.z};
    const double r3 = std::sqrt(3.0);
    auto m = metric("shape_size_orient", scale);
    BOOST_TEST(m->value(kind, in_plane(n, {0, 0, 1, 0, 0.5, r3 / 2}).data()) == 1.0, boost::test_tools::tolerance(1e-12));
    std::mt19937 rng(4);
    std::uniform_real_distribution<double> jitter(-0.25, 0.25);
    for (const char* name : {"shape_size", "shape_size_orient"})
        for (int trial = 0; trial < 20; ++trial) {
            Corners x = in_plane(n, {0, 0, 1, 0, 0.5, r3 / 2});
            for (double& c : x) c += jitter(rng);  // off the plane too
            if (trial % 3 == 2)
                for (double& c : x) c *= 2.0;
            check_gradient(*metric(name, scale), kind, x, std::string(name) + ", trial " + std::to_string(trial));
        }
}

// Surface triangles (no orientation): each triangle's basis follows its own normal, and the
// gradient has the basis's twist in it. Normals well away from a tie of their two smallest
// coordinates, where the basis jumps.
BOOST_AUTO_TEST_CASE(surface_triangles_turn_their_basis_with_their_normal) {
    const auto kind = pv::ElementKind::Triangle;
    pv::MetricScale scale = reference(pv::test::regular_simplex_volume(kind));
    scale.oriented_triangles = false;
    std::mt19937 rng(6);
    std::normal_distribution<double> gauss;
    std::uniform_real_distribution<double> jitter(-0.25, 0.25);
    const double r3 = std::sqrt(3.0);
    int checked = 0;
    while (checked < 30) {
        const pm::P n = unit({gauss(rng), gauss(rng), gauss(rng)});
        double c[3] = {std::abs(n.x), std::abs(n.y), std::abs(n.z)};
        std::sort(c, c + 3);
        if (c[1] - c[0] < 0.1) continue;
        Corners x = in_plane(n, {0, 0, 1, 0, 0.5, r3 / 2});
        BOOST_TEST(metric("shape_size_orient", scale)->value(kind, x.data()) == 1.0, boost::test_tools::tolerance(1e-12));
        for (double& v : x) v += jitter(rng);
        for (const char* name : {"shape_size", "shape_size_orient"})
            check_gradient(*metric(name, scale), kind, x, std::string(name) + ", surface trial " + std::to_string(checked));
        ++checked;
    }
}

// S = 0 with corners apart: a triangle of an oriented plane standing on its normal. Zero, and a
// zero gradient.
BOOST_AUTO_TEST_CASE(a_triangle_with_no_extent_in_the_plane_rates_zero) {
    const auto kind = pv::ElementKind::Triangle;
    auto m = metric("shape_size_orient", reference(1.0));
    const Corners x = {0, 0, 0, 0, 0, 1, 0, 0, 2};
    std::vector<double> g(9, 1.0);
    BOOST_TEST(m->value_and_gradient(kind, x.data(), g.data()) == 0.0);
    for (double gi : g) BOOST_TEST(gi == 0.0);
}

BOOST_AUTO_TEST_SUITE_END()
