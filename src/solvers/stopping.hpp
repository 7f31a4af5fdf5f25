#pragma once
// The stopping rules every solver shares: which iterate is the best, when the budget (iterations,
// seconds) is spent or the target reached, and when progress has stalled over a window. In one
// place so that a new solver stops as the others do, and every process of a distributed run
// stops at the same iteration (its decisions rest on whole-mesh figures and the slowest clock).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <optional>
#include <span>
#include <string>

#include "paloverde/parallel/reducer.hpp"
#include "paloverde/solvers/stop.hpp"
#include "paloverde/solvers/summary.hpp"
#include "paloverde/solvers/termination.hpp"
#include "run_support.hpp"

namespace paloverde::detail {

// The rule for the best iterate: fewer inverted (non-positive) elements, then a higher worst
// quality. Whether (inverted, worst) beats (best_inverted, best_worst).
inline bool better_iterate(long inverted, double worst, long best_inverted, double best_worst) {
    return inverted < best_inverted || (inverted == best_inverted && worst > best_worst);
}

// The time limit (0: none) is up by the slowest process's clock. Collective when there is one.
inline bool time_is_up(double max_seconds, const Reducer& reducer, Clock::time_point start) {
    return max_seconds > 0.0 && reducer.max(seconds_since(start)) > max_seconds;
}

// At the top of iteration `iteration` (the first is 1): IterationLimit past max_iterations, then
// TimeLimit past max_seconds; nothing while there is budget left.
inline std::optional<TerminationReason> budget_spent(const TerminationCriterion& c, int iteration,
                                                     const Reducer& reducer, Clock::time_point start) {
    if (iteration > c.max_iterations) return TerminationReason::IterationLimit;
    if (time_is_up(c.max_seconds, reducer, start)) return TerminationReason::TimeLimit;
    return std::nullopt;
}

// What a solver says when budget_spent() stops it, its iterations being called `iterations`.
inline std::string budget_message(TerminationReason reason, const TerminationCriterion& c, const std::string& iterations) {
    if (reason == TerminationReason::IterationLimit) return "stopped after " + std::to_string(c.max_iterations) + " " + iterations;
    return "time limit reached";
}

inline bool target_reached(const TerminationCriterion& c, double best_worst) {
    return c.target_worst_quality && best_worst >= *c.target_worst_quality;
}

// The stall window of a TerminationCriterion over histories of one entry per iteration, the
// latest last: progress is measured against the entry progress_window iterations back, and is
// too little when below min_progress relative to `magnitude` (the current worst quality; at
// least 1e-3 in absolute terms). No history stalls before it spans a window.
class StallWindow {
public:
    StallWindow(const TerminationCriterion& c, double magnitude)
        : window_(static_cast<std::size_t>(c.progress_window)),
          tolerance_(c.min_progress * std::max(std::abs(magnitude), 1e-3)) {}

    bool spans(std::span<const double> history) const { return history.size() > window_; }
    // The least rise that counts as progress.
    double tolerance() const { return tolerance_; }
    // The history rose by no more than the tolerance over the window.
    bool rose_too_little(std::span<const double> history) const {
        return spans(history) && history.back() - history[history.size() - 1 - window_] <= tolerance_;
    }
    // The history (a count of inverted elements) did not fall over the window.
    bool did_not_fall(std::span<const double> history) const {
        return spans(history) && history.back() >= history[history.size() - 1 - window_];
    }

    // The history (a count) rose over the window.
    bool rose(std::span<const double> history) const {
        return spans(history) && history.back() > history[history.size() - 1 - window_];
    }
    // The history's mean rise per entry over the window (spans() must hold).
    double pace(std::span<const double> history) const {
        return (history.back() - history[history.size() - 1 - window_]) / static_cast<double>(window_);
    }
    std::size_t window() const { return window_; }

private:
    std::size_t window_;
    double tolerance_;
};

}  // namespace paloverde::detail
