#pragma once
// Runs a RunSpec: reads the input, runs each method's queue on its own copy of the mesh, writes
// the outputs (each through a temporary file and a rename) and says how it went.
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "paloverde/config/config.hpp"
#include "paloverde/solvers/instruction_queue.hpp"

namespace paloverde::config {

// Exit codes of `paloverde run` and `paloverde improve`.
enum class RunStatus {
    Done = 0,             // every improver succeeded and every target was reached
    Failed = 1,           // an improver failed (could not untangle, nothing to move)
    TargetNotReached = 3, // finished with a valid mesh, but a target_worst_quality was not reached
    Interrupted = 4       // a stop was requested (SIGINT, SIGTERM); the best mesh so far was written
};
std::string_view to_string(RunStatus status);

struct MethodResult {
    std::string name;
    RunStatus status = RunStatus::Done;
    std::string message;   // why it failed or missed its target
    QueueResult queue;     // each step's report or summary
    std::string metric;    // output.metric: what the numbers below measure
    QualityReport before, after;  // the whole mesh before and after the queue
    double worst_before = 0.0, worst_after = 0.0;  // smallest `metric` over elements with a free vertex
    double mean_before = 0.0, mean_after = 0.0;    // mean `metric` over all elements
    double seconds = 0.0;  // the queue's wall time
    int iterations = 0, untangle_iterations = 0;   // over its improvers
    std::string mesh_written;  // "" if output.mesh is not set
};

// How a partitioned run got its mesh onto the ranks and what the exchange moves: the paper's
// numbers (docs/parallel.md), the same on every rank. Seconds are those of rank 0
// or, for solve and write, of the slowest rank.
struct ParallelReport {
    int ranks = 1;
    std::string exchange;          // "colored" or "root_relayed"
    bool from_pieces = false;      // the ranks read pieces (else rank 0 read and split input.mesh)
    double read_seconds = 0.0;     // rank 0 reading input.mesh; from pieces: reading, checking and building the parts
    double partition_seconds = 0.0;   // canonical order and METIS (0 from pieces)
    double distribute_seconds = 0.0;  // sending each rank its part and building it there (0 from pieces)
    double schedule_seconds = 0.0;    // process graph, edge coloring, send and receive lists
    double solve_seconds = 0.0;    // every method's queue, with its reports before and after
    double write_seconds = 0.0;    // output.mesh (gathered or pieces) and output.pieces
    std::int64_t vertices = 0, elements = 0;  // of the whole mesh
    std::int64_t ghost_copies = 0;  // ghost values received per exchange, summed over ranks
    std::int64_t messages = 0;      // point-to-point messages per exchange, summed over ranks
    int colors = 0;                 // rounds of the colored exchange
    // Rank 0 and the whole mesh: "kept" (read from input.mesh and kept through the run, to write
    // output.mesh as one file), "dropped" (read, then dropped after the scatter), "gathered"
    // (from pieces: built from the parts only to write output.mesh), "never" (from pieces).
    std::string whole_mesh_on_rank_0;
};

struct RunResult {
    std::string input;
    ElementKind kind = ElementKind::Tetrahedron;
    // How the input's element order was taken (input.orientation): whether it was flipped and why.
    OrientationDecision orientation;
    std::vector<MethodResult> methods;
    RunStatus status = RunStatus::Done;  // the worst over methods: Interrupted, Failed, then TargetNotReached
    std::optional<ParallelReport> parallel;  // set by a partitioned run

    int exit_code() const { return static_cast<int>(status); }
    // Text: the input's orientation when it is news (flipped, forced, or undecided), per method its
    // steps, then a comparison for a study.
    std::string report() const;
    // Run keys ("input_orientation": mode, flipped, sign, share, oriented), "methods": [...]; one
    // method's keys also at the top; a partitioned run adds
    // "parallel" (ranks, exchange, colors, ghost_copies, messages_per_exchange, seconds: read,
    // partition, distribute, schedule, solve, write), as paloverde_parallel_benchmark prints them.
    std::string to_json() const;
    std::string table_csv() const;    // one row per method
    std::string history_csv() const;  // method, improver (its label), then Summary::history_csv's columns
};

struct RunHooks {
    // Each recorded iteration of every improver (progress lines); must not throw.
    std::function<void(std::string_view method, std::string_view step, const IterationRecord&)> on_iteration;
    // When a method's queue has finished.
    std::function<void(const MethodResult&)> on_method_done;
};

// How the input's element order was taken, as the summary's "input_orientation" object (JSON
// text): mode, flipped, oriented, sign, share. `paloverde quality --json` prints the same.
std::string to_json(const OrientationDecision& orientation);

// The queue the steps describe; each solver uses `threads`.
InstructionQueue build_queue(std::span<const StepSpec> steps, int threads = 0);

// Checks the spec (check_runnable), runs every method and writes the outputs. Throws ConfigError
// for a config that cannot run, FileError / MeshError for unreadable input or unwritable output.
//
// A partitioned spec (RunSpec::partitioned()), or any spec while MPI_COMM_WORLD has more than
// one rank, runs over MPI_COMM_WORLD: it is collective, MPI must be initialized, every rank
// passes the same spec and gets the same result (but for the solvers' own clocks) and the same
// exceptions, and rank 0 writes the files other than pieces. Hooks are called on every rank
// that passes them. A build without MPI (PALOVERDE_MPI=OFF) refuses a partitioned spec (ConfigError).
RunResult run(const RunSpec& spec, const RunHooks& hooks = {});
// Whether run(spec) runs over MPI_COMM_WORLD, as just said: the one place that decides it.
bool runs_distributed(const RunSpec& spec);
// The same on a mesh already in memory (the Python package's improve): `input` is not read (the
// mesh's own fixed vertices stay), targets are set for the run as for a file and the mesh's own
// put back after it, the last method's result is left in `mesh` (a study's methods each start
// from the input), output.mesh and the reports are written if set. Serial only: a partitioned
// spec, or a call under mpirun with more than one rank, throws ConfigError.
RunResult run(Mesh& mesh, const RunSpec& spec, const RunHooks& hooks = {});

}  // namespace paloverde::config
