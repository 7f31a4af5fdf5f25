#pragma once
// Checkpoints of a long solver run, and resuming from one.
//
// With `file` set, the global and local solvers write their whole state there every
// `every_iterations` iterations (sweeps) and every `every_seconds` seconds, and once more when a
// stop is requested (stop.hpp): the coordinates, the phase and iteration, the barrier's mu and t,
// the step length, the conjugate-gradient state, the best iterate, the history and the counters.
// A run with `resume` set starts from such a file and ends exactly as the run that wrote it
// would have (bit for bit; the only thing that differs is the wall time). The file is binary,
// with a version and a checksum, and is written to a temporary and renamed, so a run killed
// while writing leaves the previous checkpoint intact. A distributed run writes one file from
// rank 0 holding every vertex by global id; it resumes on the same number of ranks.
//
// A run that follows a moved boundary in steps (Mesh::reference_coordinates, docs/morphing.md)
// writes the motion's state to `file` before each of its runs, and the run under way writes its
// own to `file` + ".run"; resuming goes on from both, to the same end. A run whose boundary
// slides (boundary: slide, two runs) does the same for its two runs, and a motion whose runs
// slide nests the two (`file`, ".run", ".run.run"). A run whose vertices slide fingerprints the
// surface's options too.
//
// A checkpoint records fingerprints of the mesh (connectivity, fixed flags, input coordinates)
// and of the solver's options (all but `threads`, time limits and these checkpoint settings):
// resuming on another mesh or with other options is refused with a FileError that says which.
#include <string>

namespace paloverde {

struct CheckpointOptions {
    std::string file;          // where to write checkpoints; empty: none
    int every_iterations = 0;  // 0: not by iteration count
    double every_seconds = 300.0;  // 0: not by time
    std::string resume;        // a checkpoint to continue from; empty: start afresh

    void validate() const;  // throws OptionError naming the field
};

}  // namespace paloverde
