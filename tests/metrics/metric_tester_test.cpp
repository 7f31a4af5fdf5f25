// The generic metric tester: every metric in the catalogue passes the same checks on both
// element kinds — ideal value, gradient against finite differences, invariance under
// translation, rotation, uniform scaling and even corner permutations, and sensible values on
// inverted and degenerate elements. A metric that says it rates size (rates_size()) or
// orientation (rotation_invariant() false) is checked for falling below the ideal when scaled or
// turned instead of for invariance under turns.
#include <boost/test/data/test_case.hpp>
#include <boost/test/unit_test.hpp>
#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "paloverde/metrics/quality_metric.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;
namespace bdata = boost::unit_test::data;

namespace {

using Corners = std::vector<double>;

Corners ideal(pv::ElementKind kind) { return pv::test::regular_simplex(kind); }
double ideal_volume(pv::ElementKind kind) { return pv::test::regular_simplex_volume(kind); }

// A valid but distorted element: the ideal one with every coordinate moved by up to `amount`.
Corners distorted(pv::ElementKind kind, std::mt19937& rng, double amount) {
    std::uniform_real_distribution<double> jitter(-amount, amount);
    Corners x = ideal(kind);
    for (std::size_t i = 0; i < x.size(); ++i)
        if (kind == pv::ElementKind::Tetrahedron || i % 3 != 2) x[i] += jitter(rng);
    return x;
}

std::unique_ptr<pv::QualityMetric> metric_for(const std::string& name, pv::ElementKind kind, double scale = 1.0) {
    auto m = pv::make_metric(name);
    pv::MetricScale s;
    s.reference_volume = ideal_volume(kind) * std::pow(scale, kind == pv::ElementKind::Triangle ? 2 : 3);
    m->set_scale(s);
    return m;
}

const std::vector<std::string>& names() { return pv::metric_names(); }
const std::array<pv::ElementKind, 2> kKinds{pv::ElementKind::Triangle, pv::ElementKind::Tetrahedron};

// Sign-preserving measure of the volume, to know which elements are inverted.
double signed_measure(pv::ElementKind kind, const Corners& x) {
    auto m = metric_for("scaled_volume", kind);
    return m->value(kind, x.data());
}

}  // namespace

BOOST_AUTO_TEST_SUITE(metric_tester)

BOOST_DATA_TEST_CASE(ideal_element_has_the_ideal_value, bdata::make(names()), name) {
    for (auto kind : kKinds) {
        auto m = metric_for(name, kind);
        if (!m->supports(kind)) continue;
        BOOST_TEST_CONTEXT(name << " on a " << pv::to_string(kind)) {
            const Corners x = ideal(kind);
            BOOST_TEST(m->value(kind, x.data()) == m->ideal_value(), boost::test_tools::tolerance(1e-12));
        }
    }
}

BOOST_DATA_TEST_CASE(distorted_elements_are_worse_than_ideal, bdata::make(names()), name) {
    std::mt19937 rng(7);
    for (auto kind : kKinds) {
        auto m = metric_for(name, kind);
        if (!m->supports(kind) || name == "scaled_volume") continue;  // volume is about size, not shape
        for (int trial = 0; trial < 50; ++trial) {
            const Corners x = distorted(kind, rng, 0.2);
            const double v = m->value(kind, x.data());
            BOOST_TEST_CONTEXT(name << " on a " << pv::to_string(kind) << ", trial " << trial) {
                BOOST_TEST(v > 0.0);
                if (name != "untangle_hybrid") BOOST_TEST(v <= m->ideal_value() * (1 + 1e-12));
            }
        }
    }
}

BOOST_DATA_TEST_CASE(gradient_matches_finite_differences, bdata::make(names()), name) {
    std::mt19937 rng(11);
    for (auto kind : kKinds) {
        auto m = metric_for(name, kind);
        if (!m->supports(kind) || !m->has_gradient()) continue;
        for (int trial = 0; trial < 40; ++trial) {
            // Inverted elements too (trials >= 20 mirror the element), where the metric is smooth.
            Corners x = distorted(kind, rng, 0.25);
            if (trial >= 20)
                for (std::size_t i = 0; i < x.size(); i += 3) x[i] = -x[i];
            // A metric that rates size also meets elements far from the reference volume (tau
            // from about 0.1 to 8), where its size term bends the other way.
            if (m->rates_size() && trial % 4 == 3)
                for (double& c : x) c *= trial % 8 == 3 ? 2.0 : 0.5;
            if (std::abs(signed_measure(kind, x)) < 0.05) continue;  // mean ratio's kink and edge-ratio ties
            std::vector<double> g(x.size());
            const double v = m->value_and_gradient(kind, x.data(), g.data());
            BOOST_TEST(v == m->value(kind, x.data()), boost::test_tools::tolerance(1e-14));
            const double h = 1e-6;
            double scale = 0.0;
            for (double gi : g) scale = std::max(scale, std::abs(gi));
            for (std::size_t i = 0; i < x.size(); ++i) {
                Corners plus = x, minus = x;
                plus[i] += h;
                minus[i] -= h;
                const double fd = (m->value(kind, plus.data()) - m->value(kind, minus.data())) / (2 * h);
                BOOST_TEST_CONTEXT(name << " on a " << pv::to_string(kind) << ", trial " << trial << ", coordinate "
                                        << i << ": analytic " << g[i] << ", finite difference " << fd) {
                    BOOST_TEST(std::abs(g[i] - fd) <= 1e-6 * std::max(1.0, scale));
                }
            }
        }
    }
}

// Scaled by the same factor as the reference volume (scale-free volumes are invariant). A metric
// that rates orientation (rotation_invariant() false) is only translated and scaled, not turned
// nor permuted: the next test checks that turning it costs.
BOOST_DATA_TEST_CASE(invariant_under_translation_rotation_scaling_and_even_permutation, bdata::make(names()), name) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> angle(0.0, 6.283185307179586);
    for (auto kind : kKinds) {
        if (!metric_for(name, kind)->supports(kind)) continue;
        const bool turns = metric_for(name, kind)->rotation_invariant();
        const int corners = pv::corner_count(kind);
        for (int trial = 0; trial < 20; ++trial) {
            const Corners x = distorted(kind, rng, 0.2);
            const double reference = metric_for(name, kind)->value(kind, x.data());
            // Rotation about z keeps triangles in the oriented plane; tets also get a tilt.
            double a = angle(rng), b = kind == pv::ElementKind::Tetrahedron ? angle(rng) : 0.0;
            if (!turns) a = b = 0.0;
            const double scale = std::pow(10.0, trial % 9 - 4);  // 1e-4 .. 1e4
            Corners y = x;
            for (int c = 0; c < corners; ++c) {
                double px = x[3 * c], py = x[3 * c + 1], pz = x[3 * c + 2];
                double qx = std::cos(a) * px - std::sin(a) * py, qy = std::sin(a) * px + std::cos(a) * py;
                double ry = std::cos(b) * qy - std::sin(b) * pz, rz = std::sin(b) * qy + std::cos(b) * pz;
                y[3 * c] = scale * qx + 123.0;
                y[3 * c + 1] = scale * ry - 45.0;
                y[3 * c + 2] = scale * rz + 6.0;
            }
            auto scaled = metric_for(name, kind, scale);
            BOOST_TEST_CONTEXT(name << " on a " << pv::to_string(kind) << ", trial " << trial << ", scale " << scale) {
                BOOST_TEST(scaled->value(kind, y.data()) == reference, boost::test_tools::tolerance(1e-8));
                if (!turns) continue;
                // Even permutation of the corners: (0 1 2) -> (1 2 0).
                Corners p = x;
                for (int d = 0; d < 3; ++d) {
                    p[d] = x[3 + d];
                    p[3 + d] = x[6 + d];
                    p[6 + d] = x[d];
                }
                BOOST_TEST(metric_for(name, kind)->value(kind, p.data()) == reference, boost::test_tools::tolerance(1e-12));
            }
        }
    }
}

// What the invariances above leave out: a metric that rates size is ideal only at the reference
// volume, and one that rates orientation only in the regular simplex's own orientation (but
// anywhere it is moved to).
BOOST_DATA_TEST_CASE(size_and_orientation_cost_where_a_metric_rates_them, bdata::make(names()), name) {
    for (auto kind : kKinds) {
        auto m = metric_for(name, kind);
        if (!m->supports(kind) || (!m->rates_size() && m->rotation_invariant())) continue;
        const int corners = pv::corner_count(kind);
        const Corners x = ideal(kind);
        BOOST_TEST_CONTEXT(name << " on a " << pv::to_string(kind)) {
            if (m->rates_size())
                for (double factor : {1.1, 1.0 / 1.1, 3.0}) {
                    Corners y = x;
                    for (double& c : y) c *= factor;
                    BOOST_TEST(m->value(kind, y.data()) < m->ideal_value(), "scaled by " << factor);
                }
            Corners moved = x;
            for (int c = 0; c < corners; ++c) moved[3 * c] += 7.0, moved[3 * c + 1] -= 3.0;
            BOOST_TEST(m->value(kind, moved.data()) == m->ideal_value(), boost::test_tools::tolerance(1e-12));
            if (m->rotation_invariant()) continue;
            // 10 degrees about z (in the plane of a triangle), and for a tet also about x.
            const double c10 = std::cos(std::numbers::pi / 18), s10 = std::sin(std::numbers::pi / 18);
            for (int axis : {2, 0}) {
                if (axis == 0 && kind == pv::ElementKind::Triangle) continue;
                const int i = axis == 2 ? 0 : 1, j = axis == 2 ? 1 : 2;  // the plane turned
                Corners y = x;
                for (int c = 0; c < corners; ++c) {
                    y[3 * c + i] = c10 * x[3 * c + i] - s10 * x[3 * c + j];
                    y[3 * c + j] = s10 * x[3 * c + i] + c10 * x[3 * c + j];
                }
                const double turned = m->value(kind, y.data());
                BOOST_TEST(turned < m->ideal_value(), "turned about axis " << axis);
                BOOST_TEST(turned > 0.9, "turned about axis " << axis);  // a little turn costs a little
            }
        }
    }
}

BOOST_DATA_TEST_CASE(inverted_elements_rate_below_zero_and_degenerate_ones_zero, bdata::make(names()), name) {
    std::mt19937 rng(5);
    for (auto kind : kKinds) {
        auto m = metric_for(name, kind);
        if (!m->supports(kind)) continue;
        for (int trial = 0; trial < 20; ++trial) {
            Corners x = distorted(kind, rng, 0.2);
            for (std::size_t i = 0; i < x.size(); i += 3) x[i] = -x[i];  // mirror: inverted
            BOOST_TEST_CONTEXT(name << " on an inverted " << pv::to_string(kind)) {
                BOOST_TEST(m->value(kind, x.data()) < 0.0);
            }
        }
        // Flat: every corner in one plane (z = 0, or the line y = 0 for triangles).
        Corners flat = ideal(kind);
        if (kind == pv::ElementKind::Tetrahedron) flat[11] = 0.0;
        else flat[7] = 0.0;
        BOOST_TEST_CONTEXT(name << " on a flat " << pv::to_string(kind)) {
            BOOST_TEST(m->value(kind, flat.data()) == 0.0, boost::test_tools::tolerance(1e-12));
            if (m->has_gradient()) {
                std::vector<double> g(flat.size());
                m->value_and_gradient(kind, flat.data(), g.data());
                for (double gi : g) BOOST_TEST(std::isfinite(gi));
            }
        }
        // All corners at one point: no shape at all, and no NaN.
        const Corners point(flat.size(), 2.5);
        BOOST_TEST_CONTEXT(name << " on a collapsed " << pv::to_string(kind)) {
            BOOST_TEST(m->value(kind, point.data()) == 0.0);
        }
    }
}

BOOST_AUTO_TEST_CASE(aspect_ratio_is_mean_ratio_to_the_three_halves) {
    std::mt19937 rng(13);
    const auto kind = pv::ElementKind::Tetrahedron;
    for (int trial = 0; trial < 20; ++trial) {
        const Corners x = distorted(kind, rng, 0.3);
        const double eta = metric_for("mean_ratio", kind)->value(kind, x.data());
        BOOST_TEST(metric_for("aspect_ratio", kind)->value(kind, x.data()) == std::pow(eta, 1.5),
                   boost::test_tools::tolerance(1e-12));
    }
}

BOOST_AUTO_TEST_CASE(hybrid_is_positive_exactly_for_positive_volume) {
    const auto kind = pv::ElementKind::Tetrahedron;
    auto hybrid = metric_for("untangle_hybrid", kind);
    Corners x = ideal(kind);
    for (double z : {-1.0, -1e-3, -1e-9, 1e-9, 1e-3, 1.0}) {
        x[11] = z;
        BOOST_TEST((hybrid->value(kind, x.data()) > 0.0) == (z > 0.0));
    }
}

BOOST_AUTO_TEST_CASE(unknown_metric_names_are_rejected_with_the_known_ones) {
    BOOST_CHECK_EXCEPTION(pv::make_metric("aspect"), std::exception, [](const std::exception& e) {
        return std::string(e.what()).find("aspect_ratio") != std::string::npos;
    });
    pv::MetricOptions bad;
    bad.hybrid_sharpness = -1.0;
    BOOST_CHECK_THROW(pv::make_metric("untangle_hybrid", bad), std::exception);
}

BOOST_AUTO_TEST_SUITE_END()
