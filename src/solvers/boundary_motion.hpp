#pragma once
// Morphing: a mesh whose boundary moved away from its reference (undeformed) position
// (Mesh::reference_coordinates) while the interior stayed behind. The interior is carried along
// (a harmonic extension of the boundary's displacement) and a solver that untangles runs once;
// when that fails or loses too much quality, it starts again from the reference, which is valid,
// and moves the boundary there in fractions of the whole motion (the classic incremental scheme),
// each fraction carried, untangled and improved before the next, its size chosen as it goes:
// halved when a fraction fails, doubled after one that is kept (unless it followed a failed one:
// docs/morphing.md).
#include <algorithm>
#include <functional>
#include <string>
#include <utility>

#include "paloverde/parallel/mesh_part.hpp"
#include "paloverde/solvers/checkpoint.hpp"
#include "paloverde/solvers/summary.hpp"
#include "paloverde/solvers/termination.hpp"
#include "checkpointer.hpp"

namespace paloverde::detail {

// The part carries a motion: reference coordinates from which a vertex that does not move
// freely (fixed, or sliding on the boundary) has moved. Collective.
bool has_boundary_motion(MeshPart part);

// Which run of a motion a MotionRun is, for its budget.
//   First: the run from the whole motion at once, which steps replace when it leaves inverted
//     elements or a poor worst element. It skips the solver's finishing stage (the global
//     solver's Newton finish, whose iterations cost many shape iterations each), work that steps
//     would throw away; a first run that is kept ends where its shape phase stops (an every-vertex
//     run may follow). Its untangling gets first_run_untangling of the solver's budget.
//   Step: a step short of the end, whose mesh is only where the next step starts from. Its shape
//     phase gets step_improvement of the budget; the last step raises the worst element.
//   Last: a step that reaches the end of the motion, or the run from the furthest valid step: the
//     whole budget.
//   EveryVertex: the run from a followed motion's mesh (follow_boundary_motion's
//     every_vertex_run): the whole budget, every free vertex moving in every iteration.
enum class MotionRunKind { First, Step, Last, EveryVertex };

// One whole run of a solver on the part, its time limit `seconds` (0: the solver's own), with
// `checkpoint` for its own checkpoints (not the solver's: the motion gives each run a file of its
// own).
using MotionRun = std::function<Summary(double seconds, const CheckpointOptions& checkpoint, MotionRunKind kind)>;

// The untangling budget (iterations, or sweeps) of a motion's first run, from the solver's: a fifth
// of it. Untangling that takes longer marks a motion too large for one run, which the steps follow
// sooner than a first run that uses the whole budget and fails; a motion that no step follows
// either goes on from the first run with the whole budget (follow_boundary_motion).
constexpr int first_run_untangling(int budget) { return std::max(1, budget / 5); }

// The shape budget (iterations, or sweeps) of a step short of the end, from the solver's: a fifth
// of it, but no fewer than 50 (or the whole budget where it is smaller). A step's mesh is only the
// next step's start: a few iterations leave it too poor to untangle from, and the rest of the
// budget would buy quality that the next step's motion undoes.
constexpr int step_improvement(int budget) { return std::min(budget, std::max(budget / 5, 50)); }

// Runs `solve` (one whole run of a solver on the part; from the interior carried along when that
// inverts fewer elements than the interior as given) and, if it leaves inverted elements or less
// than half the reference's worst quality, follows the motion in steps down to
// `smallest_fraction` of it, a step accepted when it leaves a valid mesh with at least half the
// worst quality of the step before (any valid one at the smallest step); the better of the first
// run and the steps is kept. A motion that cannot be followed ends with the boundary where it was
// given and the fewer inverted elements of the first run and of a last run from the furthest
// valid step (from the first run's mesh when no step was valid), reason CannotUntangle and a
// message that says how far the motion was followed.
// With `every_vertex_run`, for a solver whose runs move only the vertices near the worst elements,
// a motion that was followed goes on with one more run from its mesh (MotionRunKind::EveryVertex):
// the motion distorts the whole region around the moved boundary, and its best shape spreads the
// distortion over all of it, which those runs leave undone.
// `max_seconds` (0: none) bounds the runs together: each gets what is left (the slowest
// process's clock decides), and once it is spent the first run's mesh is handed back, reason
// TimeLimit. One Summary of every run: before is the mesh as given.
// With a checkpoint file FILE (`checkpoints`, whose fingerprint takes smallest_motion_step too),
// the motion's state is written there before the first run, before every step (what the first run
// left, the last accepted step's mesh, the fraction reached, the step size, the Summary so far) and
// before the every-vertex run (the followed motion's mesh and outcome), and the run under way
// writes its own to FILE.run (RunCheckpoints). With resume, the motion goes on from its checkpoint,
// the run it was written before from that run's own if there is one, and it ends as the
// uninterrupted run, bit for bit. Collective.
Summary follow_boundary_motion(MeshPart part, double smallest_fraction, double max_seconds,
                               const CheckpointSettings& checkpoints, const MotionRun& solve, bool every_vertex_run);

// A solver's options with its time limits (shape and untangling) at most `seconds`, > 0.
template <class Options>
Options within_seconds(Options options, double seconds) {
    for (TerminationCriterion* t : {&options.termination, &options.untangle_termination})
        t->max_seconds = t->max_seconds > 0.0 ? std::min(t->max_seconds, seconds) : seconds;
    return options;
}

// A solver's options for one run of a motion: its checkpoint settings, its budgets
// (MotionRunKind) and its time limit `seconds` (0: the solver's own).
template <class Options>
Options for_motion_run(Options each, MotionRunKind kind, const CheckpointOptions& checkpoint, double seconds) {
    each.checkpoint = checkpoint;
    if (kind == MotionRunKind::First)
        each.untangle_termination.max_iterations = first_run_untangling(each.untangle_termination.max_iterations);
    if (kind == MotionRunKind::Step)
        each.termination.max_iterations = step_improvement(each.termination.max_iterations);
    return seconds == 0.0 ? each : within_seconds(std::move(each), seconds);
}

}  // namespace paloverde::detail
