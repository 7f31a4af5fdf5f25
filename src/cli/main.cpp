#include <iostream>

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
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        const int code = app.exit(e);
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
