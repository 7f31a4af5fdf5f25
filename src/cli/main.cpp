#include <iostream>
#include <string_view>

#include "commands.hpp"
#include "paloverde/core/error.hpp"

int main(int argc, char** argv) {
    using namespace paloverde::cli;
    CLI::App app{"Paloverde: untangle and improve tetrahedral and triangle meshes by moving vertices"};
    app.require_subcommand(1);
    int exit_code = kDone;
    add_quality_command(app, exit_code);
    add_improve_command(app, exit_code);
    add_convert_command(app, exit_code);
    add_perturb_command(app, exit_code);
    add_run_command(app, exit_code);
    add_partition_command(app, exit_code);
    app.footer("Exit codes: 0 done, 1 error, 2 bad usage, 3 finished but a target was not reached (the mesh is "
               "valid). Run `paloverde COMMAND --help` for a command's options; docs/cli.md and docs/config.md.");
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        const int code = app.exit(e);
        // Earlier versions took a file name after `improve --json`.
        if (dynamic_cast<const CLI::ExtrasError*>(&e))
            for (int i = 1; i + 1 < argc; ++i)
                if (std::string_view(argv[i]) == "--json")
                    std::cerr << "paloverde: --json prints the summary on stdout; write it to a file with --summary "
                              << argv[i + 1] << "\n";
        return code == 0 ? kDone : kUsage;
    } catch (const paloverde::OptionError& e) {
        std::cerr << "paloverde: " << e.what() << "\n";
        return kUsage;
    } catch (const std::exception& e) {
        std::cerr << "paloverde: error: " << e.what() << "\n";
        return kError;
    }
    return exit_code;
}
