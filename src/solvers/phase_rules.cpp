// When the phase's objective has solved a subproblem (and moves on to the next), and when the
// phase ends: its target, a stall, a handover to the Newton finish or to local untangling. The
// rules and the measurements behind their constants: docs/global_solver.md.
#include <algorithm>
#include <string>

#include "global_phase.hpp"

namespace paloverde::detail {

namespace {

// The finish starts a fresh barrier where the worst quality rose this many times the gap to t it
// began with above t: the bulk of the elements then holds t, and the steps would trade the worst
// elements for it.
constexpr double kLostGap = 4.0;

// A shape phase the Newton finish follows hands over once its worst quality and t rose by less
// than this many times min_progress over three progress windows (docs/global_solver.md, "The
// handover"): conjugate gradients that creep that slowly are slower than Newton steps.
constexpr double kHandoverProgress = 100.0;
// And sooner, at ten times that pace, where the steps of those windows also gained less than
// kCalmGain mu each on average: the barrier's subproblems are solved at every step and only the
// worst element creeps. Where the steps still gain far more (hundreds of mu each), the conjugate
// gradients are working a plateau that they leave later, and handing over there ends lower.
constexpr double kCalmHandoverProgress = 1000.0;
constexpr double kCalmGain = 1.0;
// And after a single progress window where its worst quality and t rose by less than
// kQuickHandoverProgress times min_progress while the steps gained less than kQuickGain mu each:
// a subproblem that is close to solved but whose gains stay above gain_tolerance holds mu (and
// the rules above wait for a smaller one) while only the bulk of the focus moves. Steps that
// still gain thousands of mu do not hand over.
constexpr double kQuickHandoverProgress = 30.0;
constexpr double kQuickGain = 10.0;
// The shape phase's subproblem at one mu also counts as solved, for the max-min problem, once the
// worst element has held less than this share of the barrier's weight for a whole progress
// window: mu is then so large that t sits far below the worst, the steps work the many elements
// above t (each a term like the worst) and trade the worst ones for them (docs/global_solver.md,
// "A barrier that let its worst element go"); the next mu puts t near the worst, which then
// rises fast. On a phase's first mu, which the automatic start placed to weigh many elements
// alike, only while the worst also stands farther above t than where the phase began (its weight
// below mu / first gap): the worst rose away from a t that stayed.
constexpr double kLeastWorstWeight = 0.01;

}  // namespace

Phase::Subproblem Phase::judge_subproblem(bool accepted, bool full_step, double decrement) {
    Subproblem sub;
    const double mu = objective_.subproblem_scale();
    // The shape phase's conjugate gradients on the barrier shrink mu on their gains (below).
    sub.adaptive = !newton_ && !stage_.untangling() && options_.gain_tolerance > 0.0 && mu > 0.0;
    if (newton_) {
        // Levenberg-Marquardt: less damping after a full step that gained at least half of
        // what the model promised (decrement / 2), more after a shortened or failed one.
        const bool full = full_step && gain_ >= 0.25 * decrement;
        newton_damping_ = full ? std::max(newton_damping_ / 3.0, 1e-8) : std::min(newton_damping_ * 4.0, 1e8);
        // The subproblem at this mu is solved when the Newton decrement (in the barrier's own
        // units, F / mu) is small; a cap keeps a subproblem that cannot be solved from holding mu
        // forever.
        const bool converged = decrement <= options_.newton_tolerance * mu;
        const bool capped = ++steps_at_mu_ >= kNewtonStepsAtOneMu;
        // The finish's first part goes on with the shape phase's barrier. Where Newton steps
        // cannot solve its subproblem, the iterate is far from the barrier's central path at
        // this mu: a fresh barrier recenters it (next_stage) instead of a smaller mu.
        sub.out_of_reach = capped && !converged && stage_.kind == StageKind::Finish;
        sub.solved = converged || (capped && !sub.out_of_reach);
        if (sub.solved || !accepted) quick_solves_ = accepted && converged && steps_at_mu_ == 1 ? quick_solves_ + 1 : 0;
        return sub;
    }
    // The shape phase's barrier subproblem is solved when a step gains little against mu (F is
    // in quality units; F / mu in the barrier's own): a fixed count of steps solves a small
    // mesh's subproblem many times over and a large one's too loosely, and the result then moved
    // with the count (issue 16). No cap on the steps at one mu: a large focus keeps gaining for
    // hundreds of steps, and a mu shrunk before its subproblem is solved leaves t hugging the
    // worst element, which makes the result swing with focus_band and barrier_initial_active. A
    // stage in which neither the worst quality nor t rises for three progress windows is a stall
    // (judge_stall): mu shrinks once more if the last such shrink paid, else the phase ends.
    // At least steps_per_mu steps at each mu: a step blocked by some element also gains little,
    // and shrinking mu at each such step would run away. Or where the barrier let its worst
    // element go (kLeastWorstWeight).
    ++steps_at_mu_;
    const double weight = objective_.worst_share();
    const bool first_mu = stage_history_.back() == 0.0;
    const bool let_go_now = weight < kLeastWorstWeight && (!first_mu || (first_gap_ > 0.0 && mu > weight * first_gap_));
    let_go_steps_ = let_go_now ? let_go_steps_ + 1 : 0;
    const bool let_go = let_go_steps_ >= stop_.progress_window;
    // (The polish's objective has no mu: its conjugate directions restart on failures only.)
    sub.solved = stage_.polish() ? false
                 : sub.adaptive  ? steps_at_mu_ >= options_.steps_per_mu && accepted &&
                                      (gain_ < options_.gain_tolerance * mu || let_go)
                                 : steps_at_mu_ >= options_.steps_per_mu;
    return sub;
}

std::optional<PhaseResult> Phase::judge_end(int iteration, const Stats& s, double& objective, const Subproblem& sub) {
    if (auto ended = reached_end(s, sub.out_of_reach)) return ended;
    // The finish's steps take a gradient pass per Hessian product: it needs as much progress
    // per pass as conjugate gradients (one pass per step) need per step.
    TerminationCriterion judged = stop_;
    const auto window = static_cast<std::size_t>(stop_.progress_window);
    if (stage_.finish() && passes_history_.size() > window)
        judged.min_progress *= (passes_history_.back() - passes_history_[passes_history_.size() - 1 - window]) /
                               static_cast<double>(window);
    const StallWindow progress(judged, best_worst_);
    bool widened = false;
    if (auto ended = judge_stall(judged, progress, sub.adaptive, objective, widened)) return ended;
    if (stage_.newton_follows())
        if (auto ended = hands_over()) return ended;
    if (auto ended = too_slow_to_untangle(iteration, progress)) return ended;
    // Half way up the band, the elements above it start to matter: a new focus.
    if (focusing_ && !stage_.polish() && (widened || s.worst >= focus_base_ + 0.5 * (focus_top_ - focus_base_))) {
        refocus();
        // An objective over its focus alone keeps its weighting as its focus changes.
        if (focus_alone()) objective_.keep_weighting(work_.counted(q_, counted_), reducer_);
        update_objective(objective);
    }
    return std::nullopt;
}

// The ends that need no stall window: the target, and the Newton finish's call for a fresh barrier.
std::optional<PhaseResult> Phase::reached_end(const Stats& s, bool out_of_reach) {
    if (stage_.untangling() && s.bad == 0 && untangled()) {
        best_x_ = x_;
        return end(TerminationReason::TargetReached, "untangled");
    }
    if (!stage_.untangling() && !stage_.polish() && target_reached(stop_, best_worst_))
        return end(TerminationReason::TargetReached, "the worst quality reached the target");
    if (stage_.polish() && best_mean_ > stage_.mean_goal)
        return end(TerminationReason::Converged, "above the input's mean");
    if (out_of_reach) {
        PhaseResult result = end(TerminationReason::Converged, "the barrier's subproblem is out of Newton's reach");
        result.recenter = true;
        return result;
    }
    // One Newton step can lift the worst elements far above t. The bulk then holds t, and the
    // steps that follow trade the worst elements for it. A fresh barrier from the best iterate
    // weights the worst elements again. Measured from t or from where t began, whichever is
    // higher: each such restart needs the best worst quality to have risen by more than three
    // times the gap, so restarts cannot cycle.
    const double t = objective_.subproblem_floor();
    if (stage_.finish() && first_gap_ > 0.0 && best_worst_ - std::max(t, first_t_) > kLostGap * first_gap_) {
        PhaseResult result =
            end(TerminationReason::Converged, "the worst quality rose far above the barrier's t; a fresh barrier follows");
        result.recenter = true;
        return result;
    }
    return std::nullopt;
}

// Over a window: the worst quality and t rose too little, the inverted count did not fall. In the
// Newton finish t's rise counts only while t lies further under the best worst quality than the
// window's tolerance: each step solves its subproblem, so t follows mu up to the worst element,
// and once all of its rise still to come is less than progress, waiting for it buys Newton steps
// (each a gradient pass per Hessian product) that leave the mesh as it is. Further down, t's climb
// is how the worst element is won back after the steps traded it away.
bool Phase::standing(const StallWindow& w) const {
    const bool t_at_worst = stage_.finish() && best_worst_ - measure_history_.back() <= w.tolerance();
    return w.rose_too_little(best_history_) && (t_at_worst || w.rose_too_little(measure_history_)) &&
           w.did_not_fall(bad_history_);
}

// A stall ends the phase, unless a wider focus or a smaller mu may still pay (`widened`: the focus
// was widened).
std::optional<PhaseResult> Phase::judge_stall(const TerminationCriterion& judged, const StallWindow& progress,
                                              bool adaptive, double& objective, bool& widened) {
    // A stall is judged once a smaller mu has been tried in the window (a worst element held at
    // one mu is often freed by the next), or over three windows without (a mu held by gains
    // elsewhere while the worst stands still).
    TerminationCriterion three = judged;
    three.progress_window = 3 * stop_.progress_window;
    const bool long_stall = StallWindow(three, best_worst_).rose_too_little(best_history_);
    const bool stalled = failures_ >= options_.max_failed_searches ||
                         (standing(progress) && (stage_.polish() || progress.rose(stage_history_) || long_stall));
    // A focus that stalls may be held by the elements just outside it: a wider one, as long as the
    // last widening paid (each costs a stall window on more elements). Not before the Newton
    // finish, which starts on a fresh focus, nor in it: there a wider focus costs more than it gains.
    widened = stalled && focusing_ && !stage_.finish() && !stage_.newton_follows() && band_ < 1.0 &&
              best_worst_ > widened_at_ + progress.tolerance();
    // A stall inside one stage (mu held for three windows by gains that do not reach the worst
    // element) may be the subproblem's own plateau: a smaller mu weights the worst elements more,
    // as long as the last such cut paid.
    const bool shrink = !widened && stalled && adaptive && failures_ < options_.max_failed_searches &&
                        !progress.rose(stage_history_) && best_worst_ > shrunk_at_ + progress.tolerance();
    if (widened) {
        band_ = std::min(1.0, 2.0 * band_);
        widened_at_ = best_worst_;
        failures_ = 0;
        restart_ = true;
        restart_histories();
    } else if (shrink) {
        objective_.advance();
        steps_at_mu_ = 0;
        let_go_steps_ = 0;
        shrunk_at_ = best_worst_;
        restart_ = true;
        restart_histories();
        update_objective(objective);
    } else if (failures_ >= options_.max_failed_searches) {
        return end(TerminationReason::NoImprovingStep, "no step along the search direction raises the objective");
    } else if (stalled) {
        return end(TerminationReason::Converged,
                   stage_.polish() ? "the mean quality stopped rising" : "the worst quality stopped improving");
    }
    return std::nullopt;
}

// A shape phase the Newton finish follows hands over where its worst quality creeps. Over three
// windows, as the worst quality rises in steps (a window without a rise is common long before
// conjugate gradients stop paying); only while the barrier's t creeps too (the worst may stand
// still while t climbs toward it), and mu has shrunk meanwhile (one mu may hold while the worst
// stands still, then jump). Where the steps gained less than kCalmGain mu each, ten times that
// pace hands over; where they gained less than kQuickGain mu each, one window at
// kQuickHandoverProgress does.
std::optional<PhaseResult> Phase::hands_over() {
    auto creeping = [&](double factor, int windows) {
        TerminationCriterion slow = stop_;
        slow.min_progress *= factor;
        slow.progress_window = windows * stop_.progress_window;
        return StallWindow(slow, best_worst_);
    };
    // The steps over the window gained less than `gain` mu each on average.
    auto gained_under = [&](const StallWindow& window, double gain) {
        const std::size_t w = window.window();
        return window.spans(gain_history_) &&
               gain_history_.back() - gain_history_[gain_history_.size() - 1 - w] < gain * static_cast<double>(w);
    };
    const StallWindow creep = creeping(kHandoverProgress, 3), calm_creep = creeping(kCalmHandoverProgress, 3),
                      quick_creep = creeping(kQuickHandoverProgress, 1);
    const bool slow =
        (standing(creep) || (gained_under(creep, kCalmGain) && standing(calm_creep))) && creep.rose(stage_history_);
    if (slow || (gained_under(quick_creep, kQuickGain) && standing(quick_creep)))
        return end(TerminationReason::Converged,
                   "the worst quality rose too slowly for conjugate gradients; Newton steps take over");
    return std::nullopt;
}

// An ascent can inch up for hundreds of iterations on one element that it cannot free. When the
// inverted count did not fall over the window and, at the window's pace, the worst element would
// still be inverted when the budget runs out, untangling hands over to local untangling now.
std::optional<PhaseResult> Phase::too_slow_to_untangle(int iteration, const StallWindow& progress) {
    if (!stage_.untangling() || !progress.spans(best_history_)) return std::nullopt;
    const double pace = progress.pace(best_history_);
    const double left = static_cast<double>(stop_.max_iterations - iteration);
    if (progress.did_not_fall(bad_history_) && best_worst_ + pace * left <= 0.0)
        return end(TerminationReason::Converged,
                   "the worst element rose too slowly to become valid within the iteration budget (" +
                       std::to_string(pace) + " per iteration over the last " + std::to_string(progress.window()) +
                       ")");
    return std::nullopt;
}

}  // namespace paloverde::detail
