// The top of an iteration (src/solvers/iteration_start.hpp): every solver stops on a stop request,
// a spent budget and a reached target by the same rules and says so in the same words.
#include <boost/test/unit_test.hpp>
#include <functional>
#include <memory>
#include <string>

#include "paloverde/parallel/reducer.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "paloverde/solvers/laplace_solver.hpp"
#include "paloverde/solvers/local_solver.hpp"
#include "paloverde/solvers/stop.hpp"
#include "solvers/iteration_start.hpp"
#include "support/sliding_checks.hpp"
#include "support/solver_checks.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;
namespace detail = paloverde::detail;

namespace {

struct StopCleared {
    StopCleared() { pv::clear_stop_request(); }
    ~StopCleared() { pv::clear_stop_request(); }
};

// One solver, with what it calls an iteration, made from a termination criterion that applies to
// its shape iterations (or, with `untangling`, to its untangling).
struct Case {
    std::string name, unit;
    std::function<std::unique_ptr<pv::Solver>(const pv::TerminationCriterion&)> make;
};

std::vector<Case> cases() {
    return {
        {"global", "iterations",
         [](const pv::TerminationCriterion& t) {
             pv::GlobalSolverOptions o;
             o.termination = t;
             o.polish = pv::GlobalSolverOptions::Polish::Off;
             return std::make_unique<pv::GlobalSolver>(o);
         }},
        {"local", "sweeps",
         [](const pv::TerminationCriterion& t) {
             pv::LocalSolverOptions o;
             o.termination = t;
             return std::make_unique<pv::LocalSolver>(o);
         }},
        {"smart_laplace", "sweeps",
         [](const pv::TerminationCriterion& t) {
             pv::LaplaceSolverOptions o;
             o.termination = t;
             return std::make_unique<pv::LaplaceSolver>(o);
         }},
        {"laplace", "sweeps",
         [](const pv::TerminationCriterion& t) {
             pv::LaplaceSolverOptions o;
             o.smart = false;
             o.termination = t;
             return std::make_unique<pv::LaplaceSolver>(o);
         }},
    };
}

// Every solver, run under `t`, stops for `reason` after `iterations` (-1: the sweeps after none, the
// global solver after one) and says `words(case)`.
void every_solver_stops(const pv::TerminationCriterion& t, const std::string& reason, int iterations,
                        const std::function<std::string(const Case&)>& words) {
    for (const auto& c : cases()) {
        auto mesh = pv::test::shared_mesh("mesquite/tets/tire.vtk");
        const auto s = c.make(t)->improve(mesh);
        BOOST_TEST_INFO(c.name << ": " << s.message);
        BOOST_TEST(to_string(s.reason) == reason);
        BOOST_TEST(s.iterations == (iterations >= 0 ? iterations : c.name == "global" ? 1 : 0));
        BOOST_TEST(s.message.find(words(c)) != std::string::npos);
    }
}

}  // namespace

BOOST_AUTO_TEST_SUITE(iteration_start)

BOOST_AUTO_TEST_CASE(the_order_is_stop_then_target_then_budget) {
    const StopCleared cleared;
    pv::TerminationCriterion c;
    c.max_iterations = 3;
    c.target_worst_quality = 0.5;
    const pv::Reducer serial;
    detail::IterationStart top(c, serial, detail::Clock::now(), "sweeps", nullptr, "while testing");
    int saved = 0;
    auto save = [&] { ++saved; };
    BOOST_TEST(!top(3, 2, save, 0.4).has_value());
    BOOST_TEST(top(4, 3, save).has_value());  // out of sweeps
    const auto spent = top(4, 3, save, 0.4);
    BOOST_TEST_REQUIRE(spent.has_value());
    BOOST_TEST((spent->reason == pv::TerminationReason::IterationLimit));
    BOOST_TEST(spent->message == "stopped after 3 sweeps while testing");
    const auto target = top(4, 3, save, 0.5);  // the target before the budget
    BOOST_TEST_REQUIRE(target.has_value());
    BOOST_TEST((target->reason == pv::TerminationReason::TargetReached));
    BOOST_TEST(target->message == "the worst quality reached the target");
    pv::request_stop();
    const auto stopped = top(2, 1, save, 0.5);  // the stop before the target
    BOOST_TEST_REQUIRE(stopped.has_value());
    BOOST_TEST((stopped->reason == pv::TerminationReason::Interrupted));
    BOOST_TEST(stopped->message == "interrupted (a stop was requested) after 1 sweeps while testing");
    BOOST_TEST(saved == 0);  // no checkpointer: nothing to save
}

BOOST_AUTO_TEST_CASE(a_spent_time_limit_says_so) {
    pv::TerminationCriterion c;
    c.max_seconds = 1e-9;
    const pv::Reducer serial;
    detail::IterationStart top(c, serial, detail::Clock::now() - std::chrono::milliseconds(1), "iterations");
    const auto spent = top(1, 0, [] {});
    BOOST_TEST_REQUIRE(spent.has_value());
    BOOST_TEST((spent->reason == pv::TerminationReason::TimeLimit));
    BOOST_TEST(spent->message == "time limit reached");
}

// A stop request takes a checkpoint whether one is due or not; without one, a due checkpoint is
// taken and the iteration goes on; a run without a checkpoint file takes none.
BOOST_AUTO_TEST_CASE(a_stop_or_a_due_checkpoint_takes_the_checkpoint) {
    const StopCleared cleared;
    const pv::test::ScratchDir dir("iteration_start_checkpoints");
    auto mesh = pv::test::shared_mesh("mesquite/tets/tet_4_tangled.vtk");
    pv::CheckpointOptions every_two;
    every_two.file = (dir / "c.ckpt").string();
    every_two.every_iterations = 2;
    every_two.every_seconds = 0.0;
    const pv::Reducer serial;
    const pv::TerminationCriterion c;
    detail::Checkpointer writes(every_two, "test", "", mesh), none({}, "test", "", mesh);
    detail::IterationStart top(c, serial, detail::Clock::now(), "iterations", &writes),
        without(c, serial, detail::Clock::now(), "iterations", &none);
    int saved = 0;
    auto save = [&] { ++saved; };
    BOOST_TEST(!top(2, 1, save).has_value());
    BOOST_TEST(saved == 0);  // one iteration since the start: not due
    BOOST_TEST(!top(3, 2, save).has_value());
    BOOST_TEST(saved == 1);  // due, and the iteration goes on
    pv::request_stop();
    BOOST_TEST(without(2, 1, save).has_value());
    BOOST_TEST(saved == 1);
    const auto stopped = top(2, 1, save);
    BOOST_TEST_REQUIRE(stopped.has_value());
    BOOST_TEST((stopped->reason == pv::TerminationReason::Interrupted));
    BOOST_TEST(saved == 2);  // not due, but stopped
}

BOOST_AUTO_TEST_CASE(every_solver_stops_on_a_request_in_the_same_words) {
    const StopCleared cleared;
    pv::request_stop();
    every_solver_stops({}, "interrupted", 0, [](const Case& c) { return "interrupted (a stop was requested) after 0 " + c.unit; });
}

BOOST_AUTO_TEST_CASE(every_solver_stops_on_its_iteration_budget_in_the_same_words) {
    pv::TerminationCriterion t;
    t.max_iterations = 2;
    t.min_progress = 0.0;  // never converged: only the budget stops it
    every_solver_stops(t, "iteration_limit", 2, [](const Case& c) { return "stopped after 2 " + c.unit; });
}

BOOST_AUTO_TEST_CASE(every_solver_stops_on_its_time_limit_in_the_same_words) {
    pv::TerminationCriterion t;
    t.max_seconds = 1e-9;
    every_solver_stops(t, "time_limit", 0, [](const Case&) { return std::string("time limit reached"); });
}

// A target the input already meets: the sweeps stop before their first, the global solver after
// its first iteration (it judges the target where it measures).
BOOST_AUTO_TEST_CASE(every_solver_stops_at_its_target_in_the_same_words) {
    pv::TerminationCriterion t;
    t.target_worst_quality = -1.0;
    every_solver_stops(t, "target_reached", -1, [](const Case&) { return std::string("the worst quality reached the target"); });
}

// The untangling energy out of iterations hands over in the budget's words.
BOOST_AUTO_TEST_CASE(the_untangling_energy_out_of_iterations_says_so_in_the_same_words) {
    auto mesh = pv::test::tangled_cube();
    pv::GlobalSolverOptions o;
    o.untangle_termination.max_iterations = 2;
    const auto s = pv::GlobalSolver(o).improve(mesh);
    BOOST_TEST(to_string(s.reason) == "cannot_untangle");
    BOOST_TEST(s.message.find("untangling stopped (stopped after 2 iterations) with elements still inverted") == 0u,
               s.message);
}

// Untangling says what it was doing: the local sweeps in the message's end, the global solver's
// energy before it.
BOOST_AUTO_TEST_CASE(a_stop_while_untangling_says_so) {
    const StopCleared cleared;
    pv::request_stop();
    auto local_mesh = pv::test::tangled_cube(), global_mesh = local_mesh;
    const auto local = pv::LocalSolver().improve(local_mesh);
    BOOST_TEST(local.message.find("interrupted (a stop was requested) after 0 sweeps while untangling") == 0u, local.message);
    const auto global = pv::GlobalSolver().improve(global_mesh);
    BOOST_TEST(global.message.find("while untangling: interrupted (a stop was requested) after 0 iterations") == 0u,
               global.message);
}

BOOST_AUTO_TEST_SUITE_END()
