#pragma once
// One function per subcommand of the `paloverde` program; each adds itself to the app and runs
// when chosen. Exit codes (docs/cli.md): 0 done, 1 error (unreadable input, a solver that could
// not untangle, an unwritable output), 2 bad usage (a flag, a config key or value), 3 finished
// but a target was not reached while the mesh is still valid.
#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

#include "paloverde/config/config.hpp"

namespace paloverde::cli {

enum ExitCode : int { kDone = 0, kError = 1, kUsage = 2, kTargetNotReached = 3 };

void add_quality_command(CLI::App& app, int& exit_code);
void add_convert_command(CLI::App& app, int& exit_code);
void add_improve_command(CLI::App& app, int& exit_code);
void add_morph_command(CLI::App& app, int& exit_code);
void add_perturb_command(CLI::App& app, int& exit_code);
void add_run_command(CLI::App& app, int& exit_code);
void add_partition_command(CLI::App& app, int& exit_code);

// What `run` and `improve` share: how to report.
struct ReportFlags {
    bool print_config = false;  // print the resolved config instead of running
    bool json = false;          // the summary as JSON on stdout instead of the text report
    bool quiet = false;         // nothing but errors (and --json's output)
    std::vector<std::string> sets;  // --set key.path=value, in order

    void add_to(CLI::App& command);
};

// --orientation MODE, the same choice as the config key input.orientation.
inline CLI::Option* add_orientation_option(CLI::App& command, std::string& mode, const std::string& key_note = "") {
    return command
        .add_option("--orientation", mode,
                    key_note + "the file's element orientation convention: auto (flip every element when the total "
                               "signed volume is negative, the default), as_is, or flipped; outputs keep the file's order")
        ->check(CLI::IsMember({"auto", "as_is", "flipped"}))
        ->type_name("MODE");
}
inline OrientationMode orientation_mode(const std::string& mode) {
    return mode == "as_is" ? OrientationMode::AsIs : mode == "flipped" ? OrientationMode::Flipped : OrientationMode::Auto;
}

// Runs (or prints) a resolved config and returns the exit code. Its errors and failure messages
// name the input (a batch of runs must tell which input failed).
int execute(const config::RunSpec& spec, const ReportFlags& flags);

// Runs `work`; an error whose message names none of `inputs` is thrown again (of the same kind
// for the exit code: usage or not) with "INPUT: " in front, INPUT the inputs joined by ", ".
void naming_input(const std::vector<std::string>& inputs, const std::function<void()>& work);

}  // namespace paloverde::cli
