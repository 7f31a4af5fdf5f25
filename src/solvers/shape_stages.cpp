// The global solver's shape stages and the order they run in (ShapeStages::next_stage).
#include <iomanip>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>

#include "paloverde/core/error.hpp"
#include "global_phase.hpp"

namespace paloverde::detail {

namespace {

// The shape stages after untangling: the shape phase (once more from a close start where it
// stalls below its start), the Newton finish on its barrier and on fresh ones, and the mean's
// polish, from the best iterate of them all. next_stage() says which
// follows which.
class ShapeStages {
public:
    ShapeStages(const PhaseContext& context, std::vector<double>& xyz, const SlidingBoundary* sliding)
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
    PhaseResult run(const std::optional<SolverState>& resume, PhaseResult result) {
        result_ = std::move(result);
        const SolverState* here = resume ? &*resume : nullptr;
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
    StageKind first_stage(const std::optional<SolverState>& resume) {
        auto saved = [&](const char* key) { return resume && resume->numbers.contains(key) && resume->number(key) != 0.0; };
        if (saved("finish"))  // (checkpoints from before the finish had two parts have no "fresh": theirs was fresh)
            return !resume->numbers.contains("fresh") || resume->number("fresh") != 0.0 ? StageKind::FreshFinish
                                                                                      : StageKind::Finish;
        if (saved("close_start")) close_start_ = close_start_objective();
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
            // Stalled below where it started: the barrier's first t lay so far under the worst
            // element (the band's width below it, as after untangling, where the worst is near 0
            // and the band holds many elements) that it weighed the worst like the rest of the
            // band, and the steps traded it for them until none was left. Once more from the best
            // iterate, on a barrier whose t starts just under the worst.
            if (stalled && !ended.gained && !close_start_ && left > 0 && objective_->is_continuation()) {
                close_start_ = close_start_objective();
                return kind;
            }
            if (kind != StageKind::ShapeThenFinish || !stalled || left <= 0) return polish_or_none();
            // First with the shape phase's own barrier (its mu): where the conjugate gradients
            // stalled near a max-min point, Newton steps converge from there. That part may take
            // its kNewtonStepsAtOneMu steps before it hands over, so it goes first only where the
            // budget leaves the fresh barrier as many after them; nearer the budget's end the fresh
            // barrier goes alone, which gains more there.
            return left >= 2 * kNewtonStepsAtOneMu ? StageKind::Finish : fresh_or_none();
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
                   budget_message(TerminationReason::IterationLimit, options_.termination, "iterations")};
        return polish_or_none();
    }

    // The mean's polish, from the best iterate of them all, within what is left of the budget:
    // polish always, or auto where the mean quality fell below the input's, or where elements are
    // rated in a target's metric. There a sideways tilt of a thin element counts as a small
    // fraction of its width, so the elements the max-min leaves alone can be far from right in
    // space; raising the mean (with the worst held) straightens them.
    std::optional<StageKind> polish_or_none() {
        const bool budget_left = result_.reason != TerminationReason::IterationLimit &&
                                 result_.reason != TerminationReason::TimeLimit && shape_iterations() < budget();
        const bool sound_end =
            result_.reason != TerminationReason::Interrupted && result_.reason != TerminationReason::NumericalFailure;
        if (options_.polish == GlobalSolverOptions::Polish::Off || !budget_left || !sound_end) return std::nullopt;
        mean_before_ = mean_at(xyz_);
        if (options_.polish == GlobalSolverOptions::Polish::Auto && !rated_in_metric()) {
            mean_goal_ = mean_at(work_.mesh().coordinates());
            if (!(*mean_before_ < mean_goal_)) mean_before_.reset();  // the mean did not fall
        }
        return mean_before_ ? std::optional(StageKind::Polish) : std::nullopt;
    }

    // Whether any rank's elements carry a target's metric (so that every rank decides alike).
    bool rated_in_metric() const {
        return work_.reducer().max(work_.mesh().target_metric_roots().empty() ? 0.0 : 1.0) > 0.0;
    }

    double mean_at(std::span<const double> coordinates) {
        std::vector<double> q(static_cast<std::size_t>(work_.movable_elements())), buffer;
        work_.evaluate(*metric_, coordinates, q);
        ++context_.summary.quality_passes;
        return quality_stats(work_, q, buffer).mean;
    }

    PhaseResult run_stage(StageKind kind, const SolverState* resume) {
        const Stage stage{.kind = kind, .iterations_before = shape_iterations()};
        const SlidingVertices* sliding = sliding_ ? &*sliding_ : nullptr;
        switch (kind) {
        case StageKind::Shape:
        case StageKind::ShapeThenFinish:
            return close_start_ ? phase(*close_start_,
                                        Stage{.kind = kind, .iterations_before = shape_iterations(), .close_start = true},
                                        sliding, resume)
                                : phase(*objective_, Stage{.kind = kind}, sliding, resume);
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

    PhaseResult phase(ObjectiveFunction& objective, Stage stage, const SlidingVertices* sliding,
                      const SolverState* resume) {
        return Phase(context_, xyz_, *metric_, objective, options_.termination, stage, sliding).run(resume);
    }

    // The shape phase's barrier, started so that about kCloseStartActive elements weigh like the
    // worst (in practice its floor decides: t a thousandth of the qualities' size under the worst).
    std::unique_ptr<ObjectiveFunction> close_start_objective() const {
        constexpr double kCloseStartActive = 5.0;
        ObjectiveOptions close = options_.objective_options;
        close.initial_mu = 0.0;
        close.barrier_initial_active = kCloseStartActive;
        return make_objective(options_.objective, close);
    }

    // Runs the polish and adds what it did to the shape stages' message.
    PhaseResult polish(const SolverState* resume) {
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
    Workspace& work_;
    const GlobalSolverOptions& options_;
    std::vector<double>& xyz_;
    std::unique_ptr<QualityMetric> metric_;
    std::unique_ptr<ObjectiveFunction> objective_;  // the shape phase's, which the finish's first part goes on with
    std::optional<SlidingVertices> sliding_;
    bool finish_ = false;  // the Newton finish follows the shape phase
    // The barrier of the shape phase run again with a close start (at most once; next_stage).
    std::unique_ptr<ObjectiveFunction> close_start_;
    PhaseResult result_{TerminationReason::TargetReached, ""};
    std::optional<double> mean_before_;                             // the polish: the mean it starts from
    double mean_goal_ = std::numeric_limits<double>::infinity();  // polish always: until the mean stops rising
};

}  // namespace

PhaseResult improve_shape(const PhaseContext& context, std::vector<double>& xyz, const SlidingBoundary* sliding,
                          const std::optional<SolverState>& resume, PhaseResult before) {
    return ShapeStages(context, xyz, sliding).run(resume, std::move(before));
}

}  // namespace paloverde::detail
