#include <iostream>
#include <memory>
#include <string>

#include "commands.hpp"
#include "mpi_session.hpp"
#include "paloverde/config/run.hpp"
#include "paloverde/core/error.hpp"
#include "progress.hpp"

namespace paloverde::cli {

void ReportFlags::add_to(CLI::App& command) {
    command.add_option("--set", sets,
                       "Set a config key: key.path=value (the value is YAML), e.g. "
                       "--set queue[0].improve.termination.max_iterations=50. Repeatable; applied in order, checked "
                       "like the config file")
        ->type_name("KEY=VALUE")
        ->allow_extra_args(false);
    command.add_flag("--print-config", print_config,
                     "Print the fully resolved config (every key, with defaults) as YAML and exit without running");
    command.add_flag("--json", json, "Print the run's summary as JSON on stdout instead of the text report");
    command.add_flag("-q,--quiet", quiet, "Print nothing but errors (no progress line, no report)");
}

namespace {
std::string joined(const std::vector<std::string>& names) {
    std::string out;
    for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
    return out;
}

std::vector<std::string> inputs_of(const config::RunSpec& spec) {
    if (!spec.input.mesh.empty()) return {spec.input.mesh};
    return spec.input.pieces;
}
}  // namespace

void naming_input(const std::vector<std::string>& inputs, const std::function<void()>& work) {
    const auto named = [&](const std::string& message) {
        for (const auto& input : inputs)
            if (message.find(input) != std::string::npos) return message;
        return joined(inputs) + ": " + message;
    };
    if (inputs.empty()) return work();
    try {
        work();
    } catch (const OptionError& e) {
        throw OptionError(named(e.what()));
    } catch (const Error& e) {
        throw Error(named(e.what()));
    }
}

int execute(const config::RunSpec& spec, const ReportFlags& flags) {
    if (flags.print_config) {
        std::cout << config::to_yaml(spec);
        return kDone;
    }
    // A partitioned config runs without mpirun too, as a run of one rank.
    if (config::runs_distributed(spec)) MpiSession::ensure();
    const std::vector<std::string> inputs = inputs_of(spec);
    ProgressLine progress(!flags.quiet && MpiSession::rank() == 0 && ProgressLine::terminal());
    config::RunResult result;
    naming_input(inputs, [&] { result = config::run(spec, progress.hooks()); });
    progress.finish();
    if (flags.json) std::cout << result.to_json() << "\n";
    else if (!flags.quiet) std::cout << result.report();
    for (const auto& m : result.methods)
        if (m.status == config::RunStatus::Failed)
            std::cerr << "paloverde: " << joined(inputs) << ": " << (result.methods.size() > 1 ? m.name + ": " : std::string())
                      << m.message << "\n";
    return result.exit_code();
}

void add_run_command(CLI::App& app, int& exit_code) {
    struct Options {
        std::string config;
        std::string threads;
        bool describe = false;
        ReportFlags report;
    };
    auto o = std::make_shared<Options>();
    CLI::App* cmd = app.add_subcommand(
        "run", "Run a config file: the input mesh, the instruction queue (or a study of several methods) and the "
               "outputs (docs/config.md)");
    cmd->add_option("config", o->config,
                    "The run config (YAML). Without one, the config is the defaults plus --set (e.g. --set "
                    "input.mesh=in.vtk --set output.mesh=out.vtu)")
        ->type_name("CONFIG");
    cmd->add_option("--threads", o->threads, "Threads of every solver (the key `threads`); 0: OpenMP's default")
        ->type_name("N");
    o->report.add_to(*cmd);
    cmd->add_flag("--describe", o->describe,
                  "Print every solver, objective, metric, wrapper and config section with its options, types and "
                  "defaults (the reference of docs/config.md) and exit");
    cmd->footer("Exit codes: 0 done, 1 error, 2 bad usage or config, 3 a target_worst_quality was not reached "
                "(the mesh is valid).");
    cmd->callback([o, &exit_code] {
        if (o->describe) {
            std::cout << config::registry_markdown();
            exit_code = kDone;
            return;
        }
        std::vector<config::Override> overrides;
        if (!o->threads.empty()) overrides.push_back({"threads=" + o->threads, "--threads"});
        for (const auto& s : o->report.sets) overrides.push_back({s, "--set"});
        const config::RunSpec spec = o->config.empty() ? config::parse_config("", "--set", overrides)
                                                       : config::read_config(o->config, overrides);
        exit_code = execute(spec, o->report);
    });
}

}  // namespace paloverde::cli
