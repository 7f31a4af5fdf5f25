// The phase's state in checkpoints: what an iteration carries over to the next, saved at the top
// of an iteration and restored there.
#include <limits>

#include "global_phase.hpp"

namespace paloverde::detail {

void Phase::save_checkpoint(int iteration) {
    SolverState state;
    state.numbers = {{"untangling", stage_.untangling() ? 1.0 : 0.0},
                     {"finish", stage_.finish() ? 1.0 : 0.0},
                     {"fresh", stage_.fresh() ? 1.0 : 0.0},
                     {"polish", stage_.polish() ? 1.0 : 0.0},
                     {"close_start", stage_.close_start ? 1.0 : 0.0},
                     {"shape_reason", static_cast<double>(stage_.shape_reason)},
                     {"mean_goal", stage_.mean_goal},
                     {"best_mean", best_mean_},
                     {"round", stage_.round},
                     {"budget", stop_.max_iterations},
                     {"iteration", iteration},
                     {"best_worst", best_worst_},
                     {"best_bad", static_cast<double>(best_bad_)},
                     {"start_worst", start_worst_},
                     {"start_bad", static_cast<double>(start_bad_)},
                     {"step", step_},
                     {"first_gradient_norm", first_gradient_norm_},
                     {"restart", restart_ ? 1.0 : 0.0},
                     {"failures", failures_},
                     {"steps_at_mu", steps_at_mu_},
                     {"let_go_steps", let_go_steps_},
                     {"quick_solves", quick_solves_},
                     {"first_t", first_t_},
                     {"first_gap", first_gap_},
                     {"newton_damping", newton_damping_},
                     {"focus_base", focus_base_},
                     {"focus_top", focus_top_},
                     {"focus_band", band_},
                     {"widened_at", widened_at_},
                     {"shrunk_at", shrunk_at_}};
    state.lists = {{"objective", objective_.state()},
                   {"best_history", best_history_},
                   {"measure_history", measure_history_},
                   {"bad_history", bad_history_},
                   {"stage_history", stage_history_},
                   {"passes_history", passes_history_},
                   {"gain_history", gain_history_}};
    state.vertex_fields = {{"x", x_},
                           {"best_x", best_x_},
                           {"direction", direction_},
                           {"previous_gradient", previous_gradient_},
                           {"previous_preconditioned", previous_preconditioned_}};
    if (focusing_) {
        std::vector<double> moving(3 * moving_.size(), 0.0);
        for (std::size_t v = 0; v < moving_.size(); ++v) moving[3 * v] = moving_[v];
        state.vertex_fields["moving"] = std::move(moving);
    }
    checkpointer_.save(summary_, state, seconds_since(start_));
}

// The state saved at the top of an iteration; returns that iteration. The qualities, the
// objective and its weights are recomputed from the coordinates (each element's quality is a
// function of its corners alone, so they come out bit for bit as they were).
int Phase::restore(const SolverState& state, double& objective) {
    const std::size_t n = x_.size() / 3;
    x_ = state.vertex_field("x", n);
    trial_x_ = x_;
    best_x_ = state.vertex_field("best_x", n);
    direction_ = state.vertex_field("direction", n);
    previous_gradient_ = state.vertex_field("previous_gradient", n);
    previous_preconditioned_ = state.vertex_field("previous_preconditioned", n);
    best_worst_ = state.number("best_worst");
    best_bad_ = static_cast<long>(state.number("best_bad"));
    if (state.numbers.contains("start_worst")) {
        start_worst_ = state.number("start_worst");
        start_bad_ = static_cast<long>(state.number("start_bad"));
    }
    if (state.numbers.contains("best_mean")) best_mean_ = state.number("best_mean");
    step_ = state.number("step");
    first_gradient_norm_ = state.number("first_gradient_norm");
    restart_ = state.number("restart") != 0.0;
    failures_ = static_cast<int>(state.number("failures"));
    steps_at_mu_ = static_cast<int>(state.number("steps_at_mu"));
    let_go_steps_ = state.numbers.contains("let_go_steps") ? static_cast<int>(state.number("let_go_steps")) : 0;
    if (state.numbers.contains("newton_damping")) newton_damping_ = state.number("newton_damping");
    if (state.numbers.contains("quick_solves")) quick_solves_ = static_cast<int>(state.number("quick_solves"));
    if (state.numbers.contains("first_gap")) {
        first_t_ = state.number("first_t");
        first_gap_ = state.number("first_gap");
    }
    if (state.numbers.contains("shrunk_at")) shrunk_at_ = state.number("shrunk_at");
    objective_.restore_state(state.list("objective"));
    best_history_ = state.list("best_history");
    measure_history_ = state.list("measure_history");
    bad_history_ = state.list("bad_history");
    stage_history_ = state.list("stage_history");
    // (Checkpoints from before it have none: the gains are unknown, so no calm handover in this phase.)
    gain_history_ = state.lists.contains("gain_history")
                        ? state.list("gain_history")
                        : std::vector<double>(best_history_.size(), std::numeric_limits<double>::infinity());
    passes_history_ = state.list("passes_history");
    if (focusing_) {
        const auto& moving = state.vertex_field("moving", n);
        moving_.assign(n, 0);
        for (std::size_t v = 0; v < n; ++v) moving_[v] = moving[3 * v] != 0.0;
        focus_base_ = state.number("focus_base");
        focus_top_ = state.number("focus_top");
        band_ = state.number("focus_band");
        widened_at_ = state.number("widened_at");
        focus_on_moving();
        restart_ = state.number("restart") != 0.0;  // focusing restarts a new focus's directions, not this one's
    }
    work_.evaluate(metric_, x_, q_);
    objective = objective_value(q_);
    objective_.weights(q_, weight_);
    return static_cast<int>(state.number("iteration"));
}

}  // namespace paloverde::detail
