// Checkpoints and resuming, in process: a run resumed from any of its checkpoints (periodic ones,
// or the one written when it was stopped) ends bit for bit as the uninterrupted run, with the
// same history; a damaged or foreign checkpoint is refused with a message that says why.
#include <boost/test/unit_test.hpp>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "paloverde/core/error.hpp"
#include "paloverde/metrics/targets.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "paloverde/solvers/local_solver.hpp"
#include "robustness_support.hpp"

namespace pv = paloverde;
namespace fs = std::filesystem;
using pv::test::Outcome;
using pv::test::run;
using pv::test::StopRequestCleared;

namespace {

// An observer that copies the checkpoint file as it stood at chosen iterations, keyed by the
// iteration of the record and its phase.
struct CheckpointCopies {
    fs::path file;
    std::map<int, fs::path> at;  // record iteration -> copy
    std::map<int, std::string> phase;

    pv::IterationObserver observer() {
        return [this](const pv::IterationRecord& r) {
            const auto it = at.find(r.iteration);
            if (it == at.end() || fs::exists(it->second) || !fs::exists(file)) return;
            fs::copy_file(file, it->second);
            phase[r.iteration] = r.phase;
        };
    }
};

// Checks that resuming from each copy ends as `reference` did.
template <class Solver, class Options>
void check_resumes(const pv::Mesh& input, Options options, const CheckpointCopies& copies, const Outcome& reference,
                   std::size_t expected) {
    BOOST_TEST_REQUIRE(copies.phase.size() == expected);
    for (const auto& [iteration, path] : copies.at) {
        BOOST_TEST_CONTEXT("resumed from the checkpoint copied at iteration " << iteration << " ("
                                                                                << copies.phase.at(iteration) << ")") {
            options.checkpoint = {};
            options.checkpoint.resume = path.string();
            // A resumed run tells its observer only of the iterations after the checkpoint.
            std::vector<int> told;
            const auto resumed = run<Solver>(input, options, [&](const pv::IterationRecord& r) { told.push_back(r.iteration); });
            BOOST_TEST_REQUIRE(!told.empty());
            BOOST_TEST(told.front() > 0);
            BOOST_TEST(told.front() <= iteration);
            BOOST_TEST(told.size() < reference.summary.history.size());
            BOOST_TEST(pv::test::same_coordinates(resumed.mesh, reference.mesh));
            pv::test::check_same_run(resumed.summary, reference.summary);
        }
    }
}

}  // namespace

BOOST_AUTO_TEST_SUITE(checkpoint)

// A shape run on tire, uninterrupted, then writing checkpoints every 10 iterations (it must end
// the same), then resumed from copies of the checkpoint taken at the iterations `at`. Returns the
// phase of each copy's iteration.
std::map<int, std::string> check_global_shape_run_resumes(const pv::GlobalSolverOptions& given, const char* name,
                                                          const std::vector<int>& at, const pv::Mesh& input) {
    const StopRequestCleared cleared;
    const pv::test::ScratchDir dir(name);
    pv::GlobalSolverOptions options = given;
    const auto reference = run<pv::GlobalSolver>(input, options);
    CheckpointCopies copies{dir / "run.ckpt", {}, {}};
    for (const int iteration : at) copies.at[iteration] = dir / ("at_" + std::to_string(iteration) + ".ckpt");
    options.checkpoint.file = copies.file.string();
    options.checkpoint.every_iterations = 10;
    const auto checkpointed = run<pv::GlobalSolver>(input, options, copies.observer());
    BOOST_TEST(pv::test::same_coordinates(checkpointed.mesh, reference.mesh));
    pv::test::check_same_run(checkpointed.summary, reference.summary);
    check_resumes<pv::GlobalSolver>(input, options, copies, reference, at.size());
    // Written through a temporary and a rename: nothing else is left in the directory.
    std::size_t files = 0;
    for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir.path())) ++files;
    BOOST_TEST(files == 1 + at.size());
    return copies.phase;
}
std::map<int, std::string> check_global_shape_run_resumes(const pv::GlobalSolverOptions& given, const char* name,
                                                          const std::vector<int>& at) {
    return check_global_shape_run_resumes(given, name, at, pv::test::shared_mesh("mesquite/tets/tire.vtk"));
}

// The copy at 51 holds the checkpoint of iteration 50, nine steps into a stretch in which the
// barrier weighs tire's worst element under 1% (the count of such steps is in the checkpoint: mu
// shrinks on the tenth).
BOOST_AUTO_TEST_CASE(global_shape_run_resumed_from_a_checkpoint_ends_as_the_uninterrupted_run) {
    pv::GlobalSolverOptions options;
    options.termination.max_iterations = 150;
    check_global_shape_run_resumes(options, "checkpoint_global_shape", {23, 51, 104});
}

// Newton directions carry their damping factor across iterations: it is in the checkpoint. Slow
// (tests/CMakeLists.txt): the sanitizers see Newton steps resumed in
// global_run_resumed_around_a_restarted_barrier_ends_as_the_uninterrupted_run (the finish).
BOOST_AUTO_TEST_CASE(global_newton_run_resumed_from_a_checkpoint_ends_as_the_uninterrupted_run,
                     *boost::unit_test::label("slow")) {
    pv::GlobalSolverOptions options;
    options.direction = pv::GlobalSolverOptions::Direction::Newton;
    options.termination.max_iterations = 40;
    check_global_shape_run_resumes(options, "checkpoint_global_newton", {13, 34});
}

// The Newton finish, resumed from a checkpoint of the conjugate gradients before it and from ones
// taken in each of its parts. On tire, with min_progress a hundred times smaller than the default
// (so that the conjugate gradients hand over later, at iteration 256), the finish on their barrier
// hands over to a fresh one at 306, which runs until the budget of 440. Slow (tests/CMakeLists.txt):
// the sanitizers see both parts of the finish resumed in the next case.
BOOST_AUTO_TEST_CASE(global_run_resumed_in_its_newton_finish_ends_as_the_uninterrupted_run,
                     *boost::unit_test::label("slow")) {
    pv::GlobalSolverOptions options;
    options.termination.max_iterations = 440;
    options.termination.min_progress = 1e-8;
    const auto phase = check_global_shape_run_resumes(options, "checkpoint_global_finish", {200, 280, 385});
    BOOST_TEST(phase.at(200) == "shape");
    BOOST_TEST(phase.at(280) == "finish");
    BOOST_TEST(phase.at(385) == "finish_fresh");
}

// A finish part that ends because its worst element rose far above t hands over to a fresh
// barrier (tire with min_progress 0.1: the finish from 10, the fresh barrier from 12; resumed
// from a checkpoint taken in each): the gap and t the part began with are in the checkpoint,
// and so is the count of subproblems solved at once.
BOOST_AUTO_TEST_CASE(global_run_resumed_around_a_restarted_barrier_ends_as_the_uninterrupted_run) {
    pv::GlobalSolverOptions options;
    options.termination.min_progress = 0.1;
    const auto phase = check_global_shape_run_resumes(options, "checkpoint_global_restart", {11, 32});
    BOOST_TEST(phase.at(11) == "finish");
    BOOST_TEST(phase.at(32) == "finish_fresh");
}

// A shape phase run again with a close start (the mixed mesh with a budget of 100: the shape
// phase stalls at 62, the second run goes to 77, a fresh Newton finish to the budget's end),
// resumed from a checkpoint taken in that second run and from one in the finish after it.
BOOST_AUTO_TEST_CASE(global_run_resumed_in_a_shape_phase_run_again_ends_as_the_uninterrupted_run) {
    pv::GlobalSolverOptions options;
    options.termination.max_iterations = 100;
    auto input = pv::test::shared_mesh("mesquite/mixed/mixed-hex-pyr-tet.vtk");
    pv::set_targets(input, pv::TargetOptions::from("aspect"));  // as the command line's keep: auto
    const auto phase = check_global_shape_run_resumes(options, "checkpoint_global_close_start", {71, 91}, input);
    BOOST_TEST(phase.at(71) == "shape_close_start");
    BOOST_TEST(phase.at(91) == "finish_fresh");
}

// The mean's polish (always; on tire with a budget of 260 from iteration 182, after the finish):
// resumed from a checkpoint of the finish before it and from two taken in it, with its floor and
// mu (the objective's state), the vertices it holds still, its best mean and why the shape
// phases before it stopped.
BOOST_AUTO_TEST_CASE(global_run_resumed_in_its_polish_ends_as_the_uninterrupted_run) {
    pv::GlobalSolverOptions options;
    options.polish = pv::GlobalSolverOptions::Polish::Always;
    options.termination.max_iterations = 260;
    const auto phase = check_global_shape_run_resumes(options, "checkpoint_global_polish", {150, 195, 241});
    BOOST_TEST(phase.at(150) == "finish");
    BOOST_TEST(phase.at(195) == "polish");
    BOOST_TEST(phase.at(241) == "polish");
}

// A focused run saves which vertices its focus moves: resumed, it goes on with the same focus.
BOOST_AUTO_TEST_CASE(global_focused_run_resumed_from_a_checkpoint_ends_as_the_uninterrupted_run) {
    pv::GlobalSolverOptions options;
    options.focus_band = 0.1;
    options.termination.max_iterations = 80;
    check_global_shape_run_resumes(options, "checkpoint_global_focus", {17, 53});
}

// Untangling by the barrier ascent (it stalls, local sweeps finish it), then the shape phase:
// checkpoints in either phase and just before the local sweeps. (Untangling by the energy is
// resumed in a_stopped_run_resumes_from_the_checkpoint_it_wrote_when_stopped.)
BOOST_AUTO_TEST_CASE(global_untangling_run_resumed_in_either_phase_ends_as_the_uninterrupted_run) {
    const StopRequestCleared cleared;
    const pv::test::ScratchDir dir("checkpoint_global_untangle");
    const auto input = pv::test::perturbed_shared_mesh("stellar/house2.node", 0.3, 3);
    pv::GlobalSolverOptions options;
    options.untangling = pv::GlobalSolverOptions::Untangling::Barrier;
    options.termination.max_iterations = 30;
    const auto reference = run<pv::GlobalSolver>(input, options);
    BOOST_TEST(reference.summary.after.inverted == 0);
    int local = 0;
    for (const auto& r : reference.summary.history)
        if (r.phase == "untangle_local") local = r.iteration;
    BOOST_TEST_REQUIRE(local > 20, "no local untangling sweeps: the test would not cover them");

    const int in_shape = reference.summary.untangle_iterations + 8;
    CheckpointCopies copies{dir / "run.ckpt",
                            {{20, dir / "untangle.ckpt"}, {local, dir / "before_local.ckpt"}, {in_shape, dir / "shape.ckpt"}},
                            {}};
    options.checkpoint.file = copies.file.string();
    options.checkpoint.every_iterations = 5;
    const auto checkpointed = run<pv::GlobalSolver>(input, options, copies.observer());
    BOOST_TEST(pv::test::same_coordinates(checkpointed.mesh, reference.mesh));
    check_resumes<pv::GlobalSolver>(input, options, copies, reference, 3);
    BOOST_TEST(copies.phase.at(20) == "untangle");
    BOOST_TEST(copies.phase.at(local) == "untangle");
    BOOST_TEST(copies.phase.at(in_shape) == "shape");
}

// Stopped (as Ctrl-C would): the checkpoint written at the stop resumes to the uninterrupted end.
BOOST_AUTO_TEST_CASE(a_stopped_run_resumes_from_the_checkpoint_it_wrote_when_stopped) {
    const StopRequestCleared cleared;
    const pv::test::ScratchDir dir("checkpoint_stop");
    const auto input = pv::test::perturbed_shared_mesh("mesquite/tets/tire.vtk", 0.3, 3);
    pv::GlobalSolverOptions options;
    options.termination.max_iterations = 40;
    const auto reference = run<pv::GlobalSolver>(input, options);
    // Stopped while the energy untangles (in its first round, between rounds and in a later one),
    // then in the shape phase.
    // Stopped at 7, the run stops where the energy's second round starts (its epsilon changes).
    const auto& h = reference.summary.history;
    BOOST_TEST_REQUIRE(h[12].phase == "untangle_energy");
    BOOST_TEST_REQUIRE((h[3].mu == h[7].mu && h[8].mu < h[7].mu && h[12].mu == h[8].mu));
    for (const int k : {3, 7, 12, reference.summary.untangle_iterations + 5}) {
        BOOST_TEST_CONTEXT("stopped at iteration " << k) {
            pv::clear_stop_request();
            const fs::path file = dir / ("stop" + std::to_string(k) + ".ckpt");
            auto stopped_options = options;
            stopped_options.checkpoint.file = file.string();  // by time only (every 300 s): written at the stop
            const auto stopped = run<pv::GlobalSolver>(input, stopped_options, [k](const pv::IterationRecord& r) {
                if (r.iteration == k) pv::request_stop();
            });
            BOOST_TEST(to_string(stopped.summary.reason) == "interrupted");
            BOOST_TEST_REQUIRE(fs::exists(file));
            pv::clear_stop_request();
            auto resume_options = options;
            resume_options.checkpoint.resume = file.string();
            int told = 0;
            const auto resumed = run<pv::GlobalSolver>(input, resume_options, [&](const pv::IterationRecord&) { ++told; });
            BOOST_TEST(told < static_cast<int>(reference.summary.history.size()) - k);
            BOOST_TEST(pv::test::same_coordinates(resumed.mesh, reference.mesh));
            pv::test::check_same_run(resumed.summary, reference.summary);
        }
    }
}

BOOST_AUTO_TEST_CASE(local_run_resumed_in_either_phase_ends_as_the_uninterrupted_run) {
    const StopRequestCleared cleared;
    const pv::test::ScratchDir dir("checkpoint_local");
    const auto input = pv::test::perturbed_shared_mesh("mesquite/tets/tire.vtk", 0.3, 3);
    pv::LocalSolverOptions options;
    options.termination.max_iterations = 12;
    const auto reference = run<pv::LocalSolver>(input, options);
    BOOST_TEST_REQUIRE(reference.summary.untangle_iterations >= 2);
    BOOST_TEST(reference.summary.after.inverted == 0);

    // With a checkpoint every sweep, the file seen with the record of sweep k is the one written
    // before that sweep.
    const int in_shape = reference.summary.untangle_iterations + 4;
    CheckpointCopies copies{dir / "run.ckpt", {{2, dir / "untangle.ckpt"}, {in_shape, dir / "shape.ckpt"}}, {}};
    options.checkpoint.file = copies.file.string();
    options.checkpoint.every_iterations = 1;
    const auto checkpointed = run<pv::LocalSolver>(input, options, copies.observer());
    BOOST_TEST(pv::test::same_coordinates(checkpointed.mesh, reference.mesh));
    check_resumes<pv::LocalSolver>(input, options, copies, reference, 2);
    BOOST_TEST(copies.phase.at(2) == "untangle");
    BOOST_TEST(copies.phase.at(in_shape) == "shape");
}

// Threads and time limits may change between a run and its resumption; the result does not.
BOOST_AUTO_TEST_CASE(threads_and_time_limits_may_change_on_resuming) {
    const StopRequestCleared cleared;
    const pv::test::ScratchDir dir("checkpoint_threads");
    const auto input = pv::test::shared_mesh("mesquite/tets/tire.vtk");
    pv::GlobalSolverOptions options;
    options.termination.max_iterations = 60;
    const auto reference = run<pv::GlobalSolver>(input, options);
    CheckpointCopies copies{dir / "run.ckpt", {{35, dir / "at30.ckpt"}}, {}};
    auto writing = options;
    writing.checkpoint.file = copies.file.string();
    writing.checkpoint.every_iterations = 30;
    writing.threads = 1;
    run<pv::GlobalSolver>(input, writing, copies.observer());
    options.threads = 2;
    options.termination.max_seconds = 1e6;
    options.untangle_termination.max_seconds = 1e6;
    check_resumes<pv::GlobalSolver>(input, options, copies, reference, 1);
}

namespace {

// A valid checkpoint of a short global run on tire, and the options that wrote it.
struct Written {
    pv::test::ScratchDir dir{"checkpoint_refused"};
    pv::Mesh input = pv::test::shared_mesh("mesquite/tets/tire.vtk");
    pv::GlobalSolverOptions options;
    fs::path file = dir / "run.ckpt";
    std::string bytes;

    Written() {
        options.termination.max_iterations = 12;
        options.checkpoint.file = file.string();
        options.checkpoint.every_iterations = 10;
        run<pv::GlobalSolver>(input, options);
        bytes = pv::test::read_text(file);
        options.checkpoint = {};
    }
};

// Resuming from `bytes` throws a FileError whose message has `words`; the mesh is left as it was.
template <class Solver, class Options>
void check_refused(const pv::Mesh& input, Options options, const fs::path& path, const std::string& bytes,
                   const std::string& words) {
    pv::test::write_bytes(path, bytes);
    options.checkpoint.resume = path.string();
    auto mesh = input;
    Solver solver(options);
    BOOST_CHECK_EXCEPTION(solver.improve(mesh), pv::FileError, [&](const pv::FileError& e) {
        BOOST_TEST_MESSAGE(e.what());
        return std::string(e.what()).find(words) != std::string::npos &&
               std::string(e.what()).find(path.string()) != std::string::npos;
    });
    BOOST_TEST(pv::test::same_coordinates(mesh, input));
}

}  // namespace

BOOST_AUTO_TEST_CASE(damaged_checkpoints_are_refused) {
    const Written w;
    const fs::path bad = w.dir / "bad.ckpt";
    using S = pv::GlobalSolver;
    std::string flipped = w.bytes;
    flipped[flipped.size() / 2] ^= 0x10;
    check_refused<S>(w.input, w.options, bad, flipped, "checksum");
    check_refused<S>(w.input, w.options, bad, w.bytes.substr(0, w.bytes.size() - 100), "truncated");
    check_refused<S>(w.input, w.options, bad, "not a checkpoint at all, just some text", "not a Paloverde checkpoint");
    check_refused<S>(w.input, w.options, bad, "", "not a Paloverde checkpoint");
    std::string version = w.bytes;
    version[8] = 7;
    check_refused<S>(w.input, w.options, bad, version, "version 7");
    // A missing file.
    auto options = w.options;
    options.checkpoint.resume = (w.dir / "missing.ckpt").string();
    auto mesh = w.input;
    BOOST_CHECK_THROW(S(options).improve(mesh), pv::FileError);
}

BOOST_AUTO_TEST_CASE(checkpoints_of_another_mesh_solver_or_options_are_refused) {
    const Written w;
    const fs::path path = w.dir / "copy.ckpt";
    // Another mesh, and the same connectivity with one free vertex moved.
    check_refused<pv::GlobalSolver>(pv::test::shared_mesh("mesquite/tets/cube-clip-5.vtk"), w.options, path, w.bytes,
                                    "another mesh");
    auto moved = w.input;
    for (pv::VertexId v = 0; v < moved.num_vertices(); ++v)
        if (!moved.fixed()[v]) {
            moved.coordinates()[3 * v] += 1e-9;
            break;
        }
    check_refused<pv::GlobalSolver>(moved, w.options, path, w.bytes, "another mesh");
    auto fixed = w.input;
    std::vector<std::uint8_t> flags(fixed.fixed().begin(), fixed.fixed().end());
    for (auto& f : flags)
        if (!f) {
            f = 1;
            break;
        }
    fixed.set_fixed(flags);
    check_refused<pv::GlobalSolver>(fixed, w.options, path, w.bytes, "another mesh");
    // Other options, another solver.
    auto options = w.options;
    options.steps_per_mu = 3;
    check_refused<pv::GlobalSolver>(w.input, options, path, w.bytes, "other global solver options");
    options = w.options;
    options.termination.max_iterations = 13;
    check_refused<pv::GlobalSolver>(w.input, options, path, w.bytes, "other global solver options");
    check_refused<pv::LocalSolver>(w.input, pv::LocalSolverOptions{}, path, w.bytes, "written by the global solver");
}

BOOST_AUTO_TEST_CASE(checkpoint_options_are_validated) {
    pv::GlobalSolverOptions options;
    options.checkpoint.every_iterations = -1;
    BOOST_CHECK_THROW(pv::GlobalSolver{options}, pv::OptionError);
    pv::LocalSolverOptions local;
    local.checkpoint.every_seconds = -1.0;
    BOOST_CHECK_THROW(pv::LocalSolver{local}, pv::OptionError);
}

BOOST_AUTO_TEST_SUITE_END()
