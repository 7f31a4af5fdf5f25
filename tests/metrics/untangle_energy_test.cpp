// The regularized untangling energy (outside the metric catalogue, so the generic tester does not
// reach it): its gradient against finite differences on valid, inverted and nearly flat elements
// at several epsilons, its value for the reference element, its invariance, and the barrier it
// becomes as epsilon shrinks.
#include <boost/test/unit_test.hpp>
#include <cmath>
#include <random>
#include <vector>

#include "paloverde/core/error.hpp"
#include "paloverde/metrics/quality_metric.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;

namespace {

using Corners = std::vector<double>;

Corners regular(pv::ElementKind kind) { return pv::test::regular_simplex(kind); }
double regular_volume(pv::ElementKind kind) { return pv::test::regular_simplex_volume(kind); }

std::unique_ptr<pv::QualityMetric> energy(double epsilon, double reference_volume) {
    auto m = pv::make_untangle_energy(epsilon, 1.0 / 128.0);
    pv::MetricScale s;
    s.reference_volume = reference_volume;
    m->set_scale(s);
    return m;
}

const pv::ElementKind kKinds[] = {pv::ElementKind::Triangle, pv::ElementKind::Tetrahedron};

}  // namespace

BOOST_AUTO_TEST_SUITE(untangle_energy)

BOOST_AUTO_TEST_CASE(the_reference_element_rates_minus_one_as_epsilon_vanishes) {
    for (auto kind : kKinds) {
        const Corners x = regular(kind);
        BOOST_TEST(energy(1e-9, regular_volume(kind))->value(kind, x.data()) == -1.0, boost::test_tools::tolerance(1e-12));
        // A larger epsilon only lowers chi's hold on the volume: the value rises toward zero.
        BOOST_TEST(energy(0.5, regular_volume(kind))->value(kind, x.data()) > -1.0);
    }
}

BOOST_AUTO_TEST_CASE(gradient_matches_finite_differences_on_valid_inverted_and_flat_elements) {
    std::mt19937 rng(17);
    std::uniform_real_distribution<double> jitter(-0.3, 0.3);
    for (auto kind : kKinds) {
        for (double epsilon : {1.0, 0.1, 1e-3}) {
            const auto m = energy(epsilon, regular_volume(kind));
            for (int trial = 0; trial < 30; ++trial) {
                Corners x = regular(kind);
                for (std::size_t i = 0; i < x.size(); ++i)
                    if (kind == pv::ElementKind::Tetrahedron || i % 3 != 2) x[i] += jitter(rng);
                if (trial % 3 == 1)
                    for (std::size_t i = 0; i < x.size(); i += 3) x[i] = -x[i];  // inverted
                if (trial % 3 == 2) x[kind == pv::ElementKind::Tetrahedron ? 11 : 7] = 1e-4;  // nearly flat
                std::vector<double> g(x.size());
                const double value = m->value_and_gradient(kind, x.data(), g.data());
                BOOST_TEST(value == m->value(kind, x.data()), boost::test_tools::tolerance(1e-14));
                double scale = 0.0;
                for (double gi : g) scale = std::max(scale, std::abs(gi));
                for (std::size_t i = 0; i < x.size(); ++i) {
                    if (kind == pv::ElementKind::Triangle && i % 3 == 2) continue;  // out of the plane
                    const double h = 1e-7;
                    Corners plus = x, minus = x;
                    plus[i] += h;
                    minus[i] -= h;
                    const double fd = (m->value(kind, plus.data()) - m->value(kind, minus.data())) / (2 * h);
                    BOOST_TEST_CONTEXT(pv::to_string(kind) << ", epsilon " << epsilon << ", trial " << trial << ", coordinate "
                                                           << i << ": analytic " << g[i] << ", finite difference " << fd) {
                        BOOST_TEST(std::abs(g[i] - fd) <= 1e-5 * std::max(1.0, scale));
                    }
                }
            }
        }
    }
}

BOOST_AUTO_TEST_CASE(invariant_under_translation_rotation_and_scaling_with_the_reference) {
    for (auto kind : kKinds) {
        Corners x = regular(kind);
        x[3] += 0.2;
        x[7] -= 0.1;
        const double reference = energy(0.1, regular_volume(kind))->value(kind, x.data());
        for (double scale : {1e-4, 1.0, 1e4}) {
            const double a = 0.7;
            Corners y = x;
            for (std::size_t c = 0; c < x.size(); c += 3) {
                y[c] = scale * (std::cos(a) * x[c] - std::sin(a) * x[c + 1]) + 3.0;
                y[c + 1] = scale * (std::sin(a) * x[c] + std::cos(a) * x[c + 1]) - 2.0;
                y[c + 2] = scale * x[c + 2] + (kind == pv::ElementKind::Tetrahedron ? 1.0 : 0.0);
            }
            const double volume = regular_volume(kind) * std::pow(scale, kind == pv::ElementKind::Triangle ? 2 : 3);
            BOOST_TEST(energy(0.1, volume)->value(kind, y.data()) == reference, boost::test_tools::tolerance(1e-9));
        }
    }
}

// Finite everywhere for epsilon > 0 (a tangle has an energy to lower); as epsilon shrinks, an
// inverted or flat element costs without bound, and a valid one converges.
BOOST_AUTO_TEST_CASE(finite_for_any_element_and_a_barrier_as_epsilon_shrinks) {
    const auto kind = pv::ElementKind::Tetrahedron;
    Corners inverted = regular(kind);
    inverted[11] = -inverted[11];
    Corners flat = regular(kind);
    flat[11] = 0.0;
    const Corners valid = regular(kind);
    double previous_inverted = 0.0, previous_flat = 0.0;
    for (double epsilon : {1.0, 1e-2, 1e-4, 1e-8}) {
        const auto m = energy(epsilon, regular_volume(kind));
        const double e_inverted = m->value(kind, inverted.data()), e_flat = m->value(kind, flat.data());
        BOOST_TEST(std::isfinite(e_inverted));
        BOOST_TEST(std::isfinite(e_flat));
        if (epsilon < 1.0) {
            BOOST_TEST(e_inverted < 10 * previous_inverted);
            BOOST_TEST(e_flat < 10 * previous_flat);
        }
        previous_inverted = e_inverted;
        previous_flat = e_flat;
        BOOST_TEST(m->value(kind, valid.data()) > -1.2);
    }
    BOOST_CHECK_THROW(pv::make_untangle_energy(0.0, 0.1), pv::OptionError);
    BOOST_CHECK_THROW(pv::make_untangle_energy(1.0, 2.0), pv::OptionError);
}

BOOST_AUTO_TEST_SUITE_END()
