#include "signals.hpp"

#include <signal.h>

#include "paloverde/solvers/stop.hpp"

namespace paloverde::cli {

namespace {

// Only async-signal-safe calls: a lock-free atomic, signal() and raise().
extern "C" void on_stop_signal(int number) {
    if (paloverde::stop_requested()) {
        // Asked twice: the user does not want to wait for the current iteration.
        ::signal(number, SIG_DFL);
        ::raise(number);
        return;
    }
    paloverde::request_stop();
}

void install() {
    struct sigaction action {};
    action.sa_handler = on_stop_signal;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESTART;  // reads and writes under way go on
    ::sigaction(SIGINT, &action, nullptr);
    ::sigaction(SIGTERM, &action, nullptr);
}

}  // namespace

void stop_on_signals(CLI::App& command) {
    command.preparse_callback([](std::size_t) { install(); });
}

}  // namespace paloverde::cli
