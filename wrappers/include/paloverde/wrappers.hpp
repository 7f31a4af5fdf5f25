#pragma once
// Ready-made instruction queues for the everyday jobs (Mesquite's wrappers): each assesses the
// mesh, runs its improver(s) and assesses again. Tune the parts through the options structs; run
// with `queue.run(mesh)`. A run config names them the same (`queue: untangle_then_improve`, or a
// `wrapper:` step with the options of the solver; docs/config.md).
#include "paloverde/solvers/global_solver.hpp"
#include "paloverde/solvers/instruction_queue.hpp"
#include "paloverde/solvers/laplace_solver.hpp"
#include "paloverde/solvers/local_solver.hpp"

namespace paloverde::wrappers {

// Untangle only (global log-barrier on the hybrid metric): stops once no element is inverted.
InstructionQueue untangle(GlobalSolverOptions options = {});
// Raise the worst element of a valid mesh with the global log-barrier solver.
InstructionQueue shape_improvement(GlobalSolverOptions options = {});
// The same job with the local Freitag-Plassmann smoother.
InstructionQueue local_shape_improvement(LocalSolverOptions options = {});
// Smart Laplace by default; plain Laplace (options.smart = false) may invert elements.
InstructionQueue laplace(LaplaceSolverOptions options = {});
// Untangle, then improve the shape, each with the global solver: the default job.
InstructionQueue untangle_then_improve(GlobalSolverOptions options = {});

// Jobs with targets (metrics/targets.hpp), set from the mesh as the queue starts; the global solver
// (untangling first where needed) then rates with the metric the targets ask for (shape_size, or
// shape_size_orient where orientation is kept: options.shape_metric is replaced by it).
//
// Mesquite's size-adapt shape job: every element keeps its size, its shape is made ideal. For a
// graded mesh whose sizes were designed (refined near a feature, coarse far away).
InstructionQueue size_adapt_shape(GlobalSolverOptions options = {});
// An anisotropic (boundary-layer) mesh: every element keeps its size, aspect and orientation, its
// angles are made ideal (Mesquite's viscous-CFD job for tetrahedra; the same for hexahedra,
// wedges and quadrilaterals, whose ideal angles are right angles). The layers keep their heights.
InstructionQueue boundary_layer_shape(GlobalSolverOptions options = {});
// Mesquite's deforming-domain job (morphing): a mesh whose boundary moved away from its reference
// coordinates (Mesh::set_reference_coordinates: the undeformed mesh) with the interior left
// behind. Every element is pulled toward the size, aspect and skew it has in the reference, not its
// orientation (the motion turns elements); the motion is followed in steps where one run does not
// untangle (options.smallest_motion_step). Throws OptionError on a mesh without reference
// coordinates.
InstructionQueue deforming_domain(GlobalSolverOptions options = {});

}  // namespace paloverde::wrappers
