// Morphing (solvers/boundary_motion.hpp): a mesh whose boundary moved away from its reference
// coordinates, the interior left behind. The solvers follow a motion a valid mesh exists for, in
// steps where one run does not untangle; an impossible motion ends with the boundary where it was
// given, the fewest inverted elements found and a message that says so; no motion changes nothing.
#include <algorithm>
#include <boost/test/unit_test.hpp>
#include <cmath>
#include <numbers>
#include <vector>

#include "paloverde/assess/quality_assessor.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "paloverde/solvers/local_solver.hpp"
#include "paloverde/wrappers.hpp"
#include "support/ring_meshes.hpp"

namespace pv = paloverde;

namespace {

using pv::test::kSectors;
using pv::test::moved_ring;
using pv::test::ring;
using pv::test::turned_ring;

long inverted(const pv::Mesh& mesh) { return pv::QualityAssessor({"aspect_ratio"}).assess(mesh).inverted; }

// The fixed vertices are exactly where the motion put them.
void check_boundary_kept(const pv::Mesh& given, const pv::Mesh& result) {
    for (pv::VertexId v = 0; v < given.num_vertices(); ++v) {
        if (!given.fixed()[static_cast<std::size_t>(v)]) continue;
        for (int c = 0; c < 3; ++c) BOOST_TEST(result.coordinates()[3 * v + c] == given.coordinates()[3 * v + c]);
    }
}

// A motion followed by the global solver or the local smoother on these budgets (iterations, or
// sweeps), with every iteration's record (each run's numbered from its own start).
struct ObservedRun {
    pv::Summary summary;
    std::vector<pv::IterationRecord> records;
};
ObservedRun observed_run(pv::Mesh mesh, bool global, int untangle_budget, int shape_budget) {
    ObservedRun run;
    auto observe = [&](const pv::IterationRecord& r) { run.records.push_back(r); };
    auto solve = [&](auto options, auto solver_of) {
        options.untangle_termination.max_iterations = untangle_budget;
        options.termination.max_iterations = shape_budget;
        auto solver = solver_of(options);
        solver.set_observer(observe);
        run.summary = solver.improve(mesh);
    };
    if (global) solve(pv::GlobalSolverOptions{}, [](const pv::GlobalSolverOptions& o) { return pv::GlobalSolver(o); });
    else solve(pv::LocalSolverOptions{}, [](const pv::LocalSolverOptions& o) { return pv::LocalSolver(o); });
    return run;
}

}  // namespace

BOOST_AUTO_TEST_SUITE(morph)

BOOST_AUTO_TEST_CASE(a_turned_inner_circle_is_followed_by_the_global_and_the_local_solver) {
    const pv::Mesh given = turned_ring(120.0);
    BOOST_TEST_REQUIRE(inverted(given) > 0);
    pv::Mesh global_mesh = given;
    const pv::Summary global = pv::GlobalSolver().improve(global_mesh);
    BOOST_TEST_INFO(global.message);
    BOOST_TEST(global.valid());
    BOOST_TEST(inverted(global_mesh) == 0);
    check_boundary_kept(given, global_mesh);

    pv::LocalSolverOptions local_options;
    local_options.termination.max_iterations = 50;
    pv::Mesh local_mesh = given;
    const pv::Summary local = pv::LocalSolver(local_options).improve(local_mesh);
    BOOST_TEST_INFO(local.message);
    BOOST_TEST(local.valid());
    BOOST_TEST(inverted(local_mesh) == 0);
    check_boundary_kept(given, local_mesh);
}

BOOST_AUTO_TEST_CASE(the_first_run_of_a_motion_skips_the_newton_finish) {
    // Kept here (one run untangles the turn) after its shape phase stalled, where a run without
    // a motion goes on with Newton steps.
    pv::Mesh mesh = turned_ring(60.0);
    BOOST_TEST_REQUIRE(inverted(mesh) > 0);
    const pv::Summary s = pv::GlobalSolver().improve(mesh);
    BOOST_TEST_INFO(s.message);
    BOOST_TEST_REQUIRE(s.valid());
    BOOST_TEST_REQUIRE(s.message.find("step") == std::string::npos);  // the first run was kept
    BOOST_TEST((s.reason != pv::TerminationReason::IterationLimit));  // the shape phase stalled
    for (const auto& r : s.history) BOOST_TEST(r.phase.find("finish") == std::string::npos);
}

BOOST_AUTO_TEST_CASE(the_first_run_untangles_on_a_fifth_of_the_budget) {
    // A turn one run does not untangle in 50 iterations: the first run (whose records end where
    // the next run's numbering starts again) stops after 10, and the steps follow the motion.
    const pv::Mesh given = turned_ring(500.0);
    for (const bool global : {true, false}) {
        const auto [s, records] = observed_run(given, global, 50, 500);
        BOOST_TEST_INFO((global ? "global: " : "local: ") << s.message);
        BOOST_TEST(s.valid());
        BOOST_TEST(s.message.find("steps") != std::string::npos);
        std::size_t first_run = 1;
        while (first_run < records.size() && records[first_run].iteration > records[first_run - 1].iteration) ++first_run;
        BOOST_TEST_REQUIRE(first_run < records.size());
        BOOST_TEST(records[first_run - 1].iteration <= 10);
        BOOST_TEST(records[first_run - 1].phase.find("untangle") != std::string::npos);
    }
}

BOOST_AUTO_TEST_CASE(a_step_short_of_the_end_improves_on_a_fifth_of_the_budget) {
    // The same turn. Every run after the first (each one's records numbered from its own start)
    // but the last step improves for at most a fifth of the budget after it untangled, and no
    // fewer than 50 iterations (sweeps) where they are left: 80 of the global solver's 400, 50 of
    // the local smoother's 100; one of them uses its whole share (the smoother's steps would go on
    // for longer). After the global solver's last step comes its run with every vertex moving.
    const pv::Mesh given = turned_ring(500.0);
    for (const bool global : {true, false}) {
        const int share = global ? 80 : 50;
        const auto [s, records] = observed_run(given, global, 50, global ? 400 : 100);
        BOOST_TEST_INFO((global ? "global: " : "local: ") << s.message);
        BOOST_TEST_REQUIRE(s.valid());
        BOOST_TEST_REQUIRE(s.message.find("steps") != std::string::npos);
        // Per run: its last iteration less its untangling's.
        std::vector<int> improving{0};
        int untangled = 0;
        for (std::size_t i = 0; i < records.size(); ++i) {
            if (i > 0 && records[i].iteration < records[i - 1].iteration) improving.push_back(0), untangled = 0;
            if (records[i].phase.find("untangle") != std::string::npos) untangled = records[i].iteration;
            improving.back() = records[i].iteration - untangled;
        }
        const std::size_t after_steps = global ? 2 : 1;  // the last step, and the global solver's every-vertex run
        BOOST_TEST_REQUIRE(improving.size() >= 2 + after_steps);  // the first run, steps, then those
        int most = 0;
        for (std::size_t run = 1; run + after_steps < improving.size(); ++run) {
            BOOST_TEST(improving[run] <= share, "run " << run << ": " << improving[run]);
            most = std::max(most, improving[run]);
        }
        BOOST_TEST(most == share);
    }
}

BOOST_AUTO_TEST_CASE(a_followed_motion_ends_with_a_run_that_moves_every_vertex) {
    // The global solver's runs move the vertices near the worst elements (the records' `moved`:
    // the focus's free vertices); once the motion is followed, one more run from its mesh moves
    // every vertex (moved 0: no focus) and never ends lower. A turn that one run follows, and one
    // that takes steps. The local smoother, whose sweeps move every vertex already, adds no run.
    for (const double degrees : {60.0, 500.0}) {
        const auto [s, records] = observed_run(turned_ring(degrees), true, 50, 400);
        BOOST_TEST_INFO(degrees << " degrees: " << s.message);
        BOOST_TEST_REQUIRE(s.valid());
        BOOST_TEST(s.message.find("then, every vertex moving") != std::string::npos);
        std::size_t last_run = records.size() - 1;
        while (last_run > 0 && records[last_run].iteration > records[last_run - 1].iteration) --last_run;
        BOOST_TEST_REQUIRE(last_run > 0);
        bool focused_before = false, whole_after = true;
        for (std::size_t i = 0; i < records.size(); ++i) {
            if (records[i].phase != "shape") continue;
            if (i < last_run) focused_before = focused_before || records[i].moved > 0;
            else whole_after = whole_after && records[i].moved == 0;
        }
        BOOST_TEST(focused_before);
        BOOST_TEST(whole_after);
        BOOST_TEST(s.worst_after >= records[last_run - 1].best_worst_quality);
    }
    const auto [local, local_records] = observed_run(turned_ring(60.0), false, 50, 50);
    BOOST_TEST(local.message.find("every vertex moving") == std::string::npos);
}

// Slow (tests/CMakeLists.txt): the sanitizers see the job's queue made in config_test, and motions
// followed in the other cases here.
BOOST_AUTO_TEST_CASE(the_deforming_domain_job_rates_against_the_undeformed_mesh, *boost::unit_test::label("slow")) {
    const pv::Mesh given = turned_ring(120.0);
    pv::Mesh mesh = given;
    const pv::QueueResult result = pv::wrappers::deforming_domain().run(mesh);
    BOOST_TEST_INFO(result.message);
    BOOST_TEST(result.success);
    const auto& before = std::get<pv::QualityReport>(result.steps.front().outcome);
    const auto& after = std::get<pv::QualityReport>(result.steps.back().outcome);
    BOOST_TEST(before.inverted > 0);
    BOOST_TEST(after.inverted == 0);
    check_boundary_kept(given, mesh);
    BOOST_TEST(!mesh.has_targets());  // handed back as it came
    pv::Mesh plain = ring();
    BOOST_CHECK_THROW(pv::wrappers::deforming_domain().run(plain), pv::OptionError);
}

BOOST_AUTO_TEST_CASE(a_motion_one_run_cannot_untangle_is_followed_in_steps) {
    // Nearly a turn and a half, on an untangling budget of 5 iterations: one run from the interior
    // left behind does not untangle it, runs from the previous step do.
    const pv::Mesh given = turned_ring(500.0);
    pv::Mesh mesh = given;
    pv::GlobalSolverOptions options;
    options.untangle_termination.max_iterations = 5;
    const pv::Summary s = pv::GlobalSolver(options).improve(mesh);
    BOOST_TEST_INFO(s.message);
    BOOST_TEST(s.valid());
    BOOST_TEST(s.message.find("steps") != std::string::npos);
    BOOST_TEST(s.before.inverted == inverted(given));
    check_boundary_kept(given, mesh);
}

BOOST_AUTO_TEST_CASE(a_sliding_boundary_follows_the_motion_and_stays_on_the_moved_boundary) {
    // The boundary placed by the motion, then slid along the moved boundary's edges: every
    // boundary vertex stays on its circle's polygon (between the chords' midpoints and the circle).
    const pv::Mesh given = turned_ring(120.0);
    pv::Mesh mesh = given;
    pv::GlobalSolverOptions options;
    options.boundary = pv::GlobalSolverOptions::Boundary::Slide;
    const pv::Summary s = pv::GlobalSolver(options).improve(mesh);
    BOOST_TEST_INFO(s.message);
    BOOST_TEST(s.valid());
    BOOST_TEST(inverted(mesh) == 0);
    const double chord = std::cos(std::numbers::pi / kSectors);
    long moved = 0;
    for (pv::VertexId v = 0; v < mesh.num_vertices(); ++v) {
        if (!given.fixed()[static_cast<std::size_t>(v)]) continue;
        const double* p = &mesh.coordinates()[3 * static_cast<std::size_t>(v)];
        const double* q = &given.coordinates()[3 * static_cast<std::size_t>(v)];
        const double r = std::hypot(p[0], p[1]), circle = v < kSectors ? pv::test::kInner : pv::test::kOuter;
        BOOST_TEST(r >= circle * chord - 1e-12);
        BOOST_TEST(r <= circle + 1e-12);
        moved += p[0] != q[0] || p[1] != q[1];
    }
    BOOST_TEST(moved > 0);  // they did slide
}

BOOST_AUTO_TEST_CASE(the_time_limit_bounds_the_steps_together) {
    // The motion of the test above, on a time limit spent by the first run: no step starts, and
    // the first run's mesh comes back with the boundary where it was given.
    const pv::Mesh given = turned_ring(500.0);
    for (const bool global : {true, false}) {
        pv::Mesh mesh = given;
        pv::Summary s;
        if (global) {
            pv::GlobalSolverOptions options;
            options.untangle_termination.max_iterations = 5;
            options.termination.max_seconds = 1e-9;
            s = pv::GlobalSolver(options).improve(mesh);
        } else {
            pv::LocalSolverOptions options;
            options.untangle_termination.max_iterations = 1;
            options.termination.max_seconds = 1e-9;
            s = pv::LocalSolver(options).improve(mesh);
        }
        BOOST_TEST_INFO((global ? "global: " : "local: ") << s.message);
        BOOST_TEST((s.reason == pv::TerminationReason::TimeLimit));
        BOOST_TEST(s.message.find("time limit ran out") != std::string::npos);
        BOOST_TEST(s.after.inverted == inverted(mesh));
        check_boundary_kept(given, mesh);
    }
}

BOOST_AUTO_TEST_CASE(an_impossible_motion_keeps_the_given_boundary_and_says_it_needs_remeshing) {
    // The inner circle pushed through the outer one: no mesh of this boundary is valid.
    const pv::Mesh given = moved_ring([](double* p) { p[0] += 1.6; });
    pv::Mesh mesh = given;
    pv::GlobalSolverOptions options;
    options.untangle_termination.max_iterations = 50;
    options.termination.max_iterations = 20;
    options.smallest_motion_step = 1.0 / 8.0;
    const pv::Summary s = pv::GlobalSolver(options).improve(mesh);
    BOOST_TEST_INFO(s.message);
    BOOST_TEST(!s.valid());
    BOOST_TEST((s.reason == pv::TerminationReason::CannotUntangle));
    BOOST_TEST(s.message.find("remeshing") != std::string::npos);
    BOOST_TEST(s.after.inverted == inverted(mesh));
    BOOST_TEST(s.after.inverted <= s.before.inverted);
    check_boundary_kept(given, mesh);
}

BOOST_AUTO_TEST_CASE(reference_coordinates_where_the_boundary_is_change_nothing) {
    pv::Mesh plain = turned_ring(0.0);
    plain.clear_reference_coordinates();
    // The interior disturbed, the boundary where the reference has it: no motion to follow.
    auto xyz = plain.coordinates();
    for (std::size_t i = 3 * kSectors; i < xyz.size() - 3 * kSectors; i += 3) xyz[i] += 0.02 * std::sin(7.0 * i);
    pv::Mesh with_reference = plain;
    const pv::Mesh reference = ring();
    with_reference.set_reference_coordinates({reference.coordinates().begin(), reference.coordinates().end()});
    const pv::Summary a = pv::GlobalSolver().improve(plain);
    const pv::Summary b = pv::GlobalSolver().improve(with_reference);
    BOOST_TEST(a.iterations == b.iterations);
    for (std::size_t i = 0; i < xyz.size(); ++i) BOOST_TEST(plain.coordinates()[i] == with_reference.coordinates()[i]);
}

BOOST_AUTO_TEST_CASE(bad_reference_coordinates_and_steps_are_refused) {
    pv::Mesh mesh = ring();
    BOOST_CHECK_THROW(mesh.set_reference_coordinates(std::vector<double>(9, 0.0)), pv::MeshError);
    std::vector<double> xyz(mesh.coordinates().begin(), mesh.coordinates().end());
    xyz[4] = std::nan("");
    BOOST_CHECK_THROW(mesh.set_reference_coordinates(xyz), pv::MeshError);
    pv::GlobalSolverOptions global;
    global.smallest_motion_step = 0.0;
    BOOST_CHECK_THROW(pv::GlobalSolver{global}, pv::OptionError);
    pv::LocalSolverOptions local;
    local.smallest_motion_step = 1.5;
    BOOST_CHECK_THROW(pv::LocalSolver{local}, pv::OptionError);
}

BOOST_AUTO_TEST_SUITE_END()
