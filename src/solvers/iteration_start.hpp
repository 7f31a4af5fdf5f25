#pragma once
// The top of a solver's iteration, written once: a stop request ends the run (after a checkpoint,
// where checkpoints are written), a checkpoint that is due is taken, then the target and the
// budget are judged. Every iterating loop (the global phases, the untangling energy, the local
// sweeps, Laplace) starts its iterations here, so that they stop by the same rules, in the same
// order and in the same words. Its decisions rest on whole-run figures (a stop requested on any
// process, the slowest clock), so every process of a distributed run stops at the same iteration.
#include <optional>
#include <string>
#include <utility>

#include "checkpointer.hpp"
#include "paloverde/solvers/stop.hpp"
#include "stopping.hpp"

namespace paloverde::detail {

// Why a loop does not start its next iteration, in the Summary's words.
struct Stop {
    TerminationReason reason;
    std::string message;
};

class IterationStart {
public:
    // `unit`: what the loop calls its iterations ("iterations", "sweeps"); `checkpointer`: none for
    // a solver without checkpoints; `during`: what the loop is doing, for its messages (empty, or
    // e.g. "while untangling").
    IterationStart(TerminationCriterion criterion, const Reducer& reducer, Clock::time_point start, std::string unit,
                   Checkpointer* checkpointer = nullptr, std::string during = {})
        : criterion_(std::move(criterion)), reducer_(reducer), start_(start), unit_(std::move(unit)),
          during_(during.empty() ? std::string() : " " + std::move(during)), checkpointer_(checkpointer) {}

    // At the top of the loop's iteration `iteration` (its first is 1), with `done` iterations of
    // the whole run behind it (Summary::iterations: what checkpoints count and messages report).
    // `save()` writes the loop's checkpoint, its state being complete here. `best_worst`: the best
    // worst quality so far, for a loop that stops at the target before an iteration (none: the
    // loop judges the target where it measures). Collective.
    template <class Save>
    std::optional<Stop> operator()(int iteration, int done, Save&& save, std::optional<double> best_worst = std::nullopt) {
        if (stop_requested_anywhere(reducer_)) {
            if (checkpointer_ && checkpointer_->writes()) save();
            return Stop{TerminationReason::Interrupted, interrupted(done)};
        }
        if (checkpointer_ && checkpointer_->due(done)) save();
        if (best_worst && target_reached(criterion_, *best_worst))
            return Stop{TerminationReason::TargetReached, "the worst quality reached the target"};
        if (const auto spent = budget_spent(criterion_, iteration, reducer_, start_))
            return Stop{*spent, budget_message(*spent, criterion_, unit_) + during_};
        return std::nullopt;
    }

    // What a run stopped by a request says, `done` iterations in.
    std::string interrupted(int done) const {
        return "interrupted (a stop was requested) after " + std::to_string(done) + " " + unit_ + during_;
    }

private:
    TerminationCriterion criterion_;
    const Reducer& reducer_;
    Clock::time_point start_;
    std::string unit_, during_;
    Checkpointer* checkpointer_;
};

}  // namespace paloverde::detail
