// Checkpoints of a run that follows a moved boundary in steps (solvers/boundary_motion.hpp): one
// is written before every step, and a run resumed from any of them (or from the one left when a
// step was stopped) ends bit for bit as the uninterrupted run; a checkpoint of another motion,
// other options or the other kind of run is refused.
#include <boost/test/unit_test.hpp>
#include <filesystem>
#include <string>
#include <vector>

#include "paloverde/core/error.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "paloverde/solvers/local_solver.hpp"
#include "robustness_support.hpp"
#include "support/ring_meshes.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;
namespace fs = std::filesystem;
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

// The same end: coordinates bit for bit, the counters, the history, the message and the reports.
void check_same_end(const Outcome& a, const Outcome& b) {
    BOOST_TEST(pv::test::same_coordinates(a.mesh, b.mesh));
    pv::test::check_same_run(a.summary, b.summary);
    BOOST_TEST(a.summary.message == b.summary.message);
    BOOST_TEST(a.summary.before.inverted == b.summary.before.inverted);
    BOOST_TEST(a.summary.worst_before == b.summary.worst_before);
    BOOST_TEST(a.summary.after.to_json() == b.summary.after.to_json());
}

// An observer that copies the checkpoint each time it changed: one copy per step begun.
struct StepCopies {
    fs::path file, dir;
    std::string last;
    std::vector<fs::path> copies;

    pv::IterationObserver observer() {
        return [this](const pv::IterationRecord&) {
            if (!fs::exists(file)) return;
            std::string bytes = pv::test::read_text(file);
            if (bytes == last) return;
            last = std::move(bytes);
            copies.push_back(dir / ("step" + std::to_string(copies.size()) + ".ckpt"));
            fs::copy_file(file, copies.back());
        };
    }
};

template <class Solver, class Options>
void check_resumed_from_every_step(const std::string& name, const Options& options) {
    const StopRequestCleared cleared;
    const pv::test::ScratchDir dir("morph_checkpoint_" + name);
    const pv::Mesh input = stepped_motion();
    const Outcome uninterrupted = run<Solver>(input, options);
    BOOST_TEST_INFO(uninterrupted.summary.message);
    BOOST_TEST_REQUIRE(uninterrupted.summary.message.find("followed in") != std::string::npos);

    StepCopies copies{dir / "motion.ckpt", dir.path(), {}, {}};
    auto writing = options;
    writing.checkpoint.file = copies.file.string();
    // Writing checkpoints changes nothing.
    check_same_end(run<Solver>(input, writing, copies.observer()), uninterrupted);
    BOOST_TEST_REQUIRE(copies.copies.size() >= 3);
    for (std::size_t i = 0; i < copies.copies.size(); ++i) {
        BOOST_TEST_CONTEXT(name << " resumed before step " << i + 1) {
            auto resuming = options;
            resuming.checkpoint.resume = copies.copies[i].string();
            check_same_end(run<Solver>(input, resuming), uninterrupted);
        }
    }
}

// Resuming from `file` on `input` throws a FileError whose message has `words`; the mesh is left as it was.
template <class Solver, class Options>
void check_refused(const pv::Mesh& input, Options options, const fs::path& file, const std::string& words) {
    options.checkpoint.resume = file.string();
    pv::Mesh mesh = input;
    BOOST_CHECK_EXCEPTION(Solver(options).improve(mesh), pv::FileError, [&](const pv::FileError& e) {
        BOOST_TEST_MESSAGE(e.what());
        return std::string(e.what()).find(words) != std::string::npos;
    });
    BOOST_TEST(pv::test::same_coordinates(mesh, input));
}

}  // namespace

BOOST_AUTO_TEST_SUITE(morph_checkpoint)

BOOST_AUTO_TEST_CASE(a_global_run_in_steps_resumed_before_any_step_ends_as_the_uninterrupted_run) {
    check_resumed_from_every_step<pv::GlobalSolver>("global", global_options());
}

BOOST_AUTO_TEST_CASE(a_local_run_in_steps_resumed_before_any_step_ends_as_the_uninterrupted_run) {
    check_resumed_from_every_step<pv::LocalSolver>("local", local_options());
}

// Stopped (as Ctrl-C would) during a step: the checkpoint left is of that step's start.
BOOST_AUTO_TEST_CASE(a_run_stopped_during_a_step_resumes_from_its_start) {
    const StopRequestCleared cleared;
    const pv::test::ScratchDir dir("morph_checkpoint_stop");
    const pv::Mesh input = stepped_motion();
    const auto options = global_options();
    const Outcome uninterrupted = run<pv::GlobalSolver>(input, options);
    for (const std::size_t step : {1, 2}) {
        BOOST_TEST_CONTEXT("stopped in step " << step) {
            pv::clear_stop_request();
            const fs::path copies_dir = dir / ("stop" + std::to_string(step));
            fs::create_directory(copies_dir);
            StepCopies copies{copies_dir / "motion.ckpt", copies_dir, {}, {}};
            auto writing = options;
            writing.checkpoint.file = copies.file.string();
            const auto copy = copies.observer();
            int records = 0;
            // Three records after the step's checkpoint (a step that fails sooner: in the next one).
            const Outcome stopped = run<pv::GlobalSolver>(input, writing, [&](const pv::IterationRecord& r) {
                copy(r);
                if (copies.copies.size() >= step && ++records == 3) pv::request_stop();
            });
            BOOST_TEST(to_string(stopped.summary.reason) == "interrupted");
            pv::clear_stop_request();
            auto resuming = options;
            resuming.checkpoint.resume = copies.file.string();
            check_same_end(run<pv::GlobalSolver>(input, resuming), uninterrupted);
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

BOOST_AUTO_TEST_SUITE_END()
