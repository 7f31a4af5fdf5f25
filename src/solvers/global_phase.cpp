// The phase's iteration: the gradient, a direction (preconditioned conjugate gradients, steepest
// ascent or a truncated Newton step), the line search (line_search.cpp), then the bookkeeping of
// the best iterate and the histories that phase_rules.cpp judges.
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/blocked_sum.hpp"
#include "paloverde/core/error.hpp"
#include "global_phase.hpp"
#include "iteration_start.hpp"

namespace paloverde::detail {

const char* Stage::label() const {
    switch (kind) {
    case StageKind::Untangle: return "untangle";
    case StageKind::Polish: return "polish";
    case StageKind::FreshFinish: return "finish_fresh";
    case StageKind::Finish: return "finish";
    case StageKind::Shape:
    case StageKind::ShapeThenFinish: break;
    }
    return close_start ? "shape_close_start" : "shape";
}

PhaseResult Phase::run(const SolverState* resume) {
    prepare();
    // The objective and its weights at the current iterate, for the history and the next step.
    double objective = 0.0;
    int first_iteration = stage_.iterations_before + 1;
    if (resume) first_iteration = restore(*resume, objective);
    else if (auto ended = start(objective)) return std::move(*ended);
    for (int iteration = first_iteration;; ++iteration)
        if (auto ended = iterate(iteration, objective)) return std::move(*ended);
}

void Phase::prepare() {
    const std::size_t n3 = x_.size();
    trial_x_ = x_;  // the line search writes only the free vertices' trials
    gradient_.assign(n3, 0.0);
    direction_.assign(n3, 0.0);
    previous_gradient_.assign(n3, 0.0);
    best_x_ = x_;
    damping_.assign(n3 / 3, 1.0);
    newton_ = !stage_.untangling() && !stage_.polish() &&
              (options_.direction == GlobalSolverOptions::Direction::Newton || stage_.finish());
    // Only the preconditioner and Newton need the curvature (8 bytes per element, 48 per vertex).
    // The polish's sum has no curvature of its own: its barrier's gives the elements' scale.
    precondition_ = (stage_.untangling() && options_.precondition_untangling) || newton_ || stage_.polish();
    curvature_weight_.clear();
    curvature_.assign(precondition_ ? 2 * n3 : 0, 0.0);
    preconditioned_.assign(n3, 0.0);
    previous_preconditioned_.assign(n3, 0.0);
    stamp_.assign(n3 / 3, 0);
    mark_.assign(work_.part().whole() ? 0 : n3 / 3, 0.0);
    once_damped_mark_.assign(n3 / 3, 0);
    // Newton's directions from the start come out worse on a focus than on the whole mesh: they
    // keep the whole mesh. The finish, from where conjugate gradients stalled, focuses like them
    // (on finish_band of their band).
    focusing_ = stage_.polish() || (!stage_.untangling() && (!newton_ || stage_.finish()) && options_.focus_band < 1.0);
    band_ = stage_.polish()   ? 1.0
            : stage_.finish() ? options_.finish_band * options_.focus_band
                              : options_.focus_band;
    widened_at_ = std::numeric_limits<double>::lowest();
    shrunk_at_ = std::numeric_limits<double>::lowest();
    // Focused, the element arrays take the focus's size at the first refocus; until then only q_
    // rates the whole mesh (sizing them all for it would zero memory a large mesh then leaves unused).
    if (focusing_) q_.resize(static_cast<std::size_t>(work_.movable_elements()));
    else size_element_arrays();
}

// The phase's first iterate: the objective set up for it, its figures recorded.
std::optional<PhaseResult> Phase::start(double& objective) {
    work_.evaluate(metric_, x_, q_);
    ++summary_.quality_passes;
    // The objective's first subproblem comes from the whole mesh, focused or not: the focus's fewer
    // terms would choose a looser barrier, under which conjugate gradients let its elements sink
    // toward t. Focused, it starts no looser than the band. (The finish's fresh barrier weighs its
    // focus alone, Newton steps following its central path: its subproblem comes from it.)
    if (focusing_) objective_.focus_on_band(band_, metric_.ideal_value());
    if (!focus_alone()) objective_.update(work_.counted(q_, counted_), reducer_);
    if (focusing_) {
        if (stage_.polish()) hold_near_worst();
        else refocus();
        objective_.update(work_.counted(q_, counted_), reducer_);
    }
    const Stats s = stats(q_);
    best_worst_ = start_worst_ = s.worst;
    best_bad_ = start_bad_ = s.bad;
    best_mean_ = s.mean;
    if (objective_.subproblem_scale() > 0.0) {
        first_t_ = objective_.subproblem_floor();
        first_gap_ = best_worst_ - first_t_;
    }
    best_history_ = {best_worst_};
    measure_history_ = {measure(s)};
    bad_history_ = {static_cast<double>(s.bad)};
    stage_history_ = {0.0};
    gain_history_ = {0.0};
    passes_history_ = {static_cast<double>(summary_.gradient_passes)};
    objective = objective_value(q_);
    objective_.weights(q_, weight_);
    record(s, objective, 0.0, 0.0);
    if (!sound(s, objective))
        return end(TerminationReason::NumericalFailure,
                   "the qualities or the objective are not finite numbers at the start of the phase");
    if (stage_.untangling() && s.bad == 0 && untangled()) return end(TerminationReason::TargetReached, "untangled");
    return std::nullopt;
}

std::optional<PhaseResult> Phase::iterate(int iteration, double& objective) {
    if (auto ended = at_top(iteration)) return ended;
    if (auto ended = ascent_gradient()) return ended;
    double decrement = 0.0;
    if (newton_) decrement = newton_direction();
    else conjugate_direction();
    const double max_direction = share_direction();
    // Newton's first trial is its full step.
    if (newton_) step_ = std::min(max_direction / work_.reference_length(), 1e6);
    const double first_trial = step_;
    const bool accepted = line_search(objective, max_direction);
    const double step = accepted ? step_ : 0.0;
    ++summary_.iterations;
    if (stage_.untangling()) ++summary_.untangle_iterations;
    failures_ = accepted ? 0 : failures_ + 1;
    restart_ = !accepted;
    // Steps may grow far beyond the mesh's size: an untangled vertex can have been thrown far out
    // and must be able to come back.
    if (accepted) step_ = std::min(2.0 * step_, 1e6);
    else step_ = 0.05;
    const Subproblem sub = judge_subproblem(accepted, accepted && step == first_trial, decrement);
    if (!accepted || sub.solved) next_subproblem();
    objective_.update(work_.counted(q_, counted_), reducer_);
    const Stats s = stats(q_);
    objective = objective_value(q_);
    if (!sound(s, objective)) {
        record(s, objective, step, accepted ? gain_ : 0.0);
        return end(TerminationReason::NumericalFailure,
                   "the qualities, the objective or the barrier's t are not finite numbers (iteration " +
                       std::to_string(summary_.iterations) + "); the best iterate is handed back");
    }
    note_iterate(s, objective, step, accepted, sub.solved);
    return judge_end(iteration, s, objective, sub);
}

// Checkpoints and stops at the top of an iteration, where the state is complete. The target is
// judged after an iteration instead (reached_end), where the untangling stage has its own.
std::optional<PhaseResult> Phase::at_top(int iteration) {
    IterationStart top(stop_, reducer_, start_, "iterations", &checkpointer_);
    if (auto stop = top(iteration, summary_.iterations, [&] { save_checkpoint(iteration); }))
        return end(stop->reason, std::move(stop->message));
    return std::nullopt;
}

// The objective's gradient into gradient_ (and its curvature where needed); ends the phase where
// it is not finite or has vanished.
std::optional<PhaseResult> Phase::ascent_gradient() {
    if (precondition_) {
        objective_.curvature_weights(q_, curvature_weight_);
        work_.gradient(metric_, x_, weight_, gradient_, curvature_weight_, curvature_);
    } else {
        work_.gradient(metric_, x_, weight_, gradient_);
    }
    ++summary_.gradient_passes;
    // A sliding vertex ascends along its surface or curve.
    if (sliding_) sliding_->tangent(gradient_);
    const double g2 = free_owned_sums<1>(work_, [&](std::size_t v, auto& acc) {
        acc[0].add(gradient_[3 * v] * gradient_[3 * v] + gradient_[3 * v + 1] * gradient_[3 * v + 1] +
                   gradient_[3 * v + 2] * gradient_[3 * v + 2]);
    })[0];
    if (!std::isfinite(g2))
        return end(TerminationReason::NumericalFailure, "the objective's gradient is not a finite number (iteration " +
                                                            std::to_string(summary_.iterations + 1) +
                                                            "); the best iterate is handed back");
    const double gradient_norm = std::sqrt(g2);
    if (first_gradient_norm_ < 0.0) first_gradient_norm_ = gradient_norm;
    if (!(gradient_norm > stop_.gradient_tolerance * first_gradient_norm_))
        return end(TerminationReason::GradientVanished, "the objective's gradient vanished");
    return std::nullopt;
}

// A truncated Newton direction into direction_; returns its decrement (not positive: the
// gradient is the direction).
double Phase::newton_direction() {
    // CG to a tenth of the preconditioned residual (a usual forcing term; not tuned).
    const auto step = newton_solver_.solve(metric_, objective_, x_, q_, curvature_weight_, curvature_, gradient_,
                                           newton_damping_, 0.1, options_.newton_cg_iterations, direction_);
    summary_.quality_passes += step.products;
    summary_.gradient_passes += step.products;
    if (!(step.decrement > 0.0)) direction_ = gradient_;
    return step.decrement;
}

// Polak-Ribiere+ conjugate gradient (preconditioned) into direction_, restarted whenever the
// objective changes (mu) or the direction stops ascending; steepest ascent restarts at every step.
void Phase::conjugate_direction() {
    if (precondition_) apply_preconditioner();
    else  // read at the free vertices only
        for_each_free_coordinate(work_, [&](std::size_t i) { preconditioned_[i] = gradient_[i]; });
    if (sliding_ && precondition_) sliding_->tangent(preconditioned_);
    double beta = 0.0;
    if (options_.direction == GlobalSolverOptions::Direction::ConjugateGradient && !restart_) {
        const auto sums = free_owned_sums<2>(work_, [&](std::size_t v, auto& acc) {
            double a = 0.0, b = 0.0;
            for (std::size_t i = 3 * v; i < 3 * v + 3; ++i) {
                a += preconditioned_[i] * (gradient_[i] - previous_gradient_[i]);
                b += previous_preconditioned_[i] * previous_gradient_[i];
            }
            acc[0].add(a);
            acc[1].add(b);
        });
        beta = sums[1] > 0.0 ? std::max(0.0, sums[0] / sums[1]) : 0.0;
    }
    // Free vertices only: a new focus restarts (beta 0), and the line search reads no other.
    for (const VertexId v : work_.free_vertices())
        for (std::size_t i = 3 * static_cast<std::size_t>(v); i < 3 * static_cast<std::size_t>(v) + 3; ++i)
            direction_[i] = preconditioned_[i] + beta * direction_[i];
    // Both terms are tangential already; this keeps their sum so despite rounding.
    if (sliding_) sliding_->tangent(direction_);
    const double slope = free_owned_sums<1>(work_, [&](std::size_t v, auto& acc) {
        acc[0].add(gradient_[3 * v] * direction_[3 * v] + gradient_[3 * v + 1] * direction_[3 * v + 1] +
                   gradient_[3 * v + 2] * direction_[3 * v + 2]);
    })[0];
    if (!(slope > 0.0)) direction_ = preconditioned_;
}

// Ghosts take their owners' directions, and this iteration's gradients are kept for the next
// conjugate direction; returns the longest free vertex direction over all processes.
double Phase::share_direction() {
    work_.halo().update(direction_, 3);
    // For the next conjugate direction, which reads the free vertices only.
    for (const VertexId v : work_.free_vertices())
        for (std::size_t i = 3 * static_cast<std::size_t>(v); i < 3 * static_cast<std::size_t>(v) + 3; ++i) {
            previous_gradient_[i] = gradient_[i];
            previous_preconditioned_[i] = preconditioned_[i];
        }
    double max_direction = 0.0;
    const auto owned = work_.owned();
    for (const VertexId v : work_.free_vertices())
        if (owned[v])
            max_direction =
                std::max(max_direction, std::hypot(direction_[3 * v], direction_[3 * v + 1], direction_[3 * v + 2]));
    return reducer_.max(max_direction);
}

// The objective moves on to its next subproblem. Newton steps near the end solve each subproblem
// at once, and a fixed shrink then approaches the optimum only linearly: after k such subproblems
// in a row mu shrinks k times, so the path is followed ever faster.
void Phase::next_subproblem() {
    for (int k = 0; k < std::max(1, newton_ ? quick_solves_ : 0); ++k) objective_.advance();
    steps_at_mu_ = 0;
    let_go_steps_ = 0;
    restart_ = true;
}

// The best iterate and the histories after a step.
void Phase::note_iterate(const Stats& s, double objective, double step, bool accepted, bool solved) {
    // Better: fewer non-positive elements, then a higher worst quality; in the polish (which
    // holds the worst element) no lower worst quality and a higher mean.
    const bool better = stage_.polish() ? s.bad <= best_bad_ && s.worst >= best_worst_ && s.mean > best_mean_
                                        : better_iterate(s.bad, s.worst, best_bad_, best_worst_);
    if (better) {
        best_bad_ = s.bad;
        best_worst_ = s.worst;
        best_mean_ = s.mean;
        keep_best();
    }
    objective_.weights(q_, weight_);
    record(s, objective, step, accepted ? gain_ : 0.0);
    const double mu = objective_.subproblem_scale();
    best_history_.push_back(best_worst_);
    measure_history_.push_back(measure(s));
    bad_history_.push_back(static_cast<double>(s.bad));
    stage_history_.push_back(stage_history_.back() + ((!accepted || solved) ? 1.0 : 0.0));
    gain_history_.push_back(gain_history_.back() + (accepted && mu > 0.0 ? gain_ / mu : 0.0));
    passes_history_.push_back(static_cast<double>(summary_.gradient_passes));
}

void Phase::update_objective(double& objective) {
    objective_.update(work_.counted(q_, counted_), reducer_);
    objective = objective_value(q_);
    objective_.weights(q_, weight_);
}

bool Phase::untangled() const { return detail::untangled(work_, x_); }

// preconditioned = M^-1 gradient, M per vertex the 3x3 Gauss-Newton block of the objective
// (curvature), regularized: a Newton step for each vertex as if its neighbours stood still. It
// evens out the very different scales of elements and barrier weights.
void Phase::apply_preconditioner() {
    const std::size_t n = x_.size() / 3;
    const auto [trace_sum, counted] = owned_sums<2>(work_, [&](std::size_t v, auto& acc) {
        const double* m = &curvature_[6 * v];
        const double trace = m[0] + m[3] + m[5];
        if (trace > 0.0) acc[0].add(trace), acc[1].add(1.0);
    });
    if (counted == 0.0) {
        preconditioned_ = gradient_;
        return;
    }
    const double floor = 1e-8 * trace_sum / counted;
#pragma omp parallel for schedule(static) if (n > kParallelThreshold)
    for (std::size_t v = 0; v < n; ++v) {
        const double* m = &curvature_[6 * v];
        const double lambda = 1e-3 * (m[0] + m[3] + m[5]) / 3.0 + floor;
        solve_block(m, lambda, &gradient_[3 * v], &preconditioned_[3 * v]);
    }
}

void Phase::keep_best() {
    if (best_focus_ != work_.focus_generation()) {
        best_x_ = x_;
        best_focus_ = work_.focus_generation();
        return;
    }
    for_each_free_coordinate(work_, [&](std::size_t i) { best_x_[i] = x_[i]; });
}

PhaseResult Phase::end(TerminationReason reason, std::string message) {
    work_.unfocus();
    x_.swap(best_x_);  // the best iterate, which may be the current one
    const bool gained = better_iterate(best_bad_, best_worst_, start_bad_, start_worst_);
    return {reason, std::move(message), false, best_mean_, gained};
}

bool Phase::sound(const Stats& s, double objective) const {
    // -inf is a value the log-barrier gives on purpose (for a log sum it cannot take, so that the
    // line search rejects such a trial); NaN, +inf or a NaN t mean the arithmetic broke down.
    return s.nan == 0 && !std::isnan(objective) && objective != std::numeric_limits<double>::infinity() &&
           !std::isnan(objective_.progress_measure());
}

void Phase::restart_histories() {
    for (auto* history :
         {&best_history_, &measure_history_, &bad_history_, &stage_history_, &passes_history_, &gain_history_})
        *history = {history->back()};
}

void Phase::record(const Stats& s, double objective, double step, double gain) {
    IterationRecord r;
    r.iteration = summary_.iterations;
    r.phase = stage_.label();
    r.worst_quality = s.worst;
    r.best_worst_quality = best_worst_;
    r.mean_quality = s.mean;
    r.inverted = s.bad / work_.copies();  // an inverted element's copies are all inverted
    r.mu = objective_.subproblem_scale();
    r.t = objective_.subproblem_floor();
    r.objective = objective;
    r.step = step;
    r.gain = gain;
    r.moved = focusing_ ? focus_vertices_ : 0;
    r.seconds = seconds_since(start_);
    summary_.history.push_back(std::move(r));
    if (observer_) observer_(summary_.history.back());
}

}  // namespace paloverde::detail
