#pragma once
// Ctrl-C (SIGINT) and SIGTERM while `improve` or `run` works: the first asks the solvers to stop
// (paloverde::request_stop): they end on their best iterate, the outputs are written as usual
// and the exit code is 4. A second signal of either kind ends the process at once.
#include <CLI/CLI.hpp>

namespace paloverde::cli {

// Installs the handlers when `command` is chosen, before its options are parsed.
void stop_on_signals(CLI::App& command);

}  // namespace paloverde::cli
