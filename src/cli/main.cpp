#include <iostream>
#include <optional>
#include <streambuf>
#include <string_view>
#include <vector>

#include "commands.hpp"
#include "mpi_session.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/core/memory.hpp"
#include "signals.hpp"

namespace {
// Where the console output of ranks other than 0 goes, while this lives.
class Silence {
public:
    explicit Silence(bool on) {
        if (!on) return;
        for (std::ostream* s : {&std::cout, &std::cerr, &std::clog}) saved_.push_back(s->rdbuf(&null_));
    }
    ~Silence() {
        std::ostream* streams[] = {&std::cout, &std::cerr, &std::clog};
        for (std::size_t i = 0; i < saved_.size(); ++i) streams[i]->rdbuf(saved_[i]);
    }
    Silence(const Silence&) = delete;
    Silence& operator=(const Silence&) = delete;

private:
    struct Null : std::streambuf {
        int overflow(int c) override { return c; }
    } null_;
    std::vector<std::streambuf*> saved_;
};
}  // namespace

int main(int argc, char** argv) {
    using namespace paloverde::cli;
    paloverde::keep_freed_memory();  // arrays below 2 MiB, and larger ones where not on huge pages (huge_pages.cpp)
    // A build without MPI refuses to run under an MPI launcher, before any command runs.
    std::optional<MpiSession> mpi;
    try {
        mpi.emplace();
    } catch (const std::exception& e) {
        std::cerr << "paloverde: error: " << e.what() << "\n";
        return kError;
    }
    const bool root = MpiSession::rank() == 0;
    // Every rank runs the command, and its errors are thrown on every rank: rank 0 tells.
    const Silence others(!root);
    CLI::App app{"Paloverde: untangle and improve meshes by moving vertices: tetrahedra, hexahedra, wedges and "
                 "pyramids (mixed too), planar triangles and quadrilaterals, and surfaces of triangles and quadrilaterals in 3D (kept on themselves)"};
    app.require_subcommand(1);
    int exit_code = kDone;
    add_quality_command(app, exit_code);
    add_improve_command(app, exit_code);
    add_morph_command(app, exit_code);
    add_convert_command(app, exit_code);
    add_perturb_command(app, exit_code);
    add_run_command(app, exit_code);
    add_partition_command(app, exit_code);
    stop_on_signals(*app.get_subcommand("run"));  // improve installs its own
    app.footer("Exit codes: 0 done, 1 error, 2 bad usage, 3 finished but a target was not reached (the mesh is "
               "valid), 4 interrupted (the best mesh so far is written). Run `paloverde COMMAND --help` for a command's options; docs/cli.md and docs/config.md. "
               "Under mpirun, `run` and `improve` split the mesh over the ranks (docs/config.md, \"Partitioned runs\").");
    // Under mpirun, the commands that do not distribute work on rank 0 alone (the others would
    // write the same files at the same time).
    if (!root)
        for (const char* serial : {"quality", "convert", "perturb", "partition"})
            app.get_subcommand(serial)->callback([&exit_code] { exit_code = kDone; });
    const int code = [&]() -> int {
        try {
            app.parse(argc, argv);
        } catch (const CLI::ParseError& e) {
            const int status = app.exit(e);
            // Earlier versions took a file name after `improve --json`.
            if (dynamic_cast<const CLI::ExtrasError*>(&e))
                for (int i = 1; i + 1 < argc; ++i)
                    if (std::string_view(argv[i]) == "--json")
                        std::cerr << "paloverde: --json prints the summary on stdout; write it to a file with --summary "
                                  << argv[i + 1] << "\n";
            return status == 0 ? kDone : kUsage;
        } catch (const paloverde::OptionError& e) {
            std::cerr << "paloverde: " << e.what() << "\n";
            return kUsage;
        } catch (const std::exception& e) {
            std::cerr << "paloverde: error: " << e.what() << "\n";
            return kError;
        }
        return exit_code;
    }();
    std::cout.flush();
    // Every rank exits with the same code (rank 0's, for the commands only rank 0 runs).
    return MpiSession::agree(code);
}
