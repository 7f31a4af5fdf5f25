// dihedral_sine against the angles themselves: for random tetrahedra its value is the smallest sine
// of the six dihedral angles (minus the largest for an inverted one), each angle measured with
// atan2 from the edge's two faces, over the regular tetrahedron's; for triangles, the smallest sine
// of the corner angles over sin 60 degrees. (The generic tester checks its gradient, invariance and
// signs.)
#include <boost/test/unit_test.hpp>
#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "paloverde/metrics/quality_metric.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;

namespace {

using V3 = std::array<double, 3>;
V3 sub(const V3& a, const V3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
V3 cross(const V3& a, const V3& b) { return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}; }
double dot(const V3& a, const V3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double norm(const V3& a) { return std::sqrt(dot(a, a)); }

// The smallest of the six terms sign(V) sin(angle): the smallest sine of a valid tetrahedron, minus
// the largest of an inverted one.
double smallest_dihedral_sine(const std::vector<double>& x) {
    V3 p[4];
    for (int i = 0; i < 4; ++i) p[i] = {x[3 * i], x[3 * i + 1], x[3 * i + 2]};
    const double volume = dot(sub(p[1], p[0]), cross(sub(p[2], p[0]), sub(p[3], p[0])));
    const double sign = volume > 0 ? 1.0 : -1.0;
    double smallest = 2.0;
    for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j) {
            int k = 0, l = 0;  // the other two corners
            for (int c = 0, n = 0; c < 4; ++c)
                if (c != i && c != j) (n++ == 0 ? k : l) = c;
            // The angle at edge ij between the faces (i, j, k) and (i, j, l): between the parts of
            // the edges to k and to l that are perpendicular to ij.
            const V3 e = sub(p[j], p[i]);
            const V3 u = cross(e, cross(sub(p[k], p[i]), e)), w = cross(e, cross(sub(p[l], p[i]), e));
            const double angle = std::atan2(norm(cross(u, w)), dot(u, w));
            smallest = std::min(smallest, sign * std::sin(angle));
        }
    return smallest / (2.0 * std::sqrt(2.0) / 3.0);
}

}  // namespace

BOOST_AUTO_TEST_SUITE(dihedral_sine)

BOOST_AUTO_TEST_CASE(is_the_smallest_sine_of_the_dihedral_angles) {
    auto metric = pv::make_metric("dihedral_sine");
    const auto tet = pv::ElementKind::Tetrahedron;
    std::mt19937 rng(29);
    std::uniform_real_distribution<double> jitter(-0.45, 0.45);
    for (int trial = 0; trial < 200; ++trial) {
        auto x = pv::test::regular_simplex(tet);
        for (double& c : x) c += jitter(rng);
        if (trial % 2)
            for (std::size_t i = 0; i < x.size(); i += 3) x[i] = -x[i];  // mirrored
        BOOST_TEST(metric->value(tet, x.data()) == smallest_dihedral_sine(x), boost::test_tools::tolerance(1e-9));
    }
}

BOOST_AUTO_TEST_CASE(triangles_rate_their_corner_angles) {
    auto metric = pv::make_metric("dihedral_sine");
    const auto tri = pv::ElementKind::Triangle;
    // Angles 90, 60, 30 degrees: the smallest sine is sin 30.
    const std::vector<double> x{0, 0, 0, 1, 0, 0, 0, std::sqrt(3.0), 0};
    BOOST_TEST(metric->value(tri, x.data()) == 0.5 / (std::sqrt(3.0) / 2), boost::test_tools::tolerance(1e-12));
    // Angles 120, 30, 30: sin 120 = sin 60 is not the smallest, sin 30 is.
    const std::vector<double> obtuse{0, 0, 0, 1, 0, 0, 0.5, std::sqrt(3.0) / 6, 0};
    BOOST_TEST(metric->value(tri, obtuse.data()) == 0.5 / (std::sqrt(3.0) / 2), boost::test_tools::tolerance(1e-12));
}

// The global solver's terms (make_dihedral_sine_term): the angle at edge 01 alone. Over the six
// even corner orders that put each edge first (the workspace's copies), the smallest term is
// dihedral_sine; each term's gradient matches finite differences, valid and inverted alike.
BOOST_AUTO_TEST_CASE(six_terms_make_the_smallest_sine_and_each_has_its_gradient) {
    constexpr int kCopies[6][4] = {{0, 1, 2, 3}, {0, 2, 3, 1}, {0, 3, 1, 2}, {1, 2, 0, 3}, {1, 3, 2, 0}, {2, 3, 0, 1}};
    auto whole = pv::make_metric("dihedral_sine");
    auto term = pv::make_dihedral_sine_term();
    const auto tet = pv::ElementKind::Tetrahedron;
    std::mt19937 rng(31);
    std::uniform_real_distribution<double> jitter(-0.4, 0.4);
    int checked = 0;
    for (int trial = 0; trial < 100; ++trial) {
        auto x = pv::test::regular_simplex(tet);
        for (double& c : x) c += jitter(rng);
        if (trial % 2)
            for (std::size_t i = 0; i < x.size(); i += 3) x[i] = -x[i];  // mirrored: inverted
        double smallest = 2.0;
        for (const auto& order : kCopies) {
            std::vector<double> y;
            for (int i : order)
                for (int d = 0; d < 3; ++d) y.push_back(x[3 * i + d]);
            double g[12];
            const double value = term->value_and_gradient(tet, y.data(), g);
            smallest = std::min(smallest, value);
            const double h = 1e-6;
            for (int i = 0; i < 12; ++i) {
                auto plus = y, minus = y;
                plus[i] += h;
                minus[i] -= h;
                const double fd = (term->value(tet, plus.data()) - term->value(tet, minus.data())) / (2 * h);
                BOOST_TEST_CONTEXT("trial " << trial << ", coordinate " << i << ": analytic " << g[i] << ", finite difference " << fd) {
                    BOOST_TEST(std::abs(g[i] - fd) <= 1e-6 * std::max(1.0, std::abs(g[i])));
                }
            }
            ++checked;
        }
        BOOST_TEST(smallest == whole->value(tet, x.data()), boost::test_tools::tolerance(1e-12));
    }
    BOOST_TEST(checked == 600);
}

BOOST_AUTO_TEST_SUITE_END()
