// Stopping a solver early (stop.hpp): from an observer at iteration k, before the run, in a queue
// and in a config run; and numerical failures. Whatever stops it, a solver hands back its best
// iterate, never the input made worse.
#include <boost/test/unit_test.hpp>
#include <filesystem>

#include "paloverde/config/run.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "paloverde/solvers/instruction_queue.hpp"
#include "paloverde/solvers/laplace_solver.hpp"
#include "paloverde/solvers/local_solver.hpp"
#include "robustness_support.hpp"

namespace pv = paloverde;
using pv::test::StopRequestCleared;

namespace {

// The first iteration of `phase` whose iterate is worse than the phase's start while an earlier
// one was better: stopped there, a solver that handed back its latest iterate would hand back a
// mesh worse than its input, one that handed back its input would lose the progress. 0 if none.
int first_dip(const pv::Summary& s, const std::string& phase) {
    double start = 0.0;
    bool started = false;
    for (const auto& r : s.history) {
        if (r.phase != phase) continue;
        if (!started) start = r.worst_quality, started = true;
        else if (r.worst_quality < start && r.best_worst_quality > start) return r.iteration;
    }
    return 0;
}

// The best by the rule over the records of `phase`: fewest non-positive elements, then the highest
// worst quality.
std::pair<long, double> best_by_rule(const pv::Summary& s, const std::string& phase) {
    std::pair<long, double> best{std::numeric_limits<long>::max(), -std::numeric_limits<double>::infinity()};
    for (const auto& r : s.history)
        if (r.phase == phase && (r.inverted < best.first || (r.inverted == best.first && r.worst_quality > best.second)))
            best = {r.inverted, r.worst_quality};
    return best;
}

template <class Solver>
pv::Summary stopped_at(Solver& solver, pv::Mesh& mesh, int k) {
    solver.set_observer([k](const pv::IterationRecord& r) {
        if (r.iteration == k) pv::request_stop();
    });
    return solver.improve(mesh);
}

}  // namespace

BOOST_AUTO_TEST_SUITE(stop)

// Stopped at an iteration where the current iterate is worse than the best: the best comes back,
// exactly the mesh a run limited to that many iterations returns. Slow (tests/CMakeLists.txt): the
// sanitizers see the solvers stopped, and a best iterate handed back, in the cases below.
BOOST_AUTO_TEST_CASE(global_solver_stopped_at_iteration_k_hands_back_its_best_iterate,
                     *boost::unit_test::label("slow")) {
    const StopRequestCleared cleared;
    const auto input = pv::test::shared_mesh("mesquite/tets/tire.vtk");
    pv::GlobalSolverOptions options;
    options.termination.max_iterations = 200;
    // The whole mesh with mu shrinking every few steps: a run that dips below its start.
    options.focus_band = 1.0;
    options.gain_tolerance = 0.0;
    auto full_mesh = input;
    const auto full = pv::GlobalSolver(options).improve(full_mesh);
    const int k = first_dip(full, "shape");
    BOOST_TEST_REQUIRE(k > 0, "the run never dips below its start after rising: the test would not tell best, latest "
                              "and input apart");

    auto mesh = input;
    pv::GlobalSolver solver(options);
    const auto s = stopped_at(solver, mesh, k);
    BOOST_TEST_MESSAGE("stopped at " << k << " of " << full.iterations << ": " << s.brief_report());
    BOOST_TEST(to_string(s.reason) == "interrupted");
    BOOST_TEST(!s.success());
    BOOST_TEST(s.iterations == k);
    BOOST_TEST(s.history.back().worst_quality < s.worst_before);
    pv::test::check_never_worse(s);
    BOOST_TEST(s.worst_after > s.worst_before);
    // The mesh handed back is the best iterate: its worst quality is the history's best.
    BOOST_TEST(s.worst_after == best_by_rule(s, "shape").second, boost::test_tools::tolerance(1e-12));

    pv::clear_stop_request();
    options.termination.max_iterations = k;
    auto limited = input;
    const auto l = pv::GlobalSolver(options).improve(limited);
    BOOST_TEST(to_string(l.reason) == "iteration_limit");
    BOOST_TEST(pv::test::same_coordinates(mesh, limited));
}

BOOST_AUTO_TEST_CASE(global_solver_stopped_while_untangling_has_no_more_inverted_elements) {
    const StopRequestCleared cleared;
    const auto input = pv::test::perturbed_shared_mesh("mesquite/tets/tire.vtk", 0.3, 1);
    auto mesh = input;
    pv::GlobalSolver solver;
    const auto s = stopped_at(solver, mesh, 5);
    BOOST_TEST(to_string(s.reason) == "interrupted");
    BOOST_TEST(s.iterations == 5);
    BOOST_TEST(s.untangle_iterations == 5);
    BOOST_TEST(s.history.back().phase == "untangle_energy");
    BOOST_TEST(s.after.inverted < s.before.inverted);
    BOOST_TEST(pv::count_orientations(mesh).inverted == s.after.inverted);
    // The untangling phase's best by the rule: its non-positive count is the mesh's.
    BOOST_TEST(s.after.inverted == best_by_rule(s, "untangle_energy").first);
    pv::test::check_never_worse(s);
}

BOOST_AUTO_TEST_CASE(local_solver_stopped_at_sweep_k_hands_back_its_best_sweep) {
    const StopRequestCleared cleared;
    const auto input = pv::test::shared_mesh("mesquite/tets/tire.vtk");
    const int k = 3;
    auto mesh = input;
    pv::LocalSolver solver;
    const auto s = stopped_at(solver, mesh, k);
    BOOST_TEST(to_string(s.reason) == "interrupted");
    BOOST_TEST(s.iterations == k);
    pv::test::check_never_worse(s);
    BOOST_TEST(s.worst_after == best_by_rule(s, "shape").second, boost::test_tools::tolerance(1e-12));

    pv::clear_stop_request();
    pv::LocalSolverOptions options;
    options.termination.max_iterations = k;
    auto limited = input;
    pv::LocalSolver(options).improve(limited);
    BOOST_TEST(pv::test::same_coordinates(mesh, limited));
}

BOOST_AUTO_TEST_CASE(local_solver_stopped_while_untangling_has_no_more_inverted_elements) {
    const StopRequestCleared cleared;
    auto mesh = pv::test::perturbed_shared_mesh("mesquite/tets/tire.vtk", 0.3, 2);
    pv::LocalSolver solver;
    const auto s = stopped_at(solver, mesh, 1);
    BOOST_TEST(to_string(s.reason) == "interrupted");
    BOOST_TEST(s.history.back().phase == "untangle");
    BOOST_TEST(s.after.inverted <= s.before.inverted);
    BOOST_TEST(s.after.inverted == best_by_rule(s, "untangle").first);
    pv::test::check_never_worse(s);
}

// A stop requested before the run: nothing moves.
BOOST_AUTO_TEST_CASE(a_stop_requested_before_the_run_leaves_the_mesh_as_it_was) {
    const StopRequestCleared cleared;
    const auto input = pv::test::perturbed_shared_mesh("stellar/house2.node", 0.2, 1);
    pv::request_stop();
    for (const std::string name : {"global", "local", "smart_laplace"}) {
        auto mesh = input;
        pv::Summary s;
        if (name == "global") s = pv::GlobalSolver().improve(mesh);
        else if (name == "local") s = pv::LocalSolver().improve(mesh);
        else s = pv::LaplaceSolver().improve(mesh);
        BOOST_TEST_INFO(name);
        BOOST_TEST(to_string(s.reason) == "interrupted");
        BOOST_TEST(s.iterations == 0);
        BOOST_TEST(pv::test::same_coordinates(mesh, input));
    }
}

BOOST_AUTO_TEST_CASE(a_queue_stops_at_the_interrupted_step) {
    const StopRequestCleared cleared;
    auto mesh = pv::test::perturbed_shared_mesh("mesquite/tets/tire.vtk", 0.3, 3);
    pv::GlobalSolverOptions untangle, shape;
    untangle.improve_shape = false;
    shape.untangle = false;
    pv::InstructionQueue queue;
    queue.assess("before")
        .improve("untangle", std::make_unique<pv::GlobalSolver>(untangle))
        .improve("shape", std::make_unique<pv::GlobalSolver>(shape))
        .assess("after");
    queue.observe([](std::string_view, const pv::IterationRecord& r) {
        if (r.iteration == 3) pv::request_stop();
    });
    const auto result = queue.run(mesh);
    BOOST_TEST(!result.success);
    BOOST_TEST_REQUIRE(result.steps.size() == 2u);
    BOOST_TEST(result.message.find("'untangle' was interrupted") != std::string::npos, result.message);
}

// The config path: the run stops with status `interrupted` (exit code 4) and still writes the
// best mesh and its reports.
BOOST_AUTO_TEST_CASE(an_interrupted_config_run_writes_the_best_mesh_and_exits_four) {
    const StopRequestCleared cleared;
    const pv::test::ScratchDir dir("stop_config_run");
    const auto input = pv::test::shared_data("mesquite/tets/tire.vtk");
    const std::vector<pv::config::Override> set{{"input.mesh=" + input.string(), "test", true},
                                                {"output.mesh=" + (dir / "out.vtu").string(), "test", true},
                                                {"output.summary=" + (dir / "s.json").string(), "test", true}};
    const auto spec = pv::config::parse_config("", "test", set);
    pv::config::RunHooks hooks;
    hooks.on_iteration = [](std::string_view, std::string_view, const pv::IterationRecord& r) {
        if (r.iteration == 20) pv::request_stop();
    };
    const auto result = pv::config::run(spec, hooks);
    BOOST_TEST(result.exit_code() == 4);
    BOOST_TEST(to_string(result.status) == "interrupted");
    BOOST_TEST_REQUIRE(std::filesystem::exists(dir / "out.vtu"));
    BOOST_TEST(std::filesystem::exists(dir / "s.json"));
    const auto written = pv::read_mesh(dir / "out.vtu").mesh;
    const auto& m = result.methods.front();
    BOOST_TEST(m.worst_after >= m.worst_before);
    BOOST_TEST(pv::count_orientations(written).inverted == 0);
}

// A numerical failure (here the p-mean overflows: q^p for p = -400 is infinite for any q below
// about 0.17) ends on the best iterate with its own reason.
BOOST_AUTO_TEST_CASE(a_numerical_failure_ends_on_the_best_iterate) {
    const StopRequestCleared cleared;
    const auto input = pv::test::shared_mesh("mesquite/tets/tire.vtk");
    pv::GlobalSolverOptions options;
    options.objective = "p_mean";
    options.objective_options.p = -400.0;
    auto mesh = input;
    const auto s = pv::GlobalSolver(options).improve(mesh);
    BOOST_TEST_MESSAGE(s.brief_report());
    BOOST_TEST(to_string(s.reason) == "numerical_failure");
    BOOST_TEST(!s.success());
    pv::test::check_never_worse(s);
    BOOST_TEST(s.worst_after == best_by_rule(s, "shape").second, boost::test_tools::tolerance(1e-12));
}

BOOST_AUTO_TEST_SUITE_END()
