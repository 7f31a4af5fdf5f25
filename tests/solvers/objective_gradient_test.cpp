// The whole objective's gradient (metric gradients weighted by the objective and summed over the
// mesh by the solver's workspace) against finite differences.
#include <boost/test/unit_test.hpp>
#include <algorithm>
#include <cstdint>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "paloverde/core/error.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/perturb.hpp"
#include "paloverde/objectives/objective_function.hpp"
#include "solvers/newton_direction.hpp"
#include "solvers/workspace.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;

BOOST_AUTO_TEST_SUITE(objective_gradient)

BOOST_AUTO_TEST_CASE(whole_mesh_gradient_matches_finite_differences) {
    for (const char* metric_name : {"aspect_ratio", "mean_ratio", "inverse_condition", "untangle_hybrid"}) {
        for (const std::string objective_name : {"log_barrier", "p_mean", "mean_above_floor"}) {
            auto mesh = pv::read_mesh(pv::test::shared_data("mesquite/tets/tet_4_tangled.vtk")).mesh;
            if (objective_name != "log_barrier") {
                // p-mean needs positive qualities (and the floor lies below them): an untangled mesh.
                mesh = pv::read_mesh(pv::test::shared_data("stellar/house2.node")).mesh;
            }
            pv::detail::Workspace work(mesh, true);
            auto metric = pv::make_metric(metric_name);
            metric->set_scale(work.scale());
            std::unique_ptr<pv::ObjectiveFunction> objective;
            if (objective_name == "mean_above_floor") objective = std::make_unique<pv::MeanAboveFloor>();
            else objective = pv::make_objective(objective_name);
            const pv::Reducer serial;
            std::vector<double> x(work.mesh().coordinates().begin(), work.mesh().coordinates().end());
            const auto m = static_cast<std::size_t>(work.movable_elements());
            std::vector<double> q(m), w(m), g(x.size());
            work.evaluate(*metric, x, q);
            objective->update(q, serial);  // fixes t and mu for the comparison
            if (auto* mean = dynamic_cast<pv::MeanAboveFloor*>(objective.get())) {
                // A floor close under the worst element: its barrier term bends sharply.
                const double worst = *std::min_element(q.begin(), q.end());
                mean->set_floor(worst - 0.02, 0.01);
            }
            auto F = [&](const std::vector<double>& at) {
                std::vector<double> qq(m);
                work.evaluate(*metric, at, qq);
                return objective->value(qq, serial);
            };
            objective->weights(q, w);
            work.gradient(*metric, x, w, g);
            double largest = 0.0;
            for (double gi : g) largest = std::max(largest, std::abs(gi));
            const double h = 1e-7 * work.reference_length();
            int checked = 0;
            for (std::size_t i = 0; i < x.size() && checked < 60; i += 7) {
                if (!work.mesh().can_move(static_cast<pv::VertexId>(i / 3))) {
                    BOOST_TEST(g[i] == 0.0);
                    continue;
                }
                auto plus = x, minus = x;
                plus[i] += h;
                minus[i] -= h;
                const double fd = (F(plus) - F(minus)) / (2 * h);
                BOOST_TEST_CONTEXT(metric_name << " / " << objective_name << " coordinate " << i << ": " << g[i] << " vs "
                                               << fd) {
                    BOOST_TEST(std::abs(g[i] - fd) <= 1e-5 * largest);
                }
                ++checked;
            }
            BOOST_TEST(checked > 10);
        }
    }
}

// The mean above a floor: its weights are its value's derivatives, its curvature weights their
// negated derivatives; below the floor it has no value; its state carries floor and mu.
BOOST_AUTO_TEST_CASE(mean_above_floor_weights_and_curvature_match_finite_differences) {
    const pv::Reducer serial;
    pv::MeanAboveFloor objective;
    objective.set_floor(0.2, 0.03);
    const std::vector<double> q{0.21, 0.25, 0.4, 0.9, 0.2003};
    std::vector<double> w(q.size()), c(q.size());
    objective.weights(q, w);
    objective.curvature_weights(q, c);
    for (std::size_t i = 0; i < q.size(); ++i) {
        const double h = 1e-7 * (q[i] - 0.2);
        auto plus = q, minus = q;
        plus[i] += h;
        minus[i] -= h;
        const double dvalue = (objective.value(plus, serial) - objective.value(minus, serial)) / (2 * h);
        BOOST_TEST(dvalue == w[i], boost::test_tools::tolerance(1e-6));
        std::vector<double> wp(q.size()), wm(q.size());
        objective.weights(plus, wp);
        objective.weights(minus, wm);
        BOOST_TEST(-(wp[i] - wm[i]) / (2 * h) == c[i], boost::test_tools::tolerance(1e-6));
        BOOST_TEST(w[i] > 1.0);  // the barrier pushes every element up
    }
    BOOST_TEST(objective.domain_floor() == 0.2);
    auto at_floor = q;
    at_floor[1] = 0.2;
    BOOST_TEST(objective.value(at_floor, serial) == -std::numeric_limits<double>::infinity());
    pv::MeanAboveFloor restored;
    restored.restore_state(objective.state());
    BOOST_TEST(restored.value(q, serial) == objective.value(q, serial));
    BOOST_CHECK_THROW(restored.set_floor(std::numeric_limits<double>::quiet_NaN(), 0.1), pv::OptionError);
    BOOST_CHECK_THROW(restored.set_floor(0.1, 0.0), pv::OptionError);
    BOOST_CHECK_THROW(restored.restore_state(std::vector<double>{0.1}), pv::Error);
}

// A focus's gradient pass keeps only the vertices its elements touch (compact lanes): each moving
// vertex still gets the whole mesh's sums bit for bit, curvature included, and nothing outside
// the focus's elements is written.
BOOST_AUTO_TEST_CASE(focused_gradient_is_the_whole_meshs_at_the_moving_vertices) {
    auto mesh = pv::read_mesh(pv::test::shared_data("mesquite/tets/tire.vtk")).mesh;
    pv::detail::Workspace work(mesh, true);
    auto metric = pv::make_metric("aspect_ratio");
    metric->set_scale(work.scale());
    const std::vector<double> x(work.mesh().coordinates().begin(), work.mesh().coordinates().end());
    const auto m = static_cast<std::size_t>(work.movable_elements());
    std::vector<double> q(m), w(m), cw(m), g(x.size()), c(2 * x.size());
    work.evaluate(*metric, x, q);
    for (std::size_t e = 0; e < m; ++e) {
        w[e] = 1.0 / (q[e] + 0.01);
        cw[e] = w[e] * w[e];
    }
    work.gradient(*metric, x, w, g, cw, c);
    // The vertices of the worst hundredth of the elements move.
    std::vector<double> sorted(q);
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(m / 100), sorted.end());
    const double below = sorted[m / 100];
    std::vector<std::uint8_t> moving(static_cast<std::size_t>(work.mesh().num_vertices()), 0);
    for (std::size_t e = 0; e < m; ++e)
        if (q[e] < below)
            for (pv::VertexId v : work.mesh().element(static_cast<pv::ElementId>(e))) moving[v] = 1;
    work.focus(moving);
    const auto elements = work.focus_elements();
    BOOST_TEST_REQUIRE(elements.size() < m / 2);
    std::vector<double> wf(elements.size()), cwf(elements.size());
    for (std::size_t i = 0; i < elements.size(); ++i) {
        wf[i] = w[static_cast<std::size_t>(elements[i])];
        cwf[i] = cw[static_cast<std::size_t>(elements[i])];
    }
    const double untouched = 7.0;
    std::vector<double> gf(x.size(), untouched), cf(2 * x.size(), untouched);
    work.gradient(*metric, x, wf, gf, cwf, cf);
    const auto free = work.free_vertices();
    BOOST_TEST_REQUIRE(free.size() > 50u);
    int differ = 0;
    for (pv::VertexId v : free) {
        for (int k = 0; k < 3; ++k) differ += gf[3 * v + k] != g[3 * v + k];
        for (int k = 0; k < 6; ++k) differ += cf[6 * v + k] != c[6 * v + k];
    }
    BOOST_TEST(differ == 0);
    std::vector<std::uint8_t> in_focus(moving.size(), 0);
    for (pv::ElementId e = 0; e < work.movable_elements(); ++e)
        for (pv::VertexId v : work.mesh().element(e)) in_focus[v] = 1;
    int outside = 0, written = 0;
    for (std::size_t v = 0; v < in_focus.size(); ++v) {
        if (in_focus[v]) continue;
        ++outside;
        written += gf[3 * v] != untouched || cf[6 * v] != untouched;
    }
    BOOST_TEST(outside > 0);
    BOOST_TEST(written == 0);
    work.unfocus();
}

// A renumbered workspace mesh (and each focus made from it) is marked as in locality order, where
// the passes stop asking for corners ahead; asking or not, they give the same bits.
BOOST_AUTO_TEST_CASE(passes_over_a_locality_ordered_mesh_give_the_same_bits) {
    auto mesh = pv::read_mesh(pv::test::shared_data("mesquite/tets/tire.vtk")).mesh;
    BOOST_TEST(!mesh.locality_ordered());
    BOOST_TEST(!pv::detail::Workspace(mesh, false).mesh().locality_ordered());
    pv::detail::Workspace work(mesh, true);
    const pv::Mesh& ordered = work.mesh();
    BOOST_TEST_REQUIRE(ordered.locality_ordered());
    pv::Mesh unmarked = ordered;
    BOOST_TEST(unmarked.locality_ordered());  // copies keep the mark
    unmarked.set_locality_ordered(false);
    auto metric = pv::make_metric("aspect_ratio");
    metric->set_scale(work.scale());
    const std::vector<double> x(ordered.coordinates().begin(), ordered.coordinates().end());
    const pv::ElementId m = work.movable_elements();
    std::vector<double> q(static_cast<std::size_t>(m)), q_unmarked(q.size());
    metric->evaluate(ordered, x, 0, m, q.data());
    metric->evaluate(unmarked, x, 0, m, q_unmarked.data());
    BOOST_TEST(std::equal(q.begin(), q.end(), q_unmarked.begin()));
    std::vector<double> w(q.size()), g(x.size(), 0.0), g_unmarked(x.size(), 0.0);
    for (std::size_t e = 0; e < w.size(); ++e) w[e] = 1.0 / (q[e] + 0.01);
    pv::QualityMetric::GradientTarget target;
    target.weight = w.data();
    target.gradient = g.data();
    metric->accumulate_gradient(ordered, x, 0, m, target);
    target.gradient = g_unmarked.data();
    metric->accumulate_gradient(unmarked, x, 0, m, target);
    BOOST_TEST(std::equal(g.begin(), g.end(), g_unmarked.begin()));
    std::vector<std::uint8_t> moving(static_cast<std::size_t>(ordered.num_vertices()), 0);
    for (pv::VertexId v : ordered.element(0)) moving[v] = 1;
    work.focus(moving);
    BOOST_TEST(work.mesh().locality_ordered());
    work.unfocus();
}

// The Newton direction's Hessian product (a difference of the gradient pass at fixed t, plus
// t's move) against a central difference of the barrier's gradient with t solved afresh at each
// point: -A v = (G(x + e v) - G(x - e v)) / 2e, G = sum mu/(q_i - t(x)) grad q_i.
BOOST_AUTO_TEST_CASE(newton_hessian_product_matches_finite_differences) {
    for (const char* metric_name : {"aspect_ratio", "mean_ratio"}) {
        auto mesh = pv::read_mesh(pv::test::shared_data("stellar/house2.node")).mesh;
        pv::detail::Workspace work(mesh, true);
        auto metric = pv::make_metric(metric_name);
        metric->set_scale(work.scale());
        const pv::Reducer serial;
        const auto m = static_cast<std::size_t>(work.movable_elements());
        const std::vector<double> x(work.mesh().coordinates().begin(), work.mesh().coordinates().end());
        std::vector<double> q(m), w(m), c(m), g(x.size());
        work.evaluate(*metric, x, q);
        auto objective = pv::make_objective("log_barrier");
        objective->update(q, serial);
        objective->advance();  // a smaller mu than the start's, where the worst elements weigh more
        objective->advance();
        objective->update(q, serial);
        objective->weights(q, w);
        objective->curvature_weights(q, c);
        work.gradient(*metric, x, w, g);
        // A smooth direction on the free vertices.
        std::vector<double> v(x.size(), 0.0);
        for (std::size_t i = 0; i < x.size(); ++i)
            if (work.mesh().can_move(static_cast<pv::VertexId>(i / 3))) v[i] = std::sin(0.37 * static_cast<double>(i) + 1.0);
        std::vector<double> av(x.size());
        pv::detail::NewtonDirection newton(work);
        newton.apply(*metric, *objective, x, q, c, g, v, av);
        // The reduced gradient at x + s v, t solved for the qualities there (at the same mu).
        auto reduced_gradient = [&](double s) {
            std::vector<double> at(x), qq(m), ww(m), gg(x.size());
            for (std::size_t i = 0; i < x.size(); ++i) at[i] += s * v[i];
            work.evaluate(*metric, at, qq);
            auto there = pv::make_objective("log_barrier");
            there->restore_state(objective->state());
            there->update(qq, serial);
            there->weights(qq, ww);
            work.gradient(*metric, at, ww, gg);
            return gg;
        };
        const double e = 1e-5 * work.reference_length();
        const auto plus = reduced_gradient(e), minus = reduced_gradient(-e);
        double largest = 0.0;
        for (std::size_t i = 0; i < x.size(); ++i) largest = std::max(largest, std::abs(plus[i] - minus[i]) / (2 * e));
        BOOST_TEST_REQUIRE(largest > 0.0);
        double worst = 0.0;
        for (std::size_t i = 0; i < x.size(); ++i)
            worst = std::max(worst, std::abs(-av[i] - (plus[i] - minus[i]) / (2 * e)));
        BOOST_TEST_MESSAGE(metric_name << ": largest entry " << largest << ", largest difference " << worst);
        BOOST_TEST_CONTEXT(metric_name << ": largest entry " << largest << ", largest difference " << worst) {
            BOOST_TEST(worst <= 1e-4 * largest);
        }
    }
}

BOOST_AUTO_TEST_CASE(barrier_t_solves_its_optimality_condition) {
    const std::vector<double> q{0.2, 0.5, 0.9, 0.3, 0.7};
    pv::LogBarrier barrier(0.5, 0.01);
    const pv::Reducer serial;
    barrier.update(q, serial);
    double s = 0.0;
    for (double v : q) s += 1.0 / (v - barrier.t());
    BOOST_TEST(barrier.mu() * s == 1.0, boost::test_tools::tolerance(1e-10));
    BOOST_TEST(barrier.t() < 0.2);
    barrier.advance();
    barrier.update(q, serial);
    BOOST_TEST(barrier.mu() == 0.005);
    const double t_small_mu = barrier.t();
    BOOST_TEST(t_small_mu > 0.19);  // t climbs towards the worst quality as mu shrinks
}

// Elements that are all nearly alike: the spread (1e-13 here) is no scale for the barrier's
// first gap, which would make it so steep that the ascent creeps.
BOOST_AUTO_TEST_CASE(barrier_starts_a_sizeable_gap_below_elements_that_are_all_alike) {
    std::vector<double> q(1000);
    for (std::size_t i = 0; i < q.size(); ++i) q[i] = 0.5 + 1e-16 * static_cast<double>(i);
    pv::LogBarrier barrier;
    barrier.update(q, pv::Reducer{});
    BOOST_TEST(0.5 - barrier.t() >= 1e-3 * 0.5);
    BOOST_TEST(barrier.t() < 0.5);
}

// With barrier_initial_active 0 (the default) the barrier first weighs about 0.5% of the
// elements like the worst, at least 10,000: the same start as those numbers given explicitly.
BOOST_AUTO_TEST_CASE(barrier_start_follows_the_element_count) {
    auto start = [](std::size_t n, double initial_active) {
        std::vector<double> q(n);
        for (std::size_t i = 0; i < n; ++i) q[i] = 0.1 + 0.8 * std::sqrt(static_cast<double>(i) / static_cast<double>(n));
        pv::LogBarrier barrier(0.8, 0.0, initial_active);
        barrier.update(q, pv::Reducer{});
        return std::pair{barrier.mu(), barrier.t()};
    };
    BOOST_TEST((start(100'000, 0.0) == start(100'000, 1e4)));
    BOOST_TEST((start(3'000'000, 0.0) == start(3'000'000, 15'000.0)));
    BOOST_TEST((start(3'000'000, 0.0) != start(3'000'000, 1e4)));
    BOOST_CHECK_THROW(pv::LogBarrier(0.8, 0.0, 0.5), pv::OptionError);
}

// A focus moves the worst elements only; the still ones keep weighing in the barrier's t
// (LogBarrier::hold_still), which therefore lies where the whole mesh's barrier puts it: from the
// moving elements alone it would climb to within a few mu of the worst quality.
BOOST_AUTO_TEST_CASE(barrier_t_weighs_the_still_elements) {
    const std::size_t n = 200'000;
    // As a focus passes them: +infinity where an element moves (skipped), its quality where not.
    const double in_focus = std::numeric_limits<double>::infinity();
    std::vector<double> all(n), moving, still(n, in_focus);
    for (std::size_t i = 0; i < n; ++i) {
        all[i] = 0.1 + 0.8 * std::sqrt(static_cast<double>(i) / static_cast<double>(n));
        if (all[i] < 0.15) moving.push_back(all[i]);
        else still[i] = all[i];
    }
    const pv::Reducer serial;
    const double mu = 1e-5;
    pv::LogBarrier whole(0.8, mu), focused(0.8, mu), alone(0.8, mu);
    whole.update(all, serial);
    focused.hold_still(still, serial);
    focused.update(moving, serial);
    alone.update(moving, serial);
    const double gap = 0.1 - whole.t();
    BOOST_TEST(std::abs(focused.t() - whole.t()) <= 1e-3 * gap);
    BOOST_TEST(0.1 - alone.t() < 0.1 * gap);  // far closer: the weight on the worst few alone
    // No still element: the barrier of the moving elements alone again.
    focused.hold_still({}, serial);
    focused.update(moving, serial);
    BOOST_TEST(std::abs(focused.t() - alone.t()) <= 1e-9 * gap);
}

// Qualities from 0.2 up: a focus's 100 lowest, and the 2,000 of a wider one.
struct GrowingFocus {
    std::vector<double> small, large;
    GrowingFocus() {
        for (int i = 0; i < 2000; ++i) {
            const double q = 0.2 + 0.1 * std::sqrt(i / 2000.0);
            if (i < 100) small.push_back(q);
            large.push_back(q);
        }
    }
};

// A barrier over a focus alone (the finish's fresh barrier): when the focus takes in more elements,
// keep_weighting sets mu so that t stays where it was; with mu kept, t would sink far below the worst.
BOOST_AUTO_TEST_CASE(barrier_keeps_t_when_its_focus_grows) {
    const auto [small, large] = GrowingFocus();
    const pv::Reducer serial;
    pv::LogBarrier barrier;
    barrier.update(small, serial);
    const double t = barrier.t(), mu = barrier.mu(), gap = 0.2 - t;
    BOOST_TEST(gap > 0.0);
    pv::LogBarrier kept_mu(0.8, mu);
    kept_mu.update(large, serial);
    BOOST_TEST(0.2 - kept_mu.t() > 2.0 * gap);
    barrier.keep_weighting(large, serial);
    BOOST_TEST(barrier.mu() < 0.5 * mu);
    barrier.update(large, serial);
    BOOST_TEST(std::abs(barrier.t() - t) <= 1e-9 * gap);
}

// The wider focus takes in an element below t (outside the focus it was not a term, and the focus's
// own elements rose past it): t cannot stay, and keeps its gap below the new worst instead of
// the root at the old mu, which many more terms put far below.
BOOST_AUTO_TEST_CASE(barrier_keeps_its_gap_when_the_focus_brings_an_element_below_t) {
    auto [small, large] = GrowingFocus();
    const pv::Reducer serial;
    pv::LogBarrier barrier;
    barrier.update(small, serial);
    const double gap = 0.2 - barrier.t(), mu = barrier.mu();
    const double worst = barrier.t() - 0.5 * gap;  // below t
    large.push_back(worst);
    pv::LogBarrier kept_mu(0.8, mu);
    kept_mu.update(large, serial);
    BOOST_TEST(worst - kept_mu.t() > 2.0 * gap);  // the root at the old mu
    barrier.keep_weighting(large, serial);
    BOOST_TEST(barrier.t() < worst);
    BOOST_TEST(std::abs((worst - barrier.t()) - gap) <= 1e-12);
    BOOST_TEST(barrier.mu() < mu);
    barrier.update(large, serial);  // and the root at the new mu is that t
    BOOST_TEST(std::abs(barrier.t() - (worst - gap)) <= 1e-9 * gap);
}

BOOST_AUTO_TEST_SUITE_END()
