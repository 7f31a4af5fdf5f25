#pragma once
// Writing and reading the checkpoints of CheckpointOptions (include/paloverde/solvers/checkpoint.hpp).
//
// The file: a 32-byte header, then the content.
//   bytes 0-7    "PALOVCKP"
//   bytes 8-15   format version (1)
//   bytes 16-23  length of the content in bytes
//   bytes 24-31  64-bit FNV-1a hash of the content (a checksum)
// All numbers are little-endian 64-bit (integers unsigned or two's complement, doubles IEEE).
// The content: the solver's name (with "/motion" after it for a run that follows a moved boundary
// in steps), the fingerprints of the mesh and of the options, the number of ranks and of
// vertices, the elapsed seconds, the Summary's counters and history, then the solver's state by
// name: numbers, lists (texts among them, as lists of character codes named "text:" and the
// text's name), and vertex fields of 3 doubles per vertex indexed by the vertex's key (global id
// in a distributed run, the solver's own numbering serially).
#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "paloverde/mesh/boundary_surface.hpp"
#include "paloverde/mesh/mesh.hpp"
#include "paloverde/parallel/mesh_part.hpp"
#include "paloverde/parallel/reducer.hpp"
#include "paloverde/solvers/checkpoint.hpp"
#include "paloverde/solvers/summary.hpp"
#include "paloverde/solvers/termination.hpp"
#include "run_support.hpp"

namespace paloverde::detail {

class CheckpointWriter;

// What a solver needs to continue from an iteration boundary, by name. Vertex fields hold 3
// doubles per local vertex; only the owned vertices' values are written, and on reading every
// local vertex (ghosts too) gets its owner's.
struct SolverState {
    std::map<std::string, double> numbers;
    std::map<std::string, std::vector<double>> lists;
    std::map<std::string, std::vector<double>> vertex_fields;
    std::map<std::string, std::string> texts;
    std::string source;    // the file it was read from, for messages
    double elapsed = 0.0;  // the run's seconds when it was written

    // Each throws a FileError naming the file when the entry is missing or has the wrong size.
    double number(const std::string& name) const;
    const std::vector<double>& list(const std::string& name) const;
    const std::vector<double>& vertex_field(const std::string& name, std::size_t local_vertices) const;
    const std::string& text(const std::string& name) const;
};

// A Summary's outcome (solver, metric, reason, message, the reports and worst qualities before
// and after, how far a sliding boundary moved; not its counters or history) as entries of `state`
// named after `prefix`, and back: what a run in steps keeps of its first run, and of the followed
// motion before its every-vertex run.
void store_outcome(SolverState& state, const std::string& prefix, const Summary& summary);
Summary restored_outcome(const SolverState& state, const std::string& prefix);
// `from`'s work (counters and history) in place of `into`'s.
void take_work(Summary& into, Summary&& from);

// A single solver run, a run that follows a moved boundary in steps (boundary_motion.hpp), or a
// run whose boundary slides (sliding_boundary.hpp: the boundary fixed, then sliding): each
// resumes only its own kind.
enum class CheckpointKind { SingleRun, Motion, Sliding };

// Options of one solver as text (every field that changes the result), for the fingerprint.
class OptionsText {
public:
    OptionsText& operator()(const char* key, double value);
    OptionsText& operator()(const char* key, const std::string& value);
    OptionsText& operator()(const char* key, const char* value) { return (*this)(key, std::string(value)); }
    // Every field but max_seconds (a time limit may change between a run and its resumption).
    OptionsText& operator()(const char* key, const TerminationCriterion& t);
    // The surface sliding vertices keep to: what a run in which they slide depends on too.
    OptionsText& operator()(const char* key, const SurfaceOptions& s);
    const std::string& text() const { return text_; }

private:
    std::string text_;
};

class Checkpointer {
public:
    // `part`: the solver's part at the start of the run (serially the whole mesh; a distributed
    // part's vertices are identified by their global ids). Collective on a distributed part when
    // checkpoints are written or read. A motion's fingerprint of the mesh includes its reference
    // coordinates.
    Checkpointer(const CheckpointOptions& options, std::string solver, const std::string& options_text, MeshPart part,
                 CheckpointKind kind = CheckpointKind::SingleRun);

    bool writes() const { return !options_.file.empty(); }
    bool resumes() const { return !options_.resume.empty(); }

    // Reads options.resume, checks it belongs to this mesh, solver and options, restores the
    // summary's counters and history and the clock (elapsed seconds), and returns the state.
    // Throws FileError for a missing, corrupt or mismatched file (on every rank).
    SolverState resume(Summary& summary, SolverRun& run);
    // The same without a SolverRun: the elapsed seconds are the state's.
    SolverState resume(Summary& summary);

    // Whether a checkpoint is due after `iterations` (the same answer on every rank).
    bool due(int iterations);
    // Writes the checkpoint (collective); `elapsed` is the run's seconds so far.
    void save(const Summary& summary, const SolverState& state, double elapsed);

private:
    void encode(CheckpointWriter& w, const Summary& summary, const SolverState& state, double elapsed) const;
    const Reducer& reducer() const { return part_.reducer(); }

    CheckpointOptions options_;
    std::string solver_;
    CheckpointKind kind_;
    std::uint64_t mesh_hash_ = 0, options_hash_ = 0;
    MeshPart part_;
    std::vector<GlobalId> keys_;        // per local vertex
    std::uint64_t vertices_ = 0;        // over all processes
    int saved_iterations_ = 0;          // at the last checkpoint written or read
    Clock::time_point saved_at_;
};

// A solver's checkpoint settings, its name and its options as text (the fingerprint), for a run
// made of runs.
struct CheckpointSettings {
    CheckpointOptions options;
    std::string solver;
    std::string options_text;
};

// The checkpoints of a run made of solver runs one after another (a motion's first run and
// steps; a sliding run's boundary-fixed run and sliding one): the whole's own in FILE, written
// before each run, and the run under way's in FILE.run, written as a single run writes its own
// (every_iterations, every_seconds, at a stop). A run's checkpoint is forgotten (removed) before
// the whole's next one is written, so one found beside the whole's belongs to the run that
// checkpoint was written before. Collective.
class RunCheckpoints {
public:
    RunCheckpoints(MeshPart part, const CheckpointOptions& whole);
    // The options of the next run: its file beside the whole's; the first run after the whole
    // resumed goes on from the checkpoint beside the one it resumed from, if there is one.
    CheckpointOptions next_run();
    // Whether the whole's checkpoint is to be written now: it writes checkpoints, and not over the
    // one it resumed from while the run resumed beside it has yet to read its own.
    bool writes_now() const { return !whole_.file.empty() && !(run_pending_ && same_file_); }
    // Removes the run's checkpoint (before the whole's next one is written).
    void forget() const;

private:
    static constexpr const char* kSuffix = ".run";
    CheckpointOptions whole_;
    bool root_, run_pending_, resumable_ = false, same_file_ = false;
};

}  // namespace paloverde::detail
