// The global solver's entry (GlobalSolver::improve) and solve(), which runs its stages on the
// workspace: untangling where needed (global_untangle.cpp), then the shape stages
// (shape_stages.cpp), each a Phase of the barrier ascent (global_phase.hpp).
#include "paloverde/solvers/global_solver.hpp"

#include <cmath>
#include <optional>
#include <string>

#include "paloverde/core/error.hpp"
#include "boundary_motion.hpp"
#include "checkpointer.hpp"
#include "global_phase.hpp"
#include "run_support.hpp"
#include "sliding_boundary.hpp"
#include "stopping.hpp"
#include "workspace.hpp"

namespace paloverde {

void GlobalSolverOptions::validate() const {
    if (!(smallest_motion_step > 0.0 && smallest_motion_step <= 1.0))
        throw OptionError("smallest_motion_step must be in (0, 1] (got " + std::to_string(smallest_motion_step) + ")");
    objective_options.validate();
    metric_options.validate();
    termination.validate();
    untangle_termination.validate();
    const auto made = make_objective(objective, objective_options);
    auto metric = make_metric(shape_metric, metric_options);
    if (!metric->has_gradient())
        throw OptionError("shape_metric '" + shape_metric + "' has no gradient; choose aspect_ratio, mean_ratio, "
                          "inverse_condition or edge_ratio");
    if (threads < 0) throw OptionError("threads must be >= 0 (0: the OpenMP default)");
    if (steps_per_mu < 1) throw OptionError("steps_per_mu must be >= 1");
    if (!(gain_tolerance >= 0.0) || !std::isfinite(gain_tolerance))
        throw OptionError("gain_tolerance must be a number >= 0 (0: mu shrinks after steps_per_mu steps)");
    if (!(focus_band > 0.0 && focus_band <= 1.0)) throw OptionError("focus_band must be in (0, 1]");
    if (!(finish_band > 0.0 && finish_band <= 1.0)) throw OptionError("finish_band must be in (0, 1]");
    if (!(newton_tolerance > 0.0) || !std::isfinite(newton_tolerance))
        throw OptionError("newton_tolerance must be a positive number");
    if (newton_cg_iterations < 1) throw OptionError("newton_cg_iterations must be >= 1");
    if (direction == Direction::Newton && improve_shape && !made->is_continuation())
        throw OptionError("direction newton needs the log_barrier objective (its curvature), not '" + objective + "'");
    if (local_untangle_rounds < 0) throw OptionError("local_untangle_rounds must be >= 0");
    if (max_failed_searches < 1) throw OptionError("max_failed_searches must be >= 1");
    surface.validate();
    if (boundary == Boundary::Slide && direction == Direction::Newton)
        throw OptionError("direction newton does not go with boundary: slide yet (its Hessian solves know nothing "
                          "of the surface the boundary slides on); use conjugate_gradient or steepest_ascent");
    checkpoint.validate();
}
namespace {

using detail::PhaseContext;
using detail::PhaseResult;

// Everything that changes the result, for the checkpoint's fingerprint.
std::string options_text(const GlobalSolverOptions& o) {
    detail::OptionsText t;
    const char* direction = o.direction == GlobalSolverOptions::Direction::SteepestAscent ? "steepest_ascent"
                            : o.direction == GlobalSolverOptions::Direction::Newton       ? "newton"
                                                                                          : "conjugate_gradient";
    t("direction", direction)
        ("objective", o.objective)("barrier_shrink", o.objective_options.barrier_shrink)
        ("initial_mu", o.objective_options.initial_mu)("barrier_initial_active", o.objective_options.barrier_initial_active)
        ("p", o.objective_options.p)("shape_metric", o.shape_metric)("hybrid_sharpness", o.metric_options.hybrid_sharpness)
        ("untangle", o.untangle)("improve_shape", o.improve_shape)("termination", o.termination)
        ("untangle_termination", o.untangle_termination)("precondition_untangling", o.precondition_untangling)
        ("untangling", o.untangling == GlobalSolverOptions::Untangling::Energy ? "energy" : "barrier")
        ("local_untangle_rounds", o.local_untangle_rounds)("steps_per_mu", o.steps_per_mu)
        ("gain_tolerance", o.gain_tolerance)("damped_vertex_ascent", o.damped_vertex_ascent)
        ("max_failed_searches", o.max_failed_searches)("renumber", o.renumber);
    if (o.focus_band < 1.0) t("focus_band", o.focus_band);
    if (o.polish != GlobalSolverOptions::Polish::Auto)
        t("polish", o.polish == GlobalSolverOptions::Polish::Off ? "off" : "always");
    const bool finish = o.finish == GlobalSolverOptions::Finish::Newton;
    if (finish) t("finish", "newton")("finish_band", o.finish_band);
    if (o.direction == GlobalSolverOptions::Direction::Newton || finish)
        t("newton_tolerance", o.newton_tolerance)("newton_cg_iterations", o.newton_cg_iterations);
    return t.text();
}

// Untangling (when needed) and shape improvement on the workspace, the result handed back to the
// part; returns why the run ended, for the caller to finish the run once the workspace is gone
// (the result's report then reuses the memory the workspace held). With `sliding`, its vertices slide in
// the shape phase (and, on a surface mesh, untangling).
detail::PhaseResult solve(const GlobalSolverOptions& options, const IterationObserver& observer, detail::SolverRun& run,
                          detail::Workspace& work, detail::Checkpointer& checkpointer,
                          const detail::SlidingBoundary* sliding) {
    Summary& summary = run.summary;
    // A resumed run enters the stage (and untangling round) it was checkpointed in.
    std::optional<detail::SolverState> resume;
    if (checkpointer.resumes()) resume = checkpointer.resume(summary, run);
    const bool resume_untangling = resume && resume->number("untangling") != 0.0;
    const PhaseContext context{work, options, summary, observer, run.start(), checkpointer};
    std::vector<double> xyz(work.mesh().coordinates().begin(), work.mesh().coordinates().end());

    PhaseResult result{TerminationReason::TargetReached, ""};
    const bool tangled = summary.before.inverted - summary.before.inverted_frozen > 0 || summary.before.degenerate > 0;
    if (tangled && options.untangle && (!resume || resume_untangling)) {
        // Only a surface mesh is tangled with its vertices sliding: a volume mesh slides from the
        // valid mesh its boundary-fixed run left.
        result = detail::untangle(context, xyz, sliding, resume);
        if (result.reason != TerminationReason::TargetReached) {
            work.hand_back(xyz);
            return result;
        }
    }
    if (resume && resume_untangling)
        throw FileError(resume->source, 0, "this checkpoint is of an untangling phase, but the mesh needs none");
    const bool still_tangled = !options.untangle && tangled;
    if (options.improve_shape && !still_tangled)
        result = detail::improve_shape(context, xyz, sliding, resume, std::move(result));
    else if (resume)
        throw FileError(resume->source, 0, "this checkpoint is of a shape phase, which this run does not have");
    work.hand_back(xyz);
    if (result.reason == TerminationReason::Interrupted || result.reason == TerminationReason::NumericalFailure)
        return result;
    if (summary.before.inverted_frozen > 0)
        return {TerminationReason::CannotUntangle, std::to_string(summary.before.inverted_frozen) +
                                                       " inverted elements have all their vertices fixed; no smoother can move them"};
    if (still_tangled) return {TerminationReason::CannotUntangle, "the mesh is tangled and untangling was turned off"};
    return result;
}

// One run on the part, with the boundary sliding (`sliding`) or not (nullptr); `shared`: the
// run's reports, for the solver's one run (Solver::shared_reports).
Summary improve_part(const GlobalSolverOptions& options, const IterationObserver& observer, MeshPart part,
                     detail::SlidingBoundary* sliding, SharedReports shared = {}) {
    const std::string name = "global";
    detail::SolverRun run(part, name, options.shape_metric, shared);
    if (sliding) sliding->set_scale_exponent(run.scale_exponent());
    if (auto nothing = run.nothing_to_move()) return *nothing;
    // A run whose vertices slide depends on the surface they keep to.
    const std::string surface = sliding ? detail::OptionsText()("surface", options.surface).text() : "";
    detail::Checkpointer checkpointer(options.checkpoint, name, options_text(options) + surface, part);
    // The dihedral quality's six angles are terms of their own (docs/metrics.md): at a tie of two
    // angles the smaller one alone is a kink where the ascent stalls.
    const Mesh& mesh = part.mesh();
    const bool angle_terms = options.improve_shape && options.shape_metric == "dihedral_sine" &&
                             mesh.kind() == ElementKind::Tetrahedron && !mesh.has_cells();
    detail::PhaseResult ending = [&] {
        detail::Workspace work(part, options.renumber, angle_terms);
        return solve(options, observer, run, work, checkpointer, sliding);
    }();
    return run.finish(ending.reason, std::move(ending.message));
}

// Whether the shape phases move only the vertices near the worst elements (Newton directions
// always take every vertex).
bool focuses(const GlobalSolverOptions& o) {
    return o.focus_band < 1.0 && o.direction != GlobalSolverOptions::Direction::Newton;
}

// A surface mesh: one run with every vertex sliding on the input surface (free moves in space
// would leave it), untangling what the input turned over first. Newton directions are refused:
// their Hessian solves know nothing of it.
Summary improve_surface(const GlobalSolverOptions& options, const IterationObserver& observer, MeshPart part) {
    if (options.direction == GlobalSolverOptions::Direction::Newton)
        throw OptionError("direction newton does not go with surface meshes (its Hessian solves know nothing of the "
                          "surface); use conjugate_gradient or steepest_ascent");
    GlobalSolverOptions run = options;
    // A surface's worst triangle often sits at a corner of its creases, where the max-min can do
    // little and so leaves every other triangle as it was: the mean is raised after it.
    if (run.polish == GlobalSolverOptions::Polish::Auto) run.polish = GlobalSolverOptions::Polish::Always;
    const bool open_edges_slide = options.boundary == GlobalSolverOptions::Boundary::Slide;
    return detail::on_surface(part, options.surface, open_edges_slide,
                              [&](detail::SlidingBoundary* sliding) { return improve_part(run, observer, part, sliding); });
}

}  // namespace

GlobalSolver::GlobalSolver(GlobalSolverOptions options) : options_(std::move(options)) { options_.validate(); }

Summary GlobalSolver::improve(MeshPart part) {
    detail::ThreadScope threads(options_.threads);
    detail::check_domain(part, options_.surface.domain, options_.boundary == GlobalSolverOptions::Boundary::Slide);
    if (options_.untangle && detail::has_boundary_motion(part)) {
        // The time limit bounds the steps together: each run gets what is left of it.
        return detail::follow_boundary_motion(part, options_.smallest_motion_step, options_.termination.max_seconds,
                                              {options_.checkpoint, "global", options_text(options_)},
                                              [&](double seconds, const CheckpointOptions& checkpoint,
                                                  detail::MotionRunKind kind) {
                                                  GlobalSolverOptions each =
                                                      detail::for_motion_run(options_, kind, checkpoint, seconds);
                                                  if (kind == detail::MotionRunKind::First)
                                                      each.finish = GlobalSolverOptions::Finish::None;
                                                  // Newton steps on every vertex cost many passes each;
                                                  // sliding vertices stay where the motion's runs slid them
                                                  // (the boundary made of them is no longer the moved one).
                                                  if (kind == detail::MotionRunKind::EveryVertex) {
                                                      each.focus_band = 1.0;
                                                      each.finish = GlobalSolverOptions::Finish::None;
                                                      each.boundary = GlobalSolverOptions::Boundary::Fixed;
                                                  }
                                                  GlobalSolver within(each);
                                                  within.set_observer(observer());
                                                  return within.run_once(part);
                                              },
                                              focuses(options_) && !detail::is_surface_mesh(part));
    }
    return run_once(part);
}

Summary GlobalSolver::run_once(MeshPart part) {
    if (detail::is_surface_mesh(part)) return improve_surface(options_, observer(), part);
    if (options_.boundary != GlobalSolverOptions::Boundary::Slide)
        return improve_part(options_, observer(), part, nullptr, shared_reports());
    // The sliding run is a shape phase from the valid mesh the first run left: untangling would
    // not keep the boundary on the surface.
    return detail::fixed_then_sliding(part, options_.surface, options_.termination, options_.improve_shape,
                                      {options_.checkpoint, "global", options_text(options_)},
                                      [&](const TerminationCriterion& budget, detail::SlidingBoundary* sliding,
                                          const CheckpointOptions& checkpoint) {
                                          GlobalSolverOptions run = options_;
                                          run.termination = budget;
                                          run.checkpoint = checkpoint;
                                          if (sliding) run.untangle = false;
                                          return improve_part(run, observer(), part, sliding);
                                      });
}

}  // namespace paloverde
