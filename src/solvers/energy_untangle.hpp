#pragma once
// Global untangling by the regularized energy of Garanzha et al. (foldover-free maps, 2021): all
// free vertices minimize sum_e f_eps(J_e) together (limited-memory BFGS), and eps shrinks as the
// worst element rises, so that the energy turns into a barrier against inversion. Unlike the
// barrier ascent on the hybrid metric, nothing here needs a valid start or a feasible step: the
// energy is finite on any tangle, which is what frees tangles where the ascent stalls.
#include <string>
#include <vector>

#include "paloverde/solvers/solver.hpp"
#include "paloverde/solvers/summary.hpp"
#include "checkpointer.hpp"
#include "run_support.hpp"
#include "sliding_vertices.hpp"
#include "workspace.hpp"

namespace paloverde::detail {

struct EnergyUntangling {
    TerminationReason reason = TerminationReason::CannotUntangle;  // target_reached: untangled
    std::string message;
};

// Moves `xyz` (the workspace's order; ghosts follow their owners) and ends on the best iterate
// seen: fewest non-positive elements, then the largest smallest volume. At most `max_iterations`
// steps, each counted in the summary as an untangling iteration; collective over the workspace's
// processes, with the same steps on any number of them. Writes checkpoints (state "energy") as
// the checkpointer says and at a stop request; `resume` continues from one. With `sliding` (a
// surface mesh), its vertices step along their patches or curves, each trial projected back
// onto them, and none moves more than one reference length a step.
EnergyUntangling energy_untangle(Workspace& work, std::vector<double>& xyz, int max_iterations, double max_seconds,
                                 Summary& summary, const IterationObserver& observer, Clock::time_point start,
                                 Checkpointer& checkpointer, const SolverState* resume,
                                 const SlidingVertices* sliding = nullptr);

}  // namespace paloverde::detail
