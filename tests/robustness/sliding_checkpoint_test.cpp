// Checkpoints of a run whose boundary slides (solvers/sliding_boundary.hpp: the boundary fixed,
// then sliding): the sliding run's own, before each of its two runs, and the run under way's
// beside it (FILE.run); in a motion followed in steps, one level down (the motion's FILE, the
// step's sliding run in FILE.run, its run under way in FILE.run.run); and a surface mesh's single
// run, every vertex sliding. Resumed from any of them it ends bit for bit as the uninterrupted
// run; a checkpoint of the other kind of run, or of another surface, is refused.
#include <boost/test/unit_test.hpp>
#include <filesystem>
#include <string>
#include <vector>

#include "paloverde/solvers/global_solver.hpp"
#include "paloverde/solvers/local_solver.hpp"
#include "robustness_support.hpp"
#include "support/ring_meshes.hpp"
#include "support/surface_meshes.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;
namespace fs = std::filesystem;
using pv::test::CheckpointCopies;
using pv::test::check_refused;
using pv::test::check_same_end;
using pv::test::Outcome;
using pv::test::run;
using pv::test::StopRequestCleared;

namespace {

pv::GlobalSolverOptions global_options() {
    pv::GlobalSolverOptions options;
    options.boundary = pv::GlobalSolverOptions::Boundary::Slide;
    options.termination.max_iterations = 24;
    options.threads = 1;
    return options;
}

pv::LocalSolverOptions local_options() {
    pv::LocalSolverOptions options;
    options.boundary = pv::LocalSolverOptions::Boundary::Slide;
    options.termination.max_iterations = 8;
    options.threads = 1;
    return options;
}

// `options` on `input` resumed from every checkpoint, after checking that the run slides;
// `wholes`: how many times at least the outer file is written; `levels`: how many files deep
// the copies went.
template <class Solver, class Options>
void check_resumed_from_every_checkpoint(const std::string& name, const pv::Mesh& input, const Options& options,
                                         int every, int wholes, int levels) {
    const Outcome uninterrupted = run<Solver>(input, options);
    BOOST_TEST_INFO(uninterrupted.summary.message);
    BOOST_TEST_REQUIRE(uninterrupted.summary.message.find("then sliding") != std::string::npos);
    BOOST_TEST_REQUIRE(uninterrupted.summary.boundary->moved > 0);
    BOOST_TEST(pv::test::check_resumed_from_every_copy<Solver>("sliding_checkpoint_" + name, input, options, every,
                                                               wholes, uninterrupted) == levels);
}

}  // namespace

BOOST_AUTO_TEST_SUITE(sliding_checkpoint)

BOOST_AUTO_TEST_CASE(a_global_sliding_run_resumed_from_any_checkpoint_ends_as_the_uninterrupted_run) {
    // Before the boundary-fixed run and before the sliding one.
    check_resumed_from_every_checkpoint<pv::GlobalSolver>("global", pv::test::shared_mesh("mesquite/tets/tire.vtk"),
                                                          global_options(), 4, 2, 2);
}

BOOST_AUTO_TEST_CASE(a_local_sliding_run_resumed_from_any_checkpoint_ends_as_the_uninterrupted_run) {
    check_resumed_from_every_checkpoint<pv::LocalSolver>("local", pv::test::shared_mesh("mesquite/tets/tire.vtk"),
                                                         local_options(), 2, 2, 2);
}

// A motion followed in steps whose every run slides: three levels of files.
BOOST_AUTO_TEST_CASE(a_sliding_motion_in_steps_resumed_from_any_checkpoint_ends_as_the_uninterrupted_run) {
    auto options = global_options();
    options.untangle_termination.max_iterations = 5;
    options.termination.max_iterations = 30;
    const pv::Mesh input = pv::test::turned_ring(500.0);
    const Outcome uninterrupted = run<pv::GlobalSolver>(input, options);
    BOOST_TEST_INFO(uninterrupted.summary.message);
    BOOST_TEST_REQUIRE(uninterrupted.summary.message.find("followed in") != std::string::npos);
    check_resumed_from_every_checkpoint<pv::GlobalSolver>("motion", input, options, 12, 4, 3);
}

// A tangled torus untangled and improved on its own surface (one run, every vertex sliding):
// checkpoints while untangling and in the shape phase.
BOOST_AUTO_TEST_CASE(a_surface_run_resumed_from_any_checkpoint_ends_as_the_uninterrupted_run) {
    const pv::Mesh input = pv::test::tangled_torus(32, 16);
    pv::GlobalSolverOptions global;
    global.termination.max_iterations = 20;
    global.threads = 1;
    const Outcome by_global = run<pv::GlobalSolver>(input, global);
    BOOST_TEST_REQUIRE(by_global.summary.before.inverted > 0);
    BOOST_TEST_REQUIRE(by_global.summary.untangle_iterations > 0);
    pv::test::check_resumed_from_every_copy<pv::GlobalSolver>("sliding_checkpoint_surface_global", input, global, 6, 3,
                                                              by_global, false);
    pv::LocalSolverOptions local;
    local.termination.max_iterations = 6;
    local.threads = 1;
    const Outcome by_local = run<pv::LocalSolver>(input, local);
    BOOST_TEST_REQUIRE(by_local.summary.before.inverted > 0);
    pv::test::check_resumed_from_every_copy<pv::LocalSolver>("sliding_checkpoint_surface_local", input, local, 2, 3,
                                                             by_local, false);
    // The surface's options are the run's.
    const pv::test::ScratchDir dir("sliding_checkpoint_surface_refused");
    auto writing = global;
    writing.checkpoint.file = (dir / "run.ckpt").string();
    writing.checkpoint.every_iterations = 5;
    run<pv::GlobalSolver>(input, writing);
    BOOST_TEST_REQUIRE(fs::exists(dir / "run.ckpt"));
    auto other = global;
    other.surface.feature_angle = 30.0;
    check_refused<pv::GlobalSolver>(input, other, dir / "run.ckpt", "other global solver options");
}

// Stopped (as Ctrl-C would) in the boundary-fixed run and in the sliding one: that run wrote its
// own checkpoint at the stop, and the resumed run goes on from there.
BOOST_AUTO_TEST_CASE(a_sliding_run_stopped_in_either_run_resumes_where_it_stopped) {
    const StopRequestCleared cleared;
    const pv::test::ScratchDir dir("sliding_checkpoint_stop");
    const pv::Mesh input = pv::test::shared_mesh("mesquite/tets/tire.vtk");
    const auto options = global_options();
    const Outcome uninterrupted = run<pv::GlobalSolver>(input, options);
    for (const int in_run : {1, 2}) {
        BOOST_TEST_CONTEXT("stopped in the " << (in_run == 1 ? "boundary-fixed run" : "sliding run")) {
            pv::clear_stop_request();
            const fs::path folder = dir / ("stop" + std::to_string(in_run));
            fs::create_directory(folder);
            CheckpointCopies copies(folder / "run.ckpt", folder);
            auto writing = options;
            writing.checkpoint.file = copies.file.string();
            const auto copy = copies.observer();
            int records = 0;
            const Outcome stopped = run<pv::GlobalSolver>(input, writing, [&](const pv::IterationRecord& r) {
                copy(r);
                if (copies.wholes == in_run && ++records == 3) pv::request_stop();
            });
            BOOST_TEST(to_string(stopped.summary.reason) == "interrupted");
            BOOST_TEST_REQUIRE(fs::exists(folder / "run.ckpt.run"));
            pv::clear_stop_request();
            auto resuming = options;
            resuming.checkpoint.resume = copies.file.string();
            resuming.checkpoint.file = copies.file.string();  // writing on to the file it resumed from
            check_same_end(run<pv::GlobalSolver>(input, resuming), uninterrupted);
        }
    }
}

BOOST_AUTO_TEST_CASE(checkpoints_of_the_other_kind_of_run_or_another_surface_are_refused) {
    const pv::test::ScratchDir dir("sliding_checkpoint_refused");
    const pv::Mesh input = pv::test::shared_mesh("mesquite/tets/tire.vtk");
    const fs::path sliding = dir / "sliding.ckpt", single = dir / "single.ckpt";
    auto options = global_options();
    options.termination.max_iterations = 4;
    options.checkpoint.file = sliding.string();
    run<pv::GlobalSolver>(input, options);
    BOOST_TEST_REQUIRE(fs::exists(sliding));
    options.checkpoint = {};

    auto fixed = options;
    fixed.boundary = pv::GlobalSolverOptions::Boundary::Fixed;
    check_refused<pv::GlobalSolver>(input, fixed, sliding, "of a run whose boundary slid");
    auto other_surface = options;
    other_surface.surface.feature_angle = 30.0;
    check_refused<pv::GlobalSolver>(input, other_surface, sliding, "other global solver options");
    check_refused<pv::LocalSolver>(input, local_options(), sliding, "written by the global solver");

    fixed.checkpoint.file = single.string();
    fixed.checkpoint.every_iterations = 1;
    run<pv::GlobalSolver>(input, fixed);
    BOOST_TEST_REQUIRE(fs::exists(single));
    check_refused<pv::GlobalSolver>(input, options, single, "of a single solver run");
}

BOOST_AUTO_TEST_SUITE_END()
