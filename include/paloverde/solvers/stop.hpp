#pragma once
// A request to stop every running solver early: the command line's SIGINT/SIGTERM handlers make
// it, tests make it from an observer. Solvers look at it once per iteration (distributed runs:
// agreed over the ranks, so all stop at the same iteration) and end on their best iterate with
// TerminationReason::Interrupted. It stays set until cleared, so the steps of a queue that come
// after the interrupted one stop at once too.
#include "paloverde/parallel/reducer.hpp"

namespace paloverde {

void request_stop() noexcept;  // async-signal-safe: one lock-free atomic store
bool stop_requested() noexcept;
void clear_stop_request() noexcept;
// A stop was requested on any process of the reducer's run (collective; serially, here), so
// that every process stops at the same iteration.
bool stop_requested_anywhere(const Reducer& reducer);

}  // namespace paloverde
