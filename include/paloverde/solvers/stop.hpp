#pragma once
// A request to stop every running solver early: the command line's SIGINT/SIGTERM handlers make
// it, tests make it from an observer. Solvers look at it once per iteration (distributed runs:
// agreed over the ranks, so all stop at the same iteration) and end on their best iterate with
// TerminationReason::Interrupted. It stays set until cleared, so the steps of a queue that come
// after the interrupted one stop at once too.
namespace paloverde {

void request_stop() noexcept;  // async-signal-safe: one lock-free atomic store
bool stop_requested() noexcept;
void clear_stop_request() noexcept;

}  // namespace paloverde
