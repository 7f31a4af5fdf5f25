// The global solver's entry (GlobalSolver::improve) and the order of its stages: untangling
// (energy, barrier ascent and local rounds), then the shape stages (shape phase, Newton finish,
// mean's polish). Each stage is a Phase (global_phase.hpp).
#include "paloverde/solvers/global_solver.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>

#include "paloverde/core/error.hpp"
#include "paloverde/solvers/vertex_coloring.hpp"
#include "checkpointer.hpp"
#include "energy_untangle.hpp"
#include "global_phase.hpp"
#include "local_untangle.hpp"
#include "run_support.hpp"
#include "sliding_boundary.hpp"
#include "sliding_vertices.hpp"
#include "stopping.hpp"
#include "workspace.hpp"

namespace paloverde {

void GlobalSolverOptions::validate() const {
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
    if (boundary == Boundary::Slide) {
        detail::validate_sliding(checkpoint);
        if (direction == Direction::Newton)
            throw OptionError("direction newton does not go with boundary: slide yet (its Hessian solves know nothing "
                              "of the surface the boundary slides on); use conjugate_gradient or steepest_ascent");
    }
    checkpoint.validate();
}
namespace {

using detail::Clock;
using detail::PhaseContext;
using detail::PhaseResult;
using detail::Phase;
using detail::Stage;
using detail::StageKind;
using detail::seconds_since;

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

// Where the barrier ascent stalls with elements inverted: sweeps of local untangling (Freitag &
// Plassmann) that move each free vertex of an element non-positive at the sweep's start, its
// neighbours held still, to where its elements' smallest volume is largest; until a sweep moves
// none, at most ten. Serially the vertices go one after the other in id order; a distributed run
// goes color by color (`coloring`, from the global ids: the same moves on any number of ranks),
// ghosts taking their owners' positions after each color. Records one history entry;
// returns the vertices moved everywhere.
int local_untangle_sweeps(const detail::Workspace& work, const VertexColoring* coloring, std::vector<double>& xyz,
                          const QualityMetric& hybrid, Summary& summary, const IterationObserver& observer,
                          Clock::time_point start) {
    const Mesh& mesh = work.mesh();
    const auto owned = work.owned();
    const auto classes = coloring ? coloring->classes() : std::vector<std::vector<VertexId>>{};
    std::vector<double> q(static_cast<std::size_t>(work.movable_elements()));
    std::vector<std::uint8_t> candidate(static_cast<std::size_t>(mesh.num_vertices()));
    int moved = 0;
    for (int sweep = 0; sweep < 10; ++sweep) {
        work.evaluate(hybrid, xyz, q);
        std::fill(candidate.begin(), candidate.end(), 0);
        for (std::size_t e = 0; e < q.size(); ++e)
            if (q[e] <= 0.0)
                for (VertexId v : mesh.element(static_cast<ElementId>(e))) candidate[v] = 1;
        double moved_now = 0.0;
        auto visit = [&](VertexId v) {
            if (candidate[v] && owned[v] && mesh.can_move(v))
                moved_now += detail::untangle_vertex(mesh, xyz, v, work.scale()).moved ? 1.0 : 0.0;
        };
        if (coloring) {
            for (const auto& members : classes) {
                for (VertexId v : members) visit(v);
                work.halo().update(xyz, 3);
            }
        } else {
            for (VertexId v = 0; v < mesh.num_vertices(); ++v) visit(v);
        }
        moved_now = work.reducer().total(moved_now);
        moved += static_cast<int>(moved_now);
        if (moved_now == 0.0) break;
    }
    std::vector<double> buffer;
    work.evaluate(hybrid, xyz, q);
    ++summary.quality_passes;
    const detail::Stats s = detail::quality_stats(work, q, buffer);
    IterationRecord r;
    r.iteration = summary.iterations;
    r.phase = "untangle_local";
    r.worst_quality = s.worst;
    r.best_worst_quality = s.worst;
    r.inverted = s.bad / work.copies();  // an inverted element's copies are all inverted
    r.mean_quality = s.mean;
    r.moved = moved;
    r.seconds = seconds_since(start);
    summary.history.push_back(std::move(r));
    if (observer) observer(summary.history.back());
    return moved;
}

// Untangling: first the regularized energy, which needs no valid start; where it does not free
// every element, the barrier ascent on the hybrid metric and local rounds go on from its best
// iterate. Returns TargetReached once untangled, else how the run ends (reason and message).
class Untangling {
public:
    Untangling(const PhaseContext& context, std::vector<double>& xyz, std::optional<detail::SolverState>& resume)
        : context_(context), work_(context.work), options_(context.options), xyz_(xyz), resume_(resume),
          hybrid_(make_metric("untangle_hybrid", options_.metric_options)),
          local_volumes_(work_.local_reference_volumes()) {
        MetricScale hybrid_scale = work_.scale();
        hybrid_scale.element_reference_volume = local_volumes_;
        hybrid_->set_scale(hybrid_scale);
    }

    PhaseResult run() {
        const int first_round = resume_ ? static_cast<int>(resume_->number("round")) : 0;
        PhaseResult result{TerminationReason::Converged, "not untangled yet"};
        // (A run resumed from a checkpoint of the ascent goes straight back to it.)
        const bool resume_energy = resume_ && resume_->numbers.contains("energy");
        if (options_.untangling == GlobalSolverOptions::Untangling::Energy && (!resume_ || resume_energy)) {
            if (auto ended = energy(resume_energy, result)) return *ended;
        }
        result = rounds(first_round, result);
        resume_.reset();
        return result;
    }

private:
    static bool out_of_budget(const PhaseResult& r) {
        return r.reason == TerminationReason::IterationLimit || r.reason == TerminationReason::TimeLimit;
    }
    static bool ends_run(const PhaseResult& r) {
        return out_of_budget(r) || r.reason == TerminationReason::Interrupted ||
               r.reason == TerminationReason::NumericalFailure;
    }

    // The energy's result into `result`; how the run ends where the energy ends it.
    std::optional<PhaseResult> energy(bool resume_energy, PhaseResult& result) {
        const TerminationCriterion& limits = options_.untangle_termination;
        const auto energy =
            detail::energy_untangle(work_, xyz_, limits.max_iterations, limits.max_seconds, context_.summary,
                                    context_.observer, context_.start, context_.checkpointer,
                                    resume_energy ? &*resume_ : nullptr);
        if (resume_energy) resume_.reset();
        result = {energy.reason, energy.message};
        if (!ends_run(result)) return std::nullopt;
        if (out_of_budget(result))
            return PhaseResult{TerminationReason::CannotUntangle,
                               "untangling stopped (" + result.message + ") with elements still inverted"};
        return PhaseResult{result.reason, "while untangling: " + result.message};
    }

    // The global barrier ascent untangles most of a mesh; where it stalls on a few elements (a
    // local maximum of the worst quality), local steps move single vertices to where their
    // elements' smallest volume is largest, and the barrier ascent resumes.
    PhaseResult rounds(int first_round, PhaseResult result) {
        for (int round = first_round; result.reason != TerminationReason::TargetReached; ++round) {
            const detail::SolverState* here = resume_ && round == first_round ? &*resume_ : nullptr;
            TerminationCriterion stop = options_.untangle_termination;
            stop.max_iterations = here ? static_cast<int>(here->number("budget"))
                                       : std::max(0, stop.max_iterations - context_.summary.untangle_iterations);
            // Hybrid qualities start negative: only the barrier (any t below them) is defined there.
            auto objective = make_objective("log_barrier", options_.objective_options);
            result = Phase(context_, xyz_, *hybrid_, *objective, stop, Stage{.kind = StageKind::Untangle, .round = round})
                         .run(here);
            if (result.reason == TerminationReason::TargetReached) break;
            if (result.reason == TerminationReason::Interrupted || result.reason == TerminationReason::NumericalFailure)
                return {result.reason, "while untangling: " + result.message};
            if (work_.distributed() && !out_of_budget(result) && round < options_.local_untangle_rounds && !colors_)
                colors_ = color_vertices(*work_.distributed());
            if (out_of_budget(result) || round == options_.local_untangle_rounds ||
                local_untangle_sweeps(work_, colors_ ? &*colors_ : nullptr, xyz_, *hybrid_, context_.summary,
                                      context_.observer, context_.start) == 0)
                return {TerminationReason::CannotUntangle,
                        "untangling stopped (" + result.message + ") with elements still inverted"};
        }
        return result;
    }

    const PhaseContext& context_;
    detail::Workspace& work_;
    const GlobalSolverOptions& options_;
    std::vector<double>& xyz_;
    std::optional<detail::SolverState>& resume_;
    std::unique_ptr<QualityMetric> hybrid_;
    // Volumes measured against the size of each element's neighbourhood, so that a graded mesh's
    // small inverted elements weigh as much as its large ones.
    std::vector<double> local_volumes_;
    std::optional<VertexColoring> colors_;  // distributed runs; collective: made when first needed
};

// The shape stages after untangling: the shape phase, the Newton finish on its barrier and on
// fresh ones, and the mean's polish, from the best iterate of them all. next_stage() says which
// follows which.
class ShapeStages {
public:
    ShapeStages(const PhaseContext& context, std::vector<double>& xyz, const detail::SlidingBoundary* sliding)
        : context_(context), work_(context.work), options_(context.options), xyz_(xyz),
          metric_(work_.copies() > 1 ? make_dihedral_sine_term()
                                     : make_metric(options_.shape_metric, options_.metric_options)),
          objective_(make_objective(options_.objective, options_.objective_options)) {
        metric_->set_scale(work_.scale());
        if (sliding) sliding_.emplace(work_, *sliding);
        // Where conjugate gradients stall, the barrier's subproblems have become too
        // ill-conditioned for first-order steps; Newton steps go on from the best iterate
        // (docs/global_solver.md).
        finish_ = options_.finish == GlobalSolverOptions::Finish::Newton && objective_->is_continuation() &&
                  options_.direction != GlobalSolverOptions::Direction::Newton && !sliding;
    }

    // `result`: how the stages before (untangling) ended.
    PhaseResult run(const std::optional<detail::SolverState>& resume, PhaseResult result) {
        result_ = std::move(result);
        const detail::SolverState* here = resume ? &*resume : nullptr;
        for (std::optional<StageKind> kind = first_stage(resume); kind; here = nullptr) {
            const PhaseResult ended = run_stage(*kind, here);
            kind = next_stage(*kind, ended);
        }
        return result_;
    }

private:
    int shape_iterations() const { return context_.summary.iterations - context_.summary.untangle_iterations; }
    int budget() const { return options_.termination.max_iterations; }

    // The shape phase, or the stage a checkpoint was saved in.
    StageKind first_stage(const std::optional<detail::SolverState>& resume) {
        auto saved = [&](const char* key) { return resume && resume->numbers.contains(key) && resume->number(key) != 0.0; };
        if (saved("finish"))  // (checkpoints from before the finish had two parts have no "fresh": theirs was fresh)
            return !resume->numbers.contains("fresh") || resume->number("fresh") != 0.0 ? StageKind::FreshFinish
                                                                                      : StageKind::Finish;
        if (saved("polish")) {
            const auto shape_reason = static_cast<TerminationReason>(resume->number("shape_reason"));
            result_ = {shape_reason,
                       "the shape phases stopped (" + std::string(to_string(shape_reason)) + ") before the checkpoint"};
            mean_goal_ = resume->number("mean_goal");
            return StageKind::Polish;
        }
        return finish_ ? StageKind::ShapeThenFinish : StageKind::Shape;
    }

    // The stage that follows `kind`, which ended with `ended`; nullopt: none. The one place where
    // the stages' order is decided.
    std::optional<StageKind> next_stage(StageKind kind, const PhaseResult& ended) {
        switch (kind) {
        case StageKind::Untangle:
        case StageKind::Polish: return std::nullopt;
        case StageKind::Shape:
        case StageKind::ShapeThenFinish: {
            result_ = ended;
            const bool stalled =
                ended.reason == TerminationReason::Converged || ended.reason == TerminationReason::NoImprovingStep;
            const int left = budget() - shape_iterations();
            if (kind != StageKind::ShapeThenFinish || !stalled || left <= 0) return polish_or_none();
            // First with the shape phase's own barrier (its mu): where the conjugate gradients
            // stalled near a max-min point, Newton steps converge from there. That part may take
            // its kNewtonStepsAtOneMu steps before it hands over, so it goes first only where the
            // budget leaves the fresh barrier as many after them; nearer the budget's end the fresh
            // barrier goes alone, which gains more there.
            return left >= 2 * detail::kNewtonStepsAtOneMu ? StageKind::Finish : fresh_or_none();
        }
        case StageKind::Finish:
        case StageKind::FreshFinish:
            result_ = ended;
            // Far from that barrier's central path, or with its worst elements risen far above its
            // t (Phase::reached_end): a fresh barrier from the best iterate.
            return ended.recenter ? fresh_or_none() : polish_or_none();
        }
        return std::nullopt;
    }

    // A fresh barrier (mu from the qualities, as at the start), under which the worst elements can
    // rearrange, within the budget.
    std::optional<StageKind> fresh_or_none() {
        if (shape_iterations() < budget()) return StageKind::FreshFinish;
        result_ = {TerminationReason::IterationLimit,
                   detail::budget_message(TerminationReason::IterationLimit, options_.termination, "iterations")};
        return polish_or_none();
    }

    // The mean's polish, from the best iterate of them all, within what is left of the budget:
    // polish always, or auto where the mean quality fell below the input's.
    std::optional<StageKind> polish_or_none() {
        const bool budget_left = result_.reason != TerminationReason::IterationLimit &&
                                 result_.reason != TerminationReason::TimeLimit && shape_iterations() < budget();
        const bool sound_end =
            result_.reason != TerminationReason::Interrupted && result_.reason != TerminationReason::NumericalFailure;
        if (options_.polish == GlobalSolverOptions::Polish::Off || !budget_left || !sound_end) return std::nullopt;
        mean_before_ = mean_at(xyz_);
        if (options_.polish == GlobalSolverOptions::Polish::Auto) {
            mean_goal_ = mean_at(work_.mesh().coordinates());
            if (!(*mean_before_ < mean_goal_)) mean_before_.reset();  // the mean did not fall
        }
        return mean_before_ ? std::optional(StageKind::Polish) : std::nullopt;
    }

    double mean_at(std::span<const double> coordinates) {
        std::vector<double> q(static_cast<std::size_t>(work_.movable_elements())), buffer;
        work_.evaluate(*metric_, coordinates, q);
        ++context_.summary.quality_passes;
        return detail::quality_stats(work_, q, buffer).mean;
    }

    PhaseResult run_stage(StageKind kind, const detail::SolverState* resume) {
        const Stage stage{.kind = kind, .iterations_before = shape_iterations()};
        const detail::SlidingVertices* sliding = sliding_ ? &*sliding_ : nullptr;
        switch (kind) {
        case StageKind::Shape:
        case StageKind::ShapeThenFinish: return phase(*objective_, Stage{.kind = kind}, sliding, resume);
        case StageKind::Finish: return phase(*objective_, stage, nullptr, resume);
        case StageKind::FreshFinish: {
            auto fresh = make_objective(options_.objective, options_.objective_options);
            return phase(*fresh, stage, nullptr, resume);
        }
        case StageKind::Polish: return polish(resume);
        case StageKind::Untangle: break;
        }
        throw Error("the shape stages do not untangle");
    }

    PhaseResult phase(ObjectiveFunction& objective, Stage stage, const detail::SlidingVertices* sliding,
                      const detail::SolverState* resume) {
        return Phase(context_, xyz_, *metric_, objective, options_.termination, stage, sliding).run(resume);
    }

    // Runs the polish and adds what it did to the shape stages' message.
    PhaseResult polish(const detail::SolverState* resume) {
        MeanAboveFloor objective;
        const Stage stage{.kind = StageKind::Polish,
                          .iterations_before = shape_iterations(),
                          .mean_goal = mean_goal_,
                          .shape_reason = result_.reason};
        const PhaseResult polished = phase(objective, stage, sliding_ ? &*sliding_ : nullptr, resume);
        if (polished.reason == TerminationReason::Interrupted || polished.reason == TerminationReason::NumericalFailure) {
            result_ = polished;
            return polished;
        }
        const double mean_after = polished.mean;
        std::ostringstream then;
        then << std::setprecision(7) << "; then, with the elements near the worst held still, the mean quality ";
        if (!mean_before_) then << "came to " << mean_after;
        else if (mean_after > *mean_before_) then << "rose from " << *mean_before_ << " to " << mean_after;
        else then << "stayed at " << *mean_before_;
        then << " (" << polished.message << ")";
        result_.message += then.str();
        return polished;
    }

    const PhaseContext& context_;
    detail::Workspace& work_;
    const GlobalSolverOptions& options_;
    std::vector<double>& xyz_;
    std::unique_ptr<QualityMetric> metric_;
    std::unique_ptr<ObjectiveFunction> objective_;  // the shape phase's, which the finish's first part goes on with
    std::optional<detail::SlidingVertices> sliding_;
    bool finish_ = false;  // the Newton finish follows the shape phase
    PhaseResult result_{TerminationReason::TargetReached, ""};
    std::optional<double> mean_before_;                             // the polish: the mean it starts from
    double mean_goal_ = std::numeric_limits<double>::infinity();  // polish always: until the mean stops rising
};

// Untangling (when needed) and shape improvement on the workspace; the caller frames the run.
// With `sliding`, its vertices slide in the shape phase.
Summary solve(const GlobalSolverOptions& options, const IterationObserver& observer, detail::SolverRun& run,
              detail::Workspace& work, detail::Checkpointer& checkpointer, const detail::SlidingBoundary* sliding) {
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
        result = Untangling(context, xyz, resume).run();
        if (result.reason != TerminationReason::TargetReached) {
            work.copy_back(xyz);
            return run.finish(result.reason, result.message);
        }
    }
    if (resume && resume_untangling)
        throw FileError(resume->source, 0, "this checkpoint is of an untangling phase, but the mesh needs none");
    const bool still_tangled = !options.untangle && tangled;
    if (options.improve_shape && !still_tangled)
        result = ShapeStages(context, xyz, sliding).run(resume, std::move(result));
    else if (resume)
        throw FileError(resume->source, 0, "this checkpoint is of a shape phase, which this run does not have");
    work.copy_back(xyz);
    if (result.reason == TerminationReason::Interrupted || result.reason == TerminationReason::NumericalFailure)
        return run.finish(result.reason, result.message);
    if (summary.before.inverted_frozen > 0)
        return run.finish(TerminationReason::CannotUntangle,
                          std::to_string(summary.before.inverted_frozen) +
                              " inverted elements have all their vertices fixed; no smoother can move them");
    if (still_tangled)
        return run.finish(TerminationReason::CannotUntangle, "the mesh is tangled and untangling was turned off");
    return run.finish(result.reason, result.message);
}

// One run on the part, with the boundary sliding (`sliding`) or not (nullptr).
Summary improve_part(const GlobalSolverOptions& options, const IterationObserver& observer, MeshPart part,
                     detail::SlidingBoundary* sliding) {
    const std::string name = "global";
    detail::SolverRun run(part, name, options.shape_metric);
    if (sliding) sliding->set_scale_exponent(run.scale_exponent());
    if (auto nothing = run.nothing_to_move()) return *nothing;
    detail::Checkpointer checkpointer(options.checkpoint, name, options_text(options), part);
    // The dihedral quality's six angles are terms of their own (docs/metrics.md): at a tie of two
    // angles the smaller one alone is a kink where the ascent stalls.
    const Mesh& mesh = part.mesh();
    const bool angle_terms = options.improve_shape && options.shape_metric == "dihedral_sine" &&
                             mesh.kind() == ElementKind::Tetrahedron && !mesh.has_cells();
    detail::Workspace work(part, options.renumber, angle_terms);
    return solve(options, observer, run, work, checkpointer, sliding);
}

}  // namespace

GlobalSolver::GlobalSolver(GlobalSolverOptions options) : options_(std::move(options)) { options_.validate(); }

Summary GlobalSolver::improve(MeshPart part) {
    detail::ThreadScope threads(options_.threads);
    if (options_.boundary != GlobalSolverOptions::Boundary::Slide) return improve_part(options_, observer(), part, nullptr);
    // The sliding run is a shape phase from the valid mesh the first run left: untangling would
    // not keep the boundary on the surface.
    return detail::fixed_then_sliding(part, options_.surface, options_.termination, options_.improve_shape,
                                      [&](const TerminationCriterion& budget, detail::SlidingBoundary* sliding) {
                                          GlobalSolverOptions run = options_;
                                          run.termination = budget;
                                          if (sliding) run.untangle = false;
                                          return improve_part(run, observer(), part, sliding);
                                      });
}

}  // namespace paloverde
