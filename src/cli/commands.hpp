#pragma once
// One function per subcommand of the `paloverde` program; each adds itself to the app and runs
// when chosen. Exit codes: 0 done, 1 error, 2 bad usage, 3 finished but the target was not
// reached while the mesh is still valid.
#include <CLI/CLI.hpp>

namespace paloverde::cli {

enum ExitCode : int { kDone = 0, kError = 1, kUsage = 2, kTargetNotReached = 3 };

void add_quality_command(CLI::App& app, int& exit_code);
void add_convert_command(CLI::App& app, int& exit_code);
void add_improve_command(CLI::App& app, int& exit_code);
void add_perturb_command(CLI::App& app, int& exit_code);

}  // namespace paloverde::cli
