// Checkpoints of a run that follows a moved boundary in steps (solvers/boundary_motion.hpp): the
// motion's, before the first run and every step, and each run's own beside it (FILE.run). A run
// resumed from any of them (or from those left when a step was stopped) ends bit for bit as the
// uninterrupted run; a checkpoint of another motion, other options or the other kind of run is
// refused.
#include <boost/test/unit_test.hpp>
#include <filesystem>
#include <string>
#include <vector>

#include "paloverde/core/error.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "paloverde/solvers/local_solver.hpp"
#include "robustness_support.hpp"
#include "solvers/checkpointer.hpp"
#include "support/ring_meshes.hpp"
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

// Nearly a turn and a half of the inner circle: on the budgets below one run does not untangle it,
// and the motion is followed in several steps.
pv::Mesh stepped_motion() { return pv::test::turned_ring(500.0); }

pv::GlobalSolverOptions global_options() {
    pv::GlobalSolverOptions options;
    options.untangle_termination.max_iterations = 5;
    options.termination.max_iterations = 30;
    return options;
}

pv::LocalSolverOptions local_options() {
    pv::LocalSolverOptions options;
    options.untangle_termination.max_iterations = 1;
    options.termination.max_iterations = 10;
    return options;
}

fs::path run_file(const fs::path& motion) { return motion.string() + ".run"; }

// `options` with checkpoints of its runs every `every` iterations: resumed from every pair copied.
template <class Solver, class Options>
void check_resumed_from_every_checkpoint(const std::string& name, const Options& options, int every) {
    const pv::Mesh input = stepped_motion();
    const Outcome uninterrupted = run<Solver>(input, options);
    BOOST_TEST_INFO(uninterrupted.summary.message);
    BOOST_TEST_REQUIRE(uninterrupted.summary.message.find("followed in") != std::string::npos);
    // Before the first run and 3 steps or more.
    pv::test::check_resumed_from_every_copy<Solver>("morph_checkpoint_" + name, input, options, every, 4, uninterrupted);
}

}  // namespace

BOOST_AUTO_TEST_SUITE(morph_checkpoint)

BOOST_AUTO_TEST_CASE(a_global_run_in_steps_resumed_from_any_checkpoint_ends_as_the_uninterrupted_run) {
    check_resumed_from_every_checkpoint<pv::GlobalSolver>("global", global_options(), 12);
}

// Slow (tests/CMakeLists.txt): the sanitizers see a run in steps resumed in the case above, and the
// local smoother resumed in checkpoint_test's local_run_resumed_in_either_phase_ends_as_the_uninterrupted_run.
BOOST_AUTO_TEST_CASE(a_local_run_in_steps_resumed_from_any_checkpoint_ends_as_the_uninterrupted_run,
                     *boost::unit_test::label("slow")) {
    check_resumed_from_every_checkpoint<pv::LocalSolver>("local", local_options(), 4);
}

// Stopped (as Ctrl-C would) in the first run and during steps: the step's run wrote its own
// checkpoint at the stop, and the resumed run goes on from there.
BOOST_AUTO_TEST_CASE(a_run_stopped_during_a_step_resumes_where_it_stopped) {
    const StopRequestCleared cleared;
    const pv::test::ScratchDir dir("morph_checkpoint_stop");
    const pv::Mesh input = stepped_motion();
    const auto options = global_options();
    int all_records = 0;
    const Outcome uninterrupted = run<pv::GlobalSolver>(input, options, [&](const pv::IterationRecord&) { ++all_records; });
    for (const int step : {0, 1, 2}) {
        BOOST_TEST_CONTEXT("stopped in " << (step == 0 ? "the first run" : "step " + std::to_string(step))) {
            pv::clear_stop_request();
            const fs::path folder = dir / ("stop" + std::to_string(step));
            fs::create_directory(folder);
            CheckpointCopies copies(folder / "motion.ckpt", folder);
            auto writing = options;
            writing.checkpoint.file = copies.file.string();
            const auto copy = copies.observer();
            int records = 0, in_step = 0;
            // Three records after the motion's checkpoint before that step (a step that fails
            // sooner: in the next one).
            const Outcome stopped = run<pv::GlobalSolver>(input, writing, [&](const pv::IterationRecord& r) {
                ++records;
                copy(r);
                if (copies.wholes > step && ++in_step == 3) pv::request_stop();
            });
            BOOST_TEST(to_string(stopped.summary.reason) == "interrupted");
            BOOST_TEST_REQUIRE(fs::exists(run_file(copies.file)));
            pv::clear_stop_request();
            auto resuming = options;
            resuming.checkpoint.resume = copies.file.string();
            // Writing on to the same file, or to another one.
            resuming.checkpoint.file = step == 1 ? (folder / "again.ckpt").string() : copies.file.string();
            int told = 0;
            check_same_end(run<pv::GlobalSolver>(input, resuming, [&](const pv::IterationRecord&) { ++told; }), uninterrupted);
            // Told of what came after the stop, not of the step's first records again.
            BOOST_TEST(told < all_records - records + 3);
            BOOST_TEST(fs::exists(resuming.checkpoint.file));
        }
    }
}

BOOST_AUTO_TEST_CASE(checkpoints_of_another_motion_other_options_or_the_other_kind_of_run_are_refused) {
    const pv::test::ScratchDir dir("morph_checkpoint_refused");
    const pv::Mesh input = stepped_motion();
    const fs::path motion = dir / "motion.ckpt", single = dir / "single.ckpt";
    auto options = global_options();
    options.checkpoint.file = motion.string();
    run<pv::GlobalSolver>(input, options);
    BOOST_TEST_REQUIRE(fs::exists(motion));
    options.checkpoint = {};

    // Another motion: the boundary turned less, or the same mesh from another reference.
    check_refused<pv::GlobalSolver>(pv::test::turned_ring(490.0), options, motion, "another mesh");
    pv::Mesh other_reference = input;
    std::vector<double> reference(input.reference_coordinates().begin(), input.reference_coordinates().end());
    reference[3 * pv::test::kSectors * 3] += 1e-9;  // an interior vertex
    other_reference.set_reference_coordinates(reference);
    check_refused<pv::GlobalSolver>(other_reference, options, motion, "another mesh");
    // Other options, smallest_motion_step among them; the other solver.
    auto other = options;
    other.untangle_termination.max_iterations = 6;
    check_refused<pv::GlobalSolver>(input, other, motion, "other global solver options");
    other = options;
    other.smallest_motion_step = 1.0 / 32.0;
    check_refused<pv::GlobalSolver>(input, other, motion, "other global solver options");
    check_refused<pv::LocalSolver>(input, local_options(), motion, "written by the global solver");

    // A motion's checkpoint on a single run (the same mesh, no reference), and the reverse.
    pv::Mesh no_motion = input;
    no_motion.clear_reference_coordinates();
    check_refused<pv::GlobalSolver>(no_motion, options, motion, "followed a moved boundary in steps");
    auto single_run = options;
    single_run.checkpoint.file = single.string();
    single_run.checkpoint.every_iterations = 1;
    run<pv::GlobalSolver>(no_motion, single_run);
    BOOST_TEST_REQUIRE(fs::exists(single));
    check_refused<pv::GlobalSolver>(input, options, single, "of a single solver run");
}

// What a motion keeps of a run (its first run's, or the followed motion's before the every-vertex
// run) keeps how far a sliding boundary moved; a list of the wrong length is refused naming the
// file and the entry.
BOOST_AUTO_TEST_CASE(a_kept_outcome_keeps_its_sliding_boundary_and_a_malformed_one_is_refused) {
    pv::Summary slid;
    slid.solver = "global";
    slid.message = "followed";
    slid.quality_metric = "shape_size";
    slid.reason = pv::TerminationReason::IterationLimit;
    slid.boundary = pv::BoundaryMotion{12, 7, 1e-17, 2.5, 2.5};
    pv::detail::SolverState state;
    state.source = "h.ckpt";
    pv::detail::store_outcome(state, "followed", slid);
    const pv::Summary back = pv::detail::restored_outcome(state, "followed");
    BOOST_TEST_REQUIRE(back.boundary.has_value());
    BOOST_TEST(back.boundary->sliding == 12);
    BOOST_TEST(back.boundary->moved == 7);
    BOOST_TEST(back.boundary->largest_distance == 1e-17);
    BOOST_TEST(back.boundary->volume_after == 2.5);

    pv::Summary fixed = slid;
    fixed.boundary.reset();
    pv::detail::SolverState plain;
    pv::detail::store_outcome(plain, "followed", fixed);
    BOOST_TEST(!pv::detail::restored_outcome(plain, "followed").boundary.has_value());

    state.lists["followed.boundary"].pop_back();
    try {
        pv::detail::restored_outcome(state, "followed");
        BOOST_FAIL("a boundary entry of 4 numbers was read");
    } catch (const pv::FileError& e) {
        const std::string what = e.what();
        BOOST_TEST(what.find("h.ckpt") != std::string::npos);
        BOOST_TEST(what.find("followed.boundary holds 4 numbers, not 5") != std::string::npos);
    }
}

BOOST_AUTO_TEST_SUITE_END()
