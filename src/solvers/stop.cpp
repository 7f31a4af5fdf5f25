#include "paloverde/solvers/stop.hpp"

#include <atomic>

namespace paloverde {

namespace {
// Lock-free, hence safe to store from a signal handler.
std::atomic<bool> stop_flag{false};
static_assert(std::atomic<bool>::is_always_lock_free);
}  // namespace

void request_stop() noexcept { stop_flag.store(true, std::memory_order_relaxed); }
bool stop_requested() noexcept { return stop_flag.load(std::memory_order_relaxed); }
void clear_stop_request() noexcept { stop_flag.store(false, std::memory_order_relaxed); }
bool stop_requested_anywhere(const Reducer& reducer) { return reducer.max(stop_requested() ? 1.0 : 0.0) > 0.0; }

}  // namespace paloverde
