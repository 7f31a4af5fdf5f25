// The global log-barrier solver: never worse, never inverts a valid element, untangles what it
// can, scale-free, thread-count independent, and says why it stopped.
#include <boost/test/data/test_case.hpp>
#include <boost/test/unit_test.hpp>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "paloverde/assess/quality_assessor.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/orientation.hpp"
#include "paloverde/mesh/perturb.hpp"
#include "paloverde/metrics/targets.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "paloverde/solvers/local_solver.hpp"
#include "support/mesh_checks.hpp"
#include "support/solver_checks.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;
namespace bdata = boost::unit_test::data;
using paloverde::test::check_fixed_unchanged;
using paloverde::test::check_never_worse;
using paloverde::test::shared_mesh;

namespace {

// The first record of a phase in a run's history ("shape", "finish", "finish_fresh"; end() if none).
std::vector<pv::IterationRecord>::const_iterator first_in(const pv::Summary& summary, const std::string& phase) {
    return std::find_if(summary.history.begin(), summary.history.end(),
                        [&](const pv::IterationRecord& r) { return r.phase == phase; });
}

// The first record after the shape phase (end() if none).
std::vector<pv::IterationRecord>::const_iterator shape_end(const pv::Summary& summary) {
    return std::find_if(summary.history.begin(), summary.history.end(),
                        [](const pv::IterationRecord& r) { return r.phase != "shape"; });
}

// The local smoother's final worst quality on `input`.
double local_worst(pv::Mesh input) { return pv::LocalSolver().improve(input).worst_after; }

// The first record whose best worst quality reached the local smoother's final worst on `input`
// (end() if none).
std::vector<pv::IterationRecord>::const_iterator reaching_local(const pv::Summary& summary, const pv::Mesh& input) {
    const double local = local_worst(input);
    return std::find_if(summary.history.begin(), summary.history.end(),
                        [&](const pv::IterationRecord& r) { return r.best_worst_quality >= local - 1e-12; });
}

// The global solver with its default options, on one thread, on a shared mesh (the input is
// kept for the local smoother).
struct DefaultRun {
    pv::GlobalSolverOptions options;
    pv::Mesh input, mesh;
    pv::Summary summary;
    explicit DefaultRun(const std::string& name) : input(shared_mesh(name)), mesh(input) {
        options.threads = 1;
        summary = pv::GlobalSolver(options).improve(mesh);
    }
};

// The global solver with its default options but `polish` (and the budget `iterations`, if not
// 0), on one thread: the mesh and the summary.
std::pair<pv::Mesh, pv::Summary> with_polish(const pv::Mesh& input, pv::GlobalSolverOptions::Polish polish,
                                             int iterations = 0) {
    pv::GlobalSolverOptions options;
    options.threads = 1;
    options.polish = polish;
    if (iterations > 0) options.termination.max_iterations = iterations;
    pv::Mesh mesh = input;
    auto summary = pv::GlobalSolver(options).improve(mesh);
    return {std::move(mesh), std::move(summary)};
}

// What the steps of the records [first, last) gained, in units of their mu.
double gains_in_mu(std::vector<pv::IterationRecord>::const_iterator first, std::vector<pv::IterationRecord>::const_iterator last) {
    double gains = 0.0;
    for (; first != last; ++first) gains += first->gain / first->mu;
    return gains;
}

}  // namespace

BOOST_AUTO_TEST_SUITE(global_solver)

// A run works on the caller's mesh renumbered in place (its vertices for locality, its elements
// in the working order) and hands it back numbered as it was, with every field: moved, when the
// run ends; as it was to the bit, when the run throws.
BOOST_DATA_TEST_CASE(a_run_hands_the_mesh_back_numbered_as_it_was,
                     bdata::make({"mesquite/tets/tire.vtk", "mesquite/mixed/mixed-hex-pyr-tet.vtk"}) *
                         bdata::make({"aspect_ratio", "dihedral_sine"}),
                     name, metric) {
    pv::Mesh mesh = shared_mesh(name);
    if (mesh.has_cells() && std::string(metric) == "dihedral_sine") return;  // a tetrahedral metric
    std::vector<pv::GlobalId> ids(mesh.global_ids().size());
    for (std::size_t v = 0; v < ids.size(); ++v) ids[v] = static_cast<pv::GlobalId>(3 * v + 1);
    mesh.set_global_ids(ids);
    const pv::Mesh before = mesh;
    pv::GlobalSolverOptions options;
    options.shape_metric = metric;
    options.termination.max_iterations = 20;
    pv::GlobalSolver(options).improve(mesh);
    pv::test::check_same_mesh(mesh, before, false);
    BOOST_TEST(!std::equal(mesh.coordinates().begin(), mesh.coordinates().end(), before.coordinates().begin()));

    mesh = before;
    pv::GlobalSolver thrown(options);
    thrown.set_observer([](const pv::IterationRecord& r) {
        if (r.iteration == 5) throw std::runtime_error("an observer's own failure");
    });
    BOOST_CHECK_THROW(thrown.improve(mesh), std::runtime_error);
    pv::test::check_same_mesh(mesh, before);
}

BOOST_AUTO_TEST_CASE(untangles_the_mesquite_tangled_mesh) {
    auto mesh = shared_mesh("mesquite/tets/tet_4_tangled.vtk");
    const auto summary = pv::GlobalSolver().improve(mesh);
    BOOST_TEST_MESSAGE(summary.brief_report());
    BOOST_TEST(summary.before.inverted == 9);
    BOOST_TEST(summary.after.inverted == 0);
    BOOST_TEST(pv::count_orientations(mesh).inverted == 0);
    BOOST_TEST(summary.untangle_iterations > 0);
    BOOST_TEST(summary.success());
    check_never_worse(summary);
}

// Two regular tets, mirrored so both are inverted, sharing a free base: untangling has to flip the
// base, and the shape phase then has to bring its vertices back from wherever that left them.
// (Read as it is: with every element inverted, `auto` would take the file for the mirror convention.)
// The barrier ascent flips it back to regular tets. The regularized energy, symmetric about the
// base's plane, collapses the base and reopens it flipped but nearly flat, which the shape phase
// then raises only slowly: valid, not regular (docs/global_solver.md).
BOOST_AUTO_TEST_CASE(untangles_two_mirrored_tets_back_to_regular_ones) {
    for (auto untangling : {pv::GlobalSolverOptions::Untangling::Barrier, pv::GlobalSolverOptions::Untangling::Energy}) {
        auto mesh = shared_mesh("mesquite/tets/two_tets.vtk", pv::OrientationMode::AsIs);
        pv::GlobalSolverOptions options;
        options.untangling = untangling;
        const auto summary = pv::GlobalSolver(options).improve(mesh);
        BOOST_TEST_MESSAGE(summary.brief_report());
        BOOST_TEST(summary.before.inverted == 2);
        BOOST_TEST(summary.after.inverted == 0);
        BOOST_TEST(summary.worst_after > (untangling == pv::GlobalSolverOptions::Untangling::Barrier ? 0.99 : 0.0));
        check_never_worse(summary);
    }
}

// Interior vertices moved by up to one local edge length: tangled, yet untangleable.
BOOST_DATA_TEST_CASE(untangles_perturbed_shared_meshes,
                     bdata::make({"mesquite/tets/tire.vtk", "mesquite/tets/cube-clip-5.vtk", "stellar/house2.node",
                                  "mesquite/tris/tri_20258.vtk"}) *
                         bdata::make({1, 2, 3}),
                     name, seed) {
    auto mesh = pv::test::perturbed_shared_mesh(name, 0.3, seed);
    pv::GlobalSolverOptions options;
    options.termination.max_iterations = 30;
    const auto summary = pv::GlobalSolver(options).improve(mesh);
    BOOST_TEST_MESSAGE(name << " seed " << seed << ": " << summary.brief_report());
    BOOST_TEST(summary.after.inverted == 0);
    BOOST_TEST(pv::count_orientations(mesh).inverted == 0);
    check_never_worse(summary);
}

// The paper's tangling: a few boundary vertices moved, and the boundary then fixed. The barrier
// ascent frees all but an element or two within a few iterations and then inches up on those;
// the solver must see that and hand them to local untangling rather than creep through its
// budget. (Before it did: 220 and 253 iterations for seeds 1 and 2, and seed 3 still had an
// inverted element after 500.)
BOOST_DATA_TEST_CASE(hands_a_creeping_untangling_over_to_local_steps, bdata::make({1, 2, 3}), seed) {
    auto mesh = shared_mesh("mesquite/tets/cube-clip-5.vtk");
    pv::PerturbOptions perturb;
    perturb.interior = false;
    perturb.boundary = true;
    perturb.fraction = 0.05;
    perturb.amount = 0.3;
    perturb.seed = static_cast<std::uint64_t>(seed);
    pv::perturb(mesh, perturb);
    BOOST_TEST_REQUIRE(pv::count_orientations(mesh).inverted > 0);
    pv::GlobalSolverOptions options;
    options.improve_shape = false;
    auto energy_mesh = mesh;
    const auto energy = pv::GlobalSolver(options).improve(energy_mesh);
    BOOST_TEST_MESSAGE("seed " << seed << ", energy: " << energy.brief_report());
    BOOST_TEST(energy.after.inverted == 0);
    BOOST_TEST(energy.untangle_iterations < 100);
    check_never_worse(energy);
    // The barrier ascent alone: it stalls, and local rounds finish the job.
    options.untangling = pv::GlobalSolverOptions::Untangling::Barrier;
    const auto summary = pv::GlobalSolver(options).improve(mesh);
    BOOST_TEST_MESSAGE("seed " << seed << ": " << summary.brief_report());
    BOOST_TEST(summary.after.inverted == 0);
    BOOST_TEST(summary.untangle_iterations < 100);
    const bool local_round = std::any_of(summary.history.begin(), summary.history.end(),
                                         [](const pv::IterationRecord& r) { return r.phase == "untangle_local"; });
    BOOST_TEST(local_round);
    check_never_worse(summary);
}

BOOST_DATA_TEST_CASE(improves_valid_shared_meshes_without_making_anything_worse,
                     bdata::make({"mesquite/tets/tire.vtk", "mesquite/tets/flat-tet-sphere.vtk", "stellar/house2.node",
                                  "mesquite/tris/tri_20258.vtk"}),
                     name) {
    auto mesh = shared_mesh(name);
    const std::vector<double> before(mesh.coordinates().begin(), mesh.coordinates().end());
    const auto summary = pv::GlobalSolver().improve(mesh);
    BOOST_TEST_MESSAGE(name << ": " << summary.brief_report());
    BOOST_TEST(summary.before.inverted == 0);
    BOOST_TEST(summary.after.inverted == 0);
    BOOST_TEST(summary.worst_after > summary.worst_before);
    check_never_worse(summary);
    check_fixed_unchanged(mesh, before);
}

BOOST_AUTO_TEST_CASE(scaled_meshes_give_the_same_result) {
    // Every tolerance is relative, so a mesh scaled by 1e-4 or 1e4 follows the same path; only
    // rounding (cube roots, hypot) differs. Near 1e300 or 1e-300, where volumes would overflow or
    // underflow, the solvers work at unit scale (an exact power-of-two rescaling).
    const auto reference = shared_mesh("mesquite/tets/tet_4_tangled.vtk");
    pv::GlobalSolverOptions options;
    options.termination.max_iterations = 40;
    auto baseline = reference;
    const auto base_summary = pv::GlobalSolver(options).improve(baseline);
    for (double scale : {1e-4, 1e4, std::ldexp(1.0, -20), 1e300, 1e-300}) {
        auto mesh = reference;
        for (double& x : mesh.coordinates()) x *= scale;
        const auto summary = pv::GlobalSolver(options).improve(mesh);
        BOOST_TEST_CONTEXT("scale " << scale) {
            BOOST_TEST(summary.after.inverted == 0);
            BOOST_TEST(summary.untangle_iterations == base_summary.untangle_iterations);
            BOOST_TEST(summary.worst_after == base_summary.worst_after, boost::test_tools::tolerance(1e-6));
            double largest = 0.0;
            for (std::size_t i = 0; i < mesh.coordinates().size(); ++i)
                largest = std::max(largest, std::abs(mesh.coordinates()[i] / scale - baseline.coordinates()[i]));
            BOOST_TEST(largest < 1e-6);  // the mesh spans 10 units
        }
    }
}

// A heavy tangle (every interior vertex moved by up to 1.5 edge lengths), which the regularized
// energy untangles: the same at 1e-4 and 1e4 (its epsilon and reference volumes are scale-free).
BOOST_AUTO_TEST_CASE(heavy_tangles_untangle_alike_at_any_scale) {
    const auto reference = pv::test::perturbed_shared_mesh("mesquite/tets/tire.vtk", 1.0, 21, 1.5);
    pv::GlobalSolverOptions options;
    options.improve_shape = false;
    auto baseline = reference;
    const auto base_summary = pv::GlobalSolver(options).improve(baseline);
    BOOST_TEST_REQUIRE(base_summary.after.inverted == 0);
    for (double scale : {1e-4, 1e4}) {
        auto mesh = reference;
        for (double& x : mesh.coordinates()) x *= scale;
        const auto summary = pv::GlobalSolver(options).improve(mesh);
        BOOST_TEST_CONTEXT("scale " << scale << ": " << summary.brief_report()) {
            BOOST_TEST(summary.after.inverted == 0);
            BOOST_TEST(summary.untangle_iterations == base_summary.untangle_iterations);
            BOOST_TEST(summary.worst_after == base_summary.worst_after, boost::test_tools::tolerance(1e-6));
        }
    }
}

BOOST_AUTO_TEST_CASE(coordinates_near_1e300_or_1e_minus_300_are_assessed_and_smoothed_locally) {
    const auto reference = shared_mesh("mesquite/tets/tet_4_tangled.vtk");
    const auto unit = pv::QualityAssessor().assess(reference);
    for (double scale : {1e300, 1e-300}) {
        auto mesh = reference;
        for (double& x : mesh.coordinates()) x *= scale;
        const std::vector<double> input(mesh.coordinates().begin(), mesh.coordinates().end());
        const auto report = pv::QualityAssessor().assess(mesh);
        BOOST_TEST_CONTEXT("scale " << scale) {
            BOOST_TEST(report.inverted == 9);
            BOOST_TEST(report.metric("aspect_ratio")->all.min == unit.metric("aspect_ratio")->all.min,
                       boost::test_tools::tolerance(1e-9));
            const auto summary = pv::LocalSolver().improve(mesh);
            BOOST_TEST(summary.after.inverted == 0);
            BOOST_TEST(summary.worst_after > 0.3);
            check_fixed_unchanged(mesh, input);  // the rescaling is exact
        }
    }
}

BOOST_AUTO_TEST_CASE(result_does_not_depend_on_the_thread_count) {
    auto one = shared_mesh("mesquite/tets/cube-clip-5.vtk");
    pv::PerturbOptions perturb;
    perturb.amount = 0.7;
    pv::perturb(one, perturb);
    auto two = one;
    pv::GlobalSolverOptions options;
    options.termination.max_iterations = 25;
    options.threads = 1;
    const auto s1 = pv::GlobalSolver(options).improve(one);
    options.threads = 2;
    const auto s2 = pv::GlobalSolver(options).improve(two);
    BOOST_TEST(s1.iterations == s2.iterations);
    BOOST_TEST(std::equal(one.coordinates().begin(), one.coordinates().end(), two.coordinates().begin()));
}

// A focused shape phase works on the elements near the worst and the vertices around them: fewer
// vertices than the mesh's free ones, a new focus as the worst climbs, never a worse iterate,
// never an inverted element, and a result near the whole mesh's (the same barrier, minus terms
// that weigh almost nothing). Slow (tests/CMakeLists.txt): the sanitizers see a focused shape phase
// in checkpoint_test's global_focused_run_resumed_from_a_checkpoint_ends_as_the_uninterrupted_run.
BOOST_AUTO_TEST_CASE(a_focused_shape_phase_moves_the_vertices_near_the_worst_elements,
                     *boost::unit_test::label("slow")) {
    const auto input = shared_mesh("mesquite/tets/cube-clip-5.vtk");
    pv::GlobalSolverOptions options;
    options.termination.max_iterations = 120;
    options.focus_band = 1.0;
    auto whole = input;
    const auto unfocused = pv::GlobalSolver(options).improve(whole);
    options.focus_band = 0.1;
    auto focused_mesh = input;
    const auto focused = pv::GlobalSolver(options).improve(focused_mesh);
    pv::test::check_never_worse(focused);
    BOOST_TEST(focused.after.inverted == 0);
    std::vector<long> sizes;
    for (const auto& r : focused.history) {
        BOOST_TEST(r.moved > 0);
        BOOST_TEST(r.moved < static_cast<long>(input.num_free_vertices()));
        if (sizes.empty() || sizes.back() != r.moved) sizes.push_back(r.moved);
    }
    BOOST_TEST(sizes.size() >= 2u);  // focused anew at least once
    BOOST_TEST_MESSAGE("whole: " << unfocused.brief_report() << "\nfocused: " << focused.brief_report());
    BOOST_TEST(focused.worst_after >= 0.9 * unfocused.worst_after);
    for (const auto& r : unfocused.history) BOOST_TEST(r.moved == 0);
}

BOOST_AUTO_TEST_CASE(steepest_ascent_and_other_objectives_also_never_make_things_worse) {
    for (const char* objective : {"log_barrier", "p_mean", "min_quality"}) {
        auto mesh = shared_mesh("mesquite/tets/tire.vtk");
        pv::GlobalSolverOptions options;
        options.objective = objective;
        options.direction = pv::GlobalSolverOptions::Direction::SteepestAscent;
        options.termination.max_iterations = 30;
        const auto summary = pv::GlobalSolver(options).improve(mesh);
        BOOST_TEST_CONTEXT(objective << ": " << summary.brief_report()) {
            check_never_worse(summary);
            BOOST_TEST(summary.worst_after >= summary.worst_before);
        }
    }
}

// Truncated Newton directions in the shape phase: never a worse worst element, never an inverted
// one, the same mesh on one thread as on two. Slow (tests/CMakeLists.txt): the sanitizers see
// Newton directions in distributed_test's newton_directions_give_the_serial_answer, and Newton
// steps in the Newton finish.
BOOST_TEST_DECORATOR(*boost::unit_test::label("slow"))
BOOST_DATA_TEST_CASE(newton_directions_never_make_things_worse,
                     bdata::make({"mesquite/tets/tire.vtk", "mesquite/tets/cube-clip-5.vtk", "stellar/house2.node",
                                  "mesquite/tris/tri_20258.vtk"}),
                     name) {
    auto mesh = shared_mesh(name);
    const std::vector<double> before(mesh.coordinates().begin(), mesh.coordinates().end());
    auto again = mesh;
    pv::GlobalSolverOptions options;
    options.direction = pv::GlobalSolverOptions::Direction::Newton;
    options.termination.max_iterations = 25;
    options.threads = 1;
    const auto summary = pv::GlobalSolver(options).improve(mesh);
    BOOST_TEST_MESSAGE(name << ": " << summary.brief_report());
    BOOST_TEST(summary.after.inverted == 0);
    BOOST_TEST(summary.worst_after > summary.worst_before);
    check_never_worse(summary);
    check_fixed_unchanged(mesh, before);
    options.threads = 2;
    const auto twice = pv::GlobalSolver(options).improve(again);
    BOOST_TEST(twice.iterations == summary.iterations);
    BOOST_TEST(std::equal(mesh.coordinates().begin(), mesh.coordinates().end(), again.coordinates().begin()));
}

// The Newton finish (the default) goes on where conjugate gradients stall: from their best
// iterate, never lower, never an inverted element, and on tire and house2 higher than where they
// stopped and than without the finish (tire: 0.22104 against 0.22086, and the local smoother's
// 0.22101).
BOOST_DATA_TEST_CASE(the_newton_finish_raises_the_worst_element_where_conjugate_gradients_stall,
                     bdata::make({"mesquite/tets/tire.vtk", "stellar/house2.node"}), name) {
    auto mesh = shared_mesh(name), without = mesh;
    const std::vector<double> before(mesh.coordinates().begin(), mesh.coordinates().end());
    pv::GlobalSolverOptions options;
    options.threads = 1;
    const auto finished = pv::GlobalSolver(options).improve(mesh);
    options.finish = pv::GlobalSolverOptions::Finish::None;
    const auto stalled = pv::GlobalSolver(options).improve(without);
    BOOST_TEST_MESSAGE(name << ": " << stalled.brief_report() << "; with the finish " << finished.brief_report());
    const auto first = first_in(finished, "finish");
    BOOST_TEST_REQUIRE((first != finished.history.end()));
    // The finish starts from the conjugate gradients' best iterate and ends above it, and above
    // the run without it (whose conjugate gradients widen their focus where they stall instead).
    const auto shape_best = std::prev(first)->best_worst_quality;
    BOOST_TEST(first->best_worst_quality == shape_best);
    BOOST_TEST(finished.worst_after > shape_best);
    BOOST_TEST(finished.worst_after > stalled.worst_after);
    BOOST_TEST(finished.after.inverted == 0);
    check_never_worse(finished);
    check_fixed_unchanged(mesh, before);
}

// The finish first goes on with the conjugate gradients' own barrier (the same mu). On
// cube-clip-5 without the damped-vertex ascent its Newton steps cannot solve that barrier's
// subproblem: after the cap of 50 steps at one mu a fresh barrier (a larger mu) takes over from
// the best iterate. On tire they solve it and raise the worst element, and no fresh barrier
// follows. (Both with the default budget of 500 iterations; the shape phases hand over at 325 and
// 137. With the ascent, cube-clip-5's hands over at 114, from where the first part converges.)
BOOST_DATA_TEST_CASE(the_newton_finish_goes_on_with_the_shape_phases_barrier_and_recenters_out_of_reach,
                     bdata::make({"mesquite/tets/cube-clip-5.vtk", "mesquite/tets/tire.vtk"}), name) {
    auto mesh = shared_mesh(name);
    pv::GlobalSolverOptions options;
    options.threads = 1;
    options.damped_vertex_ascent = std::string(name) == "mesquite/tets/tire.vtk";
    const auto summary = pv::GlobalSolver(options).improve(mesh);
    const auto& h = summary.history;
    const auto finish = first_in(summary, "finish"), fresh = first_in(summary, "finish_fresh");
    BOOST_TEST_REQUIRE((finish != h.end()));
    BOOST_TEST(finish->mu == std::prev(finish)->mu);
    BOOST_TEST(finish->best_worst_quality == std::prev(finish)->best_worst_quality);
    BOOST_TEST(summary.worst_after > finish->best_worst_quality);
    check_never_worse(summary);
    if (std::string(name) == "mesquite/tets/cube-clip-5.vtk") {
        BOOST_TEST_REQUIRE((fresh != h.end()));
        BOOST_TEST((fresh - finish) == 51);  // its first record, then 50 steps
        BOOST_TEST(std::all_of(finish, fresh, [&](const pv::IterationRecord& r) { return r.mu == finish->mu; }));
        BOOST_TEST(fresh->mu > finish->mu);
        BOOST_TEST(fresh->best_worst_quality == std::prev(fresh)->best_worst_quality);
        BOOST_TEST(summary.worst_after > fresh->best_worst_quality);
    } else {
        BOOST_TEST((fresh == h.end()));
    }
}

// A vertex the line search damped so that nothing blocks is damped further while its own
// elements' barrier terms would fall (damped_vertex_ascent, the default): the long steps that pay
// for the bulk of the barrier no longer take the worst elements' neighbourhoods down with them.
// On cube-clip-5 the best worst quality after 100 iterations is 0.2319 against 0.1166 and the shape
// phase hands over far sooner (iteration 114 on 0.2320 against 325 on 0.2283); the Newton finish
// then carries both runs to within 1e-4 of each other (0.2337638 against 0.2338321), so the end is
// only required not to be lower by more than that. Slow (tests/CMakeLists.txt): the sanitizers see
// runs with the ascent and without it in the test before this one.
BOOST_AUTO_TEST_CASE(damped_vertices_whose_own_elements_would_fall_are_damped_again, *boost::unit_test::label("slow")) {
    auto mesh = shared_mesh("mesquite/tets/cube-clip-5.vtk"), without = mesh;
    const std::vector<double> before(mesh.coordinates().begin(), mesh.coordinates().end());
    pv::GlobalSolverOptions options;
    options.threads = 1;
    const auto ascending = pv::GlobalSolver(options).improve(mesh);
    options.damped_vertex_ascent = false;
    const auto plain = pv::GlobalSolver(options).improve(without);
    BOOST_TEST_MESSAGE("cube-clip-5: " << ascending.brief_report() << "; without " << plain.brief_report());
    BOOST_TEST_REQUIRE(ascending.history.size() > 100);
    BOOST_TEST_REQUIRE(plain.history.size() > 100);
    BOOST_TEST(ascending.history[100].best_worst_quality > plain.history[100].best_worst_quality);
    BOOST_TEST_REQUIRE((shape_end(ascending) != ascending.history.end()));
    BOOST_TEST_REQUIRE((shape_end(plain) != plain.history.end()));
    BOOST_TEST(shape_end(ascending)->iteration + 100 < shape_end(plain)->iteration);
    BOOST_TEST(ascending.worst_after > plain.worst_after - 1e-4);
    BOOST_TEST(ascending.after.inverted == 0);
    check_never_worse(ascending);
    check_never_worse(plain);
    check_fixed_unchanged(mesh, before);
}

// Conjugate gradients that creep hand over to the Newton finish before they stall: on tire the
// shape phase ends while its worst quality still rises by more than min_progress per window (the
// stall test would go on for about 160 iterations more), and the run ends at or above the local
// smoother's worst, reached about 230 iterations sooner than when the phase waited for its stall.
// Where the steps gain less than a mu each (the barrier's subproblems solved at every step) while
// the worst element creeps, the phase hands over at ten times the pace of the 100 times
// min_progress rule: on tire at iteration 137, where the worst still rose by 1.7e-4 over the last
// three windows (before the let-go rule of kLeastWorstWeight: at 140, and the 100 rule alone went
// on to 179).
BOOST_AUTO_TEST_CASE(a_creeping_shape_phase_hands_over_before_it_stalls) {
    const DefaultRun run("mesquite/tets/tire.vtk");
    const auto& summary = run.summary;
    const pv::TerminationCriterion& limits = run.options.termination;
    const auto& h = summary.history;
    const auto finish = shape_end(summary);
    const auto window = static_cast<std::ptrdiff_t>(limits.progress_window);
    BOOST_TEST_REQUIRE((finish - h.begin()) > 3 * window + 1);
    BOOST_TEST_REQUIRE(finish->phase == "finish");
    const auto last = std::prev(finish);
    auto rise_over = [&](std::ptrdiff_t n) { return last->best_worst_quality - std::prev(last, n)->best_worst_quality; };
    const double min_progress = limits.min_progress;
    BOOST_TEST_MESSAGE("tire: handover at " << finish->iteration << ", the worst rose " << rise_over(3 * window)
                                            << " over three windows");
    BOOST_TEST(rise_over(window) > min_progress * last->best_worst_quality);  // not a stall
    BOOST_TEST(rise_over(3 * window) > 100.0 * min_progress * last->best_worst_quality);  // a calm creep
    BOOST_TEST(gains_in_mu(std::prev(last, 3 * window - 1), finish) < static_cast<double>(3 * window));
    BOOST_TEST(summary.worst_after >= local_worst(run.input));
    check_never_worse(summary);
}

// Where mu is so large that t sits far below the worst element, the barrier weighs the many
// elements near t like the worst and its steps trade the worst ones for them: after a progress
// window of steps in which the worst element held under 1% of the weight (mu / (worst - t)), mu
// shrinks (docs/global_solver.md, "A barrier that let its worst element go"). On cub_wedge_like
// one mu used to hold for 60 iterations, 36 of them in a row with the worst under 1%; the phase's
// first mu only where the worst also rose away from t (the automatic start weighs many elements
// alike on purpose; the next test). Slow (tests/CMakeLists.txt): the sanitizers see the default run
// and its rules in a_creeping_shape_phase_hands_over_before_it_stalls (tire).
BOOST_AUTO_TEST_CASE(mu_shrinks_where_the_barrier_let_its_worst_element_go, *boost::unit_test::label("slow")) {
    const DefaultRun run("mesquite/tets/cub_wedge_like.vtk");
    const auto& summary = run.summary;
    const pv::TerminationCriterion& limits = run.options.termination;
    const auto& h = summary.history;
    const int window = limits.progress_window;
    int longest = 0, streak = 0, stages = 0;
    for (std::size_t i = 1; i < h.size() && h[i].phase == "shape"; ++i) {
        if (h[i].mu != h[i - 1].mu) {
            ++stages;
            streak = 0;
        }
        // The record after a step holds the weight the next step is judged on.
        const bool let_go = h[i].mu / (h[i].worst_quality - h[i].t) < 0.01;
        streak = let_go ? streak + 1 : 0;
        if (stages > 0) longest = std::max(longest, streak);
    }
    BOOST_TEST_MESSAGE("cub_wedge_like: " << stages << " smaller mus, at most " << longest
                                          << " steps in a row with the worst element under 1%");
    BOOST_TEST(stages > 3);
    BOOST_TEST(longest <= window);
    BOOST_TEST(summary.worst_after >= local_worst(run.input));
    check_never_worse(summary);
}

// The phase's first mu is spared that rule while the automatic start's weighting holds, but not
// once the worst element rose away from a t that stayed: on cube-clip-5 the worst's gap above t
// grows from 0.030 to 0.074 over the first ten steps (its weight from 1/700 to 1/1,800), and the
// first mu now ends at step 10 instead of 17; the local smoother's worst comes at iteration 42
// instead of 59.
BOOST_AUTO_TEST_CASE(the_first_mu_shrinks_once_the_worst_rose_away_from_t) {
    const DefaultRun run("mesquite/tets/cube-clip-5.vtk");
    const auto& summary = run.summary;
    const pv::TerminationCriterion& limits = run.options.termination;
    const auto& h = summary.history;
    const int window = limits.progress_window;
    const auto first_other = std::find_if(h.begin(), h.end(), [&](const pv::IterationRecord& r) { return r.mu != h.front().mu; });
    BOOST_TEST_REQUIRE((first_other != h.end()));
    BOOST_TEST(first_other->iteration <= window);
    const double first_gap = h.front().worst_quality - h.front().t;
    for (auto r = std::next(h.begin()); r != first_other; ++r) {
        BOOST_TEST(r->worst_quality - r->t > first_gap);
        BOOST_TEST(r->mu / (r->worst_quality - r->t) < 0.01);
    }
    const auto reached = reaching_local(summary, run.input);
    BOOST_TEST_REQUIRE((reached != h.end()));
    BOOST_TEST_MESSAGE("cube-clip-5: the first mu ends at " << first_other->iteration << ", the local smoother's worst at "
                                                            << reached->iteration);
    BOOST_TEST(reached->iteration < 50);
    check_never_worse(summary);
}

// Where the steps gain a few mu each while the worst quality stands still, conjugate gradients
// hand over after a single progress window (kQuickHandoverProgress, kQuickGain): on cub_wedge_like
// one mu held from iteration 55 to 89, the worst within 2e-5 from 75 on; the shape phase now
// hands over at 87 instead of 113, and the local smoother's worst comes at 94 instead of 120.
// Slow (tests/CMakeLists.txt): as mu_shrinks_where_the_barrier_let_its_worst_element_go.
BOOST_AUTO_TEST_CASE(a_shape_phase_whose_steps_gain_little_hands_over_after_one_window,
                     *boost::unit_test::label("slow")) {
    const DefaultRun run("mesquite/tets/cub_wedge_like.vtk");
    const auto& summary = run.summary;
    const pv::TerminationCriterion& limits = run.options.termination;
    const auto& h = summary.history;
    const auto finish = shape_end(summary);
    const auto window = static_cast<std::ptrdiff_t>(limits.progress_window);
    BOOST_TEST_REQUIRE((finish != h.end()));
    BOOST_TEST_REQUIRE((finish - h.begin()) > window + 1);
    const auto last = std::prev(finish);
    BOOST_TEST_MESSAGE("cub_wedge_like: handover at " << finish->iteration);
    BOOST_TEST(finish->iteration < 100);
    const auto before = std::prev(last, window);
    BOOST_TEST(before->mu == last->mu);  // no smaller mu in the window: the three-window rules wait for one
    BOOST_TEST(last->best_worst_quality - before->best_worst_quality <
               30.0 * limits.min_progress * last->best_worst_quality);
    BOOST_TEST(gains_in_mu(std::next(before), finish) < 10.0 * static_cast<double>(window));
    const auto reached = reaching_local(summary, run.input);
    BOOST_TEST_REQUIRE((reached != h.end()));
    BOOST_TEST(reached->iteration < 105);
    BOOST_TEST(summary.worst_after >= reached->best_worst_quality);
    check_never_worse(summary);
}

// finish_band 1/3 (the default): the finish works on the few worst elements. Where the conjugate gradients
// stalled the qualities have piled up above the worst, and the whole band holds far more vertices
// (tire: 98, against the shape phase's last 142; with a third of it 53; fandisk-9M: 135,957
// against 53, its Newton steps 1.5 s against under a millisecond). The result is no worse.
BOOST_AUTO_TEST_CASE(finish_band_focuses_the_finish_on_a_fraction_of_the_band) {
    auto mesh = shared_mesh("mesquite/tets/tire.vtk"), local = mesh;
    pv::GlobalSolverOptions options;
    options.threads = 1;
    options.finish_band = 1.0 / 3.0;
    const auto summary = pv::GlobalSolver(options).improve(mesh);
    const auto finish = shape_end(summary);
    BOOST_TEST_REQUIRE((finish != summary.history.begin() && finish != summary.history.end()));
    const long shape_focus = std::prev(finish)->moved;
    BOOST_TEST_MESSAGE("tire: the shape phase's last focus " << shape_focus << " vertices, the finish's " << finish->moved);
    BOOST_TEST(finish->moved > 0);
    BOOST_TEST(2 * finish->moved < shape_focus);
    BOOST_TEST(summary.worst_after >= pv::LocalSolver().improve(local).worst_after);
    check_never_worse(summary);
}

// With fewer than twice the 50 steps left in the budget when the conjugate gradients hand over
// (tire: at iteration 137, as the same run with the whole budget tells), the fresh barrier goes
// first and alone.
BOOST_AUTO_TEST_CASE(near_the_budgets_end_the_finish_starts_on_a_fresh_barrier) {
    auto mesh = shared_mesh("mesquite/tets/tire.vtk"), budgeted = mesh;
    pv::GlobalSolverOptions options;
    options.threads = 1;
    const auto whole = pv::GlobalSolver(options).improve(mesh);
    const auto handover = shape_end(whole);
    BOOST_TEST_REQUIRE((handover != whole.history.end()));
    BOOST_TEST_REQUIRE(handover->phase == "finish");
    options.termination.max_iterations = handover->iteration + 2 * 50 - 1;
    const auto summary = pv::GlobalSolver(options).improve(budgeted);
    const auto& h = summary.history;
    const auto fresh = shape_end(summary);
    BOOST_TEST_REQUIRE((fresh != h.end()));
    BOOST_TEST(fresh->phase == "finish_fresh");
    BOOST_TEST(fresh->iteration == handover->iteration);
    BOOST_TEST((first_in(summary, "finish") == h.end()));
    BOOST_TEST(summary.worst_after > fresh->best_worst_quality);
    check_never_worse(summary);
}

// A shape phase that stalls without ever beating its start runs once more, from its best iterate,
// on a barrier whose t starts just under the worst element. On the mixed mesh, right after
// untangling, the worst element (0.0044) lies far under the rest of the band the shape phase's
// barrier starts under; its steps trade it away (to 2e-6) and stall. The second run starts with t
// tens of times closer to it, and the run ends above where the shape phase began.
BOOST_AUTO_TEST_CASE(a_shape_phase_stalled_below_its_start_runs_again_with_t_close_under_the_worst) {
    auto mesh = shared_mesh("mesquite/mixed/mixed-hex-pyr-tet.vtk");
    pv::set_targets(mesh, pv::TargetOptions::from("aspect"));  // as the command line's keep: auto
    pv::GlobalSolverOptions options;
    options.threads = 1;
    options.termination.max_iterations = 100;
    const auto summary = pv::GlobalSolver(options).improve(mesh);
    const auto& h = summary.history;
    const auto shape = first_in(summary, "shape"), again = first_in(summary, "shape_close_start");
    BOOST_TEST_REQUIRE((shape != h.end()));
    BOOST_TEST_REQUIRE((again != h.end()));
    BOOST_TEST(std::prev(again)->phase == "shape");  // right after the shape phase
    for (auto r = shape; r != again; ++r) BOOST_TEST(r->best_worst_quality == shape->worst_quality);
    BOOST_TEST(std::prev(again)->worst_quality < 0.01 * shape->worst_quality);  // traded away
    BOOST_TEST(again->worst_quality == shape->worst_quality);                   // from the best iterate
    const double shape_gap = shape->worst_quality - shape->t, close_gap = again->worst_quality - again->t;
    BOOST_TEST(close_gap > 0.0);
    BOOST_TEST(close_gap < shape_gap / 10.0);
    BOOST_TEST(std::count_if(h.begin(), h.end(), [](const pv::IterationRecord& r) { return r.phase == "shape_close_start"; }) > 1);
    BOOST_TEST(summary.worst_after > shape->worst_quality);
    check_never_worse(summary);
}

// Once the finish's worst element stands (it rose by less than the progress tolerance over a
// window) with t within that tolerance under it, the finish ends: what is left of t's rise cannot
// lift the worst by a tolerance's worth, and each further Newton step costs many gradient passes.
// The least tolerance is min_progress times the worst (one gradient pass an iteration); waiting
// for t, the finish of tri_5_xz took four more iterations after that.
BOOST_AUTO_TEST_CASE(the_finish_ends_once_its_worst_stands_with_t_just_under_it) {
    const DefaultRun run("mesquite/tris/tri_5_xz.vtk");
    const auto& h = run.summary.history;
    auto in_finish = [](const pv::IterationRecord& r) { return r.phase.starts_with("finish"); };
    const auto finish = std::find_if(h.begin(), h.end(), in_finish);
    const auto after = std::find_if_not(finish, h.end(), in_finish);  // the polish's, if any
    BOOST_TEST_REQUIRE((after - finish) > 10);
    BOOST_TEST((run.summary.reason == pv::TerminationReason::Converged));
    const auto window = static_cast<std::ptrdiff_t>(run.options.termination.progress_window);
    for (auto r = finish + window; r < after; ++r) {
        if (r->phase != (r - window)->phase) continue;  // a window within one part of the finish
        const double tolerance = run.options.termination.min_progress * std::abs(r->best_worst_quality);
        const bool stands = r->best_worst_quality - (r - window)->best_worst_quality <= tolerance;
        if (stands && r->best_worst_quality - r->t <= tolerance) {
            BOOST_TEST((after - r) <= 1, "the finish went on " << (after - r - 1) << " iterations from " << r->iteration);
            break;
        }
    }
    check_never_worse(run.summary);
}

// Where the finish's worst element rises far above the barrier's t (four times the gap it began
// with), t no longer weighs the worst elements and a fresh barrier starts from the best iterate.
// On fandisk-9M with barrier_shrink 0.88 this lifts the result from 0.18682 to 0.19100; here
// tire's shape phase is ended early (min_progress 0.1), its finish climbs from 0.1687 faster than
// its fixed mu lets t follow, and hands over to a fresh barrier at iteration 35, before its 50
// steps (without the rule the first part stalls at 40 on 0.2008; with it the run ends on 0.2188).
BOOST_AUTO_TEST_CASE(the_finish_starts_a_fresh_barrier_where_the_worst_rose_far_above_t) {
    auto mesh = shared_mesh("mesquite/tets/tire.vtk");
    pv::GlobalSolverOptions options;
    options.threads = 1;
    options.termination.min_progress = 0.1;
    const auto summary = pv::GlobalSolver(options).improve(mesh);
    BOOST_TEST_MESSAGE("tire, min_progress 0.1: " << summary.brief_report());
    const auto& h = summary.history;
    const auto finish = first_in(summary, "finish"), fresh = first_in(summary, "finish_fresh");
    BOOST_TEST_REQUIRE((finish != h.end()));
    BOOST_TEST_REQUIRE((fresh != h.end()));
    BOOST_TEST((fresh - finish) < 51);  // before the first part's 50 steps at one mu
    const auto last = std::prev(fresh);
    BOOST_TEST(last->best_worst_quality - last->t > 4.0 * (finish->best_worst_quality - finish->t));
    BOOST_TEST(summary.worst_after > last->best_worst_quality);
    BOOST_TEST(summary.after.inverted == 0);
    check_never_worse(summary);
}

// The finish's fresh barrier weighs its focus alone (docs/global_solver.md, "The fresh barrier
// weighs its focus alone"): its mu comes from the focus's terms, and a refocus keeps its t. With
// the still elements' terms too, mu times the element count would stay below 1 - t (no term is less
// than 1 / (1 - t)): tire's fresh barrier (min_progress 0.1, as above) starts at 5.9 against 0.83.
// Where Newton steps lifted the focus past a still element (the whole mesh's worst below t: here
// at the refocuses of iterations 15, 16 and 17), the refocus that takes it in cannot keep t;
// keep_weighting then keeps t's gap below that element (objective_gradient_test), and one step later t
// stands within 0.01 of it. Without keep_weighting the first refocus (44 to 92 vertices, before the
// one-window handover) dropped t by 0.19, and the run ended on 0.190 instead of 0.219.
BOOST_AUTO_TEST_CASE(the_fresh_barrier_weighs_its_focus_alone_and_keeps_t_on_a_refocus) {
    auto mesh = shared_mesh("mesquite/tets/tire.vtk");
    const auto elements = static_cast<double>(mesh.num_elements());
    pv::GlobalSolverOptions options;
    options.threads = 1;
    options.termination.min_progress = 0.1;
    const auto summary = pv::GlobalSolver(options).improve(mesh);
    const auto& h = summary.history;
    const auto fresh = first_in(summary, "finish_fresh");
    BOOST_TEST_REQUIRE((fresh != h.end()));
    BOOST_TEST(fresh->mu * elements > 1.0 - fresh->t);
    int wider = 0;
    // Within one fresh barrier: a new one starts on the iteration the last one ended.
    for (auto r = fresh; std::next(r) != h.end() && std::next(r)->phase == "finish_fresh"; ++r) {
        const auto next = std::next(r);
        if (next->iteration != r->iteration && next->moved > r->moved) {
            ++wider;
            if (r->worst_quality > r->t) BOOST_TEST(next->t >= r->t);
            else BOOST_TEST(next->t > r->worst_quality - 0.01);  // a gap of at most 0.01 below it, then one step
        }
    }
    BOOST_TEST(wider > 0);
    BOOST_TEST(summary.worst_after > 0.219);
    check_never_worse(summary);
}

// Near its end the finish's Newton steps solve each barrier subproblem with their first step.
// After k such subproblems in a row mu shrinks k times, so the finish follows the central path
// ever faster instead of linearly. On flat-tet-sphere, with no progress too small to count
// (min_progress 0; by default the finish ends 1e-12 short, once t is that close under the worst),
// it reaches the max-min point the local smoother finds (0.18552040067497, to the last bits).
BOOST_AUTO_TEST_CASE(the_finish_shrinks_mu_faster_while_newton_solves_each_subproblem_at_once) {
    auto mesh = shared_mesh("mesquite/tets/flat-tet-sphere.vtk"), local = mesh;
    pv::GlobalSolverOptions options;
    options.threads = 1;
    options.termination.min_progress = 0.0;
    const auto summary = pv::GlobalSolver(options).improve(mesh);
    const auto smoothed = pv::LocalSolver().improve(local);
    BOOST_TEST_MESSAGE("flat-tet-sphere: " << summary.brief_report() << "; local " << smoothed.brief_report());
    BOOST_TEST(summary.worst_after > smoothed.worst_after - 1e-15);
    const auto& h = summary.history;
    const double shrink = options.objective_options.barrier_shrink;
    bool faster = false;
    for (std::size_t i = 1; i < h.size(); ++i)
        faster = faster || (h[i].phase != "shape" && h[i].phase == h[i - 1].phase && h[i].mu < 0.99 * shrink * h[i - 1].mu);
    BOOST_TEST(faster);
    check_never_worse(summary);
}

// The mean's polish (auto, the default): on TetWild's armadillo the shape phases raise the worst
// quality from 0.226 to 0.348 and leave the mean quality below the input's (0.750404 against
// 0.750479); the polish brings it back above, and every element within its band of the worst
// keeps its quality bit for bit, so the worst quality is that of the run without it.
BOOST_AUTO_TEST_CASE(the_polish_brings_the_mean_back_above_the_inputs_with_the_worst_held) {
    const auto input = shared_mesh("tetwild/armadillo.mesh");
    const auto [polished, summary] = with_polish(input, pv::GlobalSolverOptions::Polish::Auto);
    const auto [unpolished, without] = with_polish(input, pv::GlobalSolverOptions::Polish::Off);
    check_never_worse(summary);
    auto mean = [](const pv::QualityReport& report) { return report.metric("aspect_ratio")->all.mean; };
    BOOST_TEST_MESSAGE(summary.brief_report() << "\n" << summary.message);
    BOOST_TEST(mean(without.after) < mean(without.before));  // what the polish is for
    BOOST_TEST(mean(summary.after) > mean(summary.before));
    BOOST_TEST(summary.worst_after == without.worst_after);
    BOOST_TEST(summary.worst_after > 1.5 * summary.worst_before);
    const auto polish = first_in(summary, "polish");
    BOOST_TEST_REQUIRE((polish != summary.history.end()));
    BOOST_TEST(std::count_if(polish, summary.history.end(), [](const auto& r) { return r.phase == "polish"; }) ==
               summary.history.end() - polish);  // the last phase
    BOOST_TEST(summary.message.find("mean quality rose from") != std::string::npos);
    // Up to the polish the two runs are the same run.
    BOOST_TEST_REQUIRE(static_cast<std::size_t>(polish - summary.history.begin()) <= without.history.size());
    for (auto r = summary.history.begin(), w = without.history.begin(); r != polish; ++r, ++w)
        BOOST_TEST((r->phase == w->phase && r->worst_quality == w->worst_quality && r->mean_quality == w->mean_quality));
    // The band's elements stand still: their qualities, bit for bit.
    const auto metric = pv::make_metric("aspect_ratio");
    const double top = without.worst_after + 0.03 * (1.0 - without.worst_after);
    long held = 0, moved = 0;
    for (pv::ElementId e = 0; e < input.num_elements(); ++e) {
        const double before = metric->element_value(unpolished, unpolished.coordinates(), e);
        const double after = metric->element_value(polished, polished.coordinates(), e);
        if (before <= top) {
            ++held;
            BOOST_TEST(after == before, "element " << e);
        } else {
            moved += after != before;
            BOOST_TEST(after > top, "element " << e);
        }
    }
    BOOST_TEST(held > 0);
    BOOST_TEST(moved > 1000);
}

// polish always: the polish runs after shape phases that raised the mean already, raises it
// further while the worst element stands still, and ends when the mean stops rising (on tire after
// 535 iterations in all: a budget of 1,000). Slow (tests/CMakeLists.txt): the sanitizers see the
// polish in checkpoint_test's global_run_resumed_in_its_polish_ends_as_the_uninterrupted_run.
BOOST_AUTO_TEST_CASE(polish_always_raises_the_mean_until_it_stalls, *boost::unit_test::label("slow")) {
    const auto input = shared_mesh("mesquite/tets/tire.vtk");
    const auto without = with_polish(input, pv::GlobalSolverOptions::Polish::Auto, 1000).second;
    BOOST_TEST((first_in(without, "polish") == without.history.end()));  // auto: the mean rose already
    const auto summary = with_polish(input, pv::GlobalSolverOptions::Polish::Always, 1000).second;
    check_never_worse(summary);
    BOOST_TEST(summary.worst_after == without.worst_after);
    const auto polish = first_in(summary, "polish");
    BOOST_TEST_REQUIRE((polish != summary.history.end()));
    BOOST_TEST((summary.history.end() - polish > 20));
    for (auto r = polish; r != summary.history.end(); ++r) BOOST_TEST(r->worst_quality == polish->worst_quality);
    auto mean = [](const pv::Summary& s) { return s.after.metric("aspect_ratio")->all.mean; };
    BOOST_TEST(mean(summary) > mean(without) + 0.01);
    BOOST_TEST(pv::to_string(summary.reason) == pv::to_string(without.reason));  // the shape phases' reason; the polish's in the message
    BOOST_TEST(summary.message.find("the mean quality stopped rising") != std::string::npos);
}

// A tangled mesh: untangled with conjugate gradients as before, then Newton steps. Slow
// (tests/CMakeLists.txt): as newton_directions_never_make_things_worse; untangling in the cases above.
BOOST_AUTO_TEST_CASE(newton_directions_after_untangling, *boost::unit_test::label("slow")) {
    auto mesh = pv::test::perturbed_shared_mesh("mesquite/tets/cube-clip-5.vtk", 0.3, 1);
    pv::GlobalSolverOptions options;
    options.direction = pv::GlobalSolverOptions::Direction::Newton;
    options.termination.max_iterations = 30;
    const auto summary = pv::GlobalSolver(options).improve(mesh);
    BOOST_TEST_MESSAGE(summary.brief_report());
    BOOST_TEST(summary.before.inverted > 0);
    BOOST_TEST(summary.after.inverted == 0);
    check_never_worse(summary);
}

// The dihedral quality, raised by both solvers on a valid mesh: never worse, never an inverted
// element, and the smallest dihedral angle of the movable tets up (house2: 1.85 degrees before).
BOOST_AUTO_TEST_CASE(both_solvers_raise_the_dihedral_quality) {
    const auto input = shared_mesh("stellar/house2.node");
    const pv::QualityAssessor assessor({"min_dihedral_deg", "dihedral_sine"});
    const double before = assessor.assess(input).metric("min_dihedral_deg")->movable.min;
    for (const char* method : {"global", "local"}) {
        auto mesh = input;
        pv::Summary summary;
        if (std::string(method) == "global") {
            pv::GlobalSolverOptions options;
            options.shape_metric = "dihedral_sine";
            summary = pv::GlobalSolver(options).improve(mesh);
        } else {
            pv::LocalSolverOptions options;
            options.metric = "dihedral_sine";
            summary = pv::LocalSolver(options).improve(mesh);
        }
        const auto after = assessor.assess(mesh);
        BOOST_TEST_CONTEXT(method << ": " << summary.brief_report()) {
            check_never_worse(summary);
            BOOST_TEST(summary.after.inverted == 0);
            BOOST_TEST(summary.worst_after > summary.worst_before);
            BOOST_TEST(after.metric("dihedral_sine")->movable.min == summary.worst_after);
            BOOST_TEST(after.metric("min_dihedral_deg")->movable.min > 5.0 * before);
        }
    }
}

BOOST_AUTO_TEST_CASE(all_vertices_fixed_means_nothing_to_move) {
    auto mesh = shared_mesh("mesquite/tets/tire.vtk");
    mesh.set_fixed(std::vector<std::uint8_t>(mesh.num_vertices(), 1));
    const auto summary = pv::GlobalSolver().improve(mesh);
    BOOST_TEST((summary.reason == pv::TerminationReason::NothingToMove));
    BOOST_TEST(!summary.success());
    BOOST_TEST(summary.message.find("fixed") != std::string::npos);
    pv::Mesh empty;
    BOOST_TEST((pv::GlobalSolver().improve(empty).reason == pv::TerminationReason::NothingToMove));
}

BOOST_AUTO_TEST_CASE(an_inverted_tet_with_every_vertex_fixed_cannot_be_untangled) {
    auto mesh = pv::test::frozen_inverted_tet();
    const auto summary = pv::GlobalSolver().improve(mesh);
    BOOST_TEST((summary.reason == pv::TerminationReason::CannotUntangle));
    BOOST_TEST(summary.after.inverted == 1);
    BOOST_TEST(summary.after.inverted_frozen == 1);
    BOOST_TEST(!summary.success());
    BOOST_TEST(summary.worst_after >= summary.worst_before);
}

BOOST_AUTO_TEST_CASE(impossible_options_are_rejected_by_name) {
    auto expect = [](auto change, const std::string& word) {
        pv::test::check_option_rejected<pv::GlobalSolver, pv::GlobalSolverOptions>(change, word);
    };
    expect([](auto& o) { o.objective = "lp"; }, "log_barrier");
    expect([](auto& o) { o.shape_metric = "min_dihedral_deg"; }, "gradient");
    expect([](auto& o) { o.objective_options.barrier_shrink = 0.0; }, "barrier_shrink");
    expect([](auto& o) { o.termination.max_iterations = -1; }, "max_iterations");
    expect([](auto& o) { o.threads = -2; }, "threads");
    expect([](auto& o) { o.newton_tolerance = 0.0; }, "newton_tolerance");
    expect([](auto& o) { o.newton_cg_iterations = 0; }, "newton_cg_iterations");
    expect([](auto& o) { o.gain_tolerance = -0.1; }, "gain_tolerance");
    expect([](auto& o) { o.gain_tolerance = std::numeric_limits<double>::quiet_NaN(); }, "gain_tolerance");
    expect([](auto& o) { o.focus_band = 0.0; }, "focus_band");
    expect([](auto& o) { o.focus_band = 1.5; }, "focus_band");
    expect([](auto& o) { o.finish_band = 0.0; }, "finish_band");
    expect([](auto& o) { o.finish_band = std::numeric_limits<double>::quiet_NaN(); }, "finish_band");
    expect([](auto& o) {
        o.direction = pv::GlobalSolverOptions::Direction::Newton;
        o.objective = "p_mean";
    }, "log_barrier");
}

BOOST_AUTO_TEST_SUITE_END()
