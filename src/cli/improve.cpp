#include <iostream>
#include <memory>
#include <string>

#include "commands.hpp"
#include "paloverde/assess/quality_assessor.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/io/atomic_file.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "paloverde/solvers/laplace_solver.hpp"
#include "paloverde/solvers/local_solver.hpp"

namespace paloverde::cli {

void add_improve_command(CLI::App& app, int& exit_code) {
    // Options bind straight to the solver's options struct: one set of defaults.
    struct Options {
        std::string input, output, history, json, method = "global";
        bool untangle_only = false, no_untangle = false, quiet = false, ascii = false, steepest = false;
        std::optional<double> target;
        GlobalSolverOptions solver;
        LocalSolverOptions local;
    };
    auto o = std::make_shared<Options>();
    GlobalSolverOptions& s = o->solver;
    CLI::App* cmd = app.add_subcommand(
        "improve", "Untangle a mesh (if it has inverted elements) and raise its worst element's quality");
    cmd->add_option("input", o->input, "Mesh to improve")->required();
    cmd->add_option("-o,--output", o->output, "Where to write the improved mesh (.vtk .vtu .msh .mesh)")->required();
    cmd->add_option("--method", o->method,
                    "Solver: global (log-barrier over the whole mesh), local (Freitag-Plassmann max-min per vertex, "
                    "by colors), smart-laplace, or laplace (may invert elements)")
        ->check(CLI::IsMember({"global", "local", "laplace", "smart-laplace"}))
        ->capture_default_str();
    cmd->add_option("--improve-below", o->local.improve_below,
                    "Local method: move only vertices whose worst element is in this lowest fraction of the range worst..ideal")
        ->capture_default_str();
    cmd->add_option("--iterations", s.termination.max_iterations, "Most shape-improvement iterations")
        ->capture_default_str();
    cmd->add_flag("--untangle", o->untangle_only, "Only untangle: stop once no element is inverted");
    cmd->add_flag("--no-untangle", o->no_untangle, "Do not untangle; only improve a mesh that is already valid");
    cmd->add_flag("--steepest", o->steepest, "Steepest ascent instead of conjugate gradient directions");
    cmd->add_option("--objective", s.objective, "Objective: log_barrier, p_mean or min_quality")->capture_default_str();
    cmd->add_option("--metric", s.shape_metric, "Shape metric: aspect_ratio, mean_ratio, inverse_condition, edge_ratio")
        ->capture_default_str();
    cmd->add_option("--barrier-shrink", s.objective_options.barrier_shrink,
                    "Log-barrier: mu is multiplied by this after each round of steps, in (0, 1]")
        ->capture_default_str();
    cmd->add_option("--target", o->target, "Stop once the worst quality reaches this value");
    cmd->add_option("--time-limit", s.termination.max_seconds, "Stop after this many seconds (0: no limit)");
    cmd->add_option("--threads", s.threads, "Threads (0: OpenMP's default); results do not depend on it");
    cmd->add_option("--history", o->history, "Write the per-iteration history as CSV");
    cmd->add_option("--json", o->json, "Write the summary as JSON");
    cmd->add_flag("--ascii", o->ascii, "Write the mesh as text where the format has a binary form");
    cmd->add_flag("-q,--quiet", o->quiet, "Print nothing but errors");
    cmd->callback([o, &exit_code] {
        GlobalSolverOptions options = o->solver;
        if (o->steepest) options.direction = GlobalSolverOptions::Direction::SteepestAscent;
        options.untangle = !o->no_untangle;
        options.improve_shape = !o->untangle_only;
        options.untangle_termination.max_seconds = options.termination.max_seconds;
        options.termination.target_worst_quality = o->target;
        // Each solver is built (and its options validated) before the mesh is read.
        std::unique_ptr<Solver> solver;
        if (o->method == "global") {
            solver = std::make_unique<GlobalSolver>(options);
        } else if (o->method == "local") {
            if (o->untangle_only) throw OptionError("--untangle: only the global method stops after untangling");
            LocalSolverOptions local = o->local;
            local.metric = options.shape_metric;
            local.untangle = options.untangle;
            local.termination.max_iterations = options.termination.max_iterations;
            local.termination.max_seconds = options.termination.max_seconds;
            local.termination.target_worst_quality = o->target;
            local.untangle_termination.max_seconds = options.termination.max_seconds;
            local.threads = options.threads;
            solver = std::make_unique<LocalSolver>(local);
        } else {
            if (o->untangle_only || o->no_untangle)
                throw OptionError("--untangle/--no-untangle: the Laplace methods do not untangle");
            LaplaceSolverOptions laplace;
            laplace.smart = o->method == "smart-laplace";
            laplace.metric = options.shape_metric;
            laplace.termination.max_iterations = options.termination.max_iterations;
            laplace.termination.max_seconds = options.termination.max_seconds;
            laplace.termination.target_worst_quality = o->target;
            laplace.threads = options.threads;
            solver = std::make_unique<LaplaceSolver>(laplace);
        }

        MeshFile file = read_mesh(o->input);
        const Summary summary = solver->improve(file.mesh);

        WriteOptions write;
        write.encoding = o->ascii ? Encoding::Ascii : Encoding::Binary;
        write_mesh(o->output, file.mesh, write, file.point_fields);
        if (!o->history.empty()) write_text_file(o->history, summary.history_csv());
        if (!o->json.empty()) write_text_file(o->json, summary.to_json() + "\n");
        if (!o->quiet) std::cout << summary.full_report();
        if (!summary.success()) {
            std::cerr << "paloverde: " << summary.message << "\n";
            exit_code = kError;
        } else if (o->target && summary.reason != TerminationReason::TargetReached) {
            exit_code = kTargetNotReached;
        } else {
            exit_code = kDone;
        }
    });
}

}  // namespace paloverde::cli
