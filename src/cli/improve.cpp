#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "mpi_session.hpp"
#include "paloverde/config/registry.hpp"
#include "signals.hpp"

namespace paloverde::cli {

namespace {
// The help of a registry option, so a flag and its config key say the same thing.
std::string help_of(std::string_view kind, std::string_view name, std::string_view key) {
    for (const auto& option : config::describe(kind, name).options)
        if (option.key == key) return option.help;
    return "";
}

// What a solver does is read from its options in the registry, so a new solver takes the flags
// that fit it without this file naming it.
bool solver_has(const std::string& solver, std::string_view key) {
    return !help_of("solver", solver, key).empty();
}

// "global or local": the solvers that have `key`.
std::string solvers_with(std::string_view key) {
    std::vector<std::string> names;
    for (const auto& name : config::names_of("solver"))
        if (solver_has(name, key)) names.push_back(name);
    std::string out;
    for (std::size_t i = 0; i < names.size(); ++i)
        out += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
    return out;
}

// The help of a solver option, from the first solver that has it.
std::string solver_option_help(std::string_view key) {
    for (const auto& name : config::names_of("solver"))
        if (solver_has(name, key)) return help_of("solver", name, key);
    throw Error("no solver has the option '" + std::string(key) + "'");
}

// The solver an improve step runs when none is named.
std::string default_solver() {
    for (const auto& option : config::describe("section", "improve step").options)
        if (option.key == "name") return option.default_value;
    throw Error("the registry's improve step has no default solver");
}

// Each solver with the first sentence of its registry help.
std::string method_help() {
    std::string out;
    const std::string fallback = default_solver();
    for (const auto& name : config::names_of("solver")) {
        std::string help = config::describe("solver", name).help;
        help = help.substr(0, help.find(". "));
        if (help.ends_with('.')) help.pop_back();
        out += (out.empty() ? "" : "; ") + name + (name == fallback ? " (the default)" : "") + ": " + help;
    }
    return out;
}
}  // namespace

// `improve` is a one-step run: each flag stands for a config key (docs/cli.md lists them), so
// `--print-config` turns a command line into the equivalent config file. `morph` is the same run
// on a mesh whose boundary a point field moves (input.displacement), the input its reference.
namespace {
void add_improving_command(CLI::App& app, int& exit_code, bool morph) {
    struct Options {
        std::string input, output, method, history, summary, table, plot, fixed, metric, objective, threads, orientation;
        std::string iterations, target, time_limit, barrier_shrink, improve_below, boundary, feature_angle, domain;
        std::string checkpoint, checkpoint_every, resume, keep, reference, displacement, size_field, metric_field;
        bool untangle_only = false, no_untangle = false, ascii = false, steepest = false;
        ReportFlags report;
    };
    auto o = std::make_shared<Options>();
    CLI::App* cmd =
        morph ? app.add_subcommand("morph", "Move a mesh's boundary by a displacement field and bring the interior along: "
                                            "untangled, each element pulled toward its shape and size in the input (the "
                                            "motion followed in steps where one does not untangle); the flags of improve")
              : app.add_subcommand("improve", "Untangle a mesh (if it has inverted elements) and raise its worst element's "
                                              "quality: a run of one improve step, each flag a config key (see --print-config)");
    std::vector<std::string> methods = config::names_of("solver");
    for (std::size_t i = 0, n = methods.size(); i < n; ++i)  // earlier versions spelled them with hyphens
        if (std::string hyphens = methods[i]; std::replace(hyphens.begin(), hyphens.end(), '_', '-'), hyphens != methods[i])
            methods.push_back(hyphens);
    cmd->add_option("input", o->input, "Mesh to improve (input.mesh)")->required()->type_name("IN");
    cmd->add_option("-o,--output", o->output, "Where to write the improved mesh, .vtk .vtu .msh .mesh (output.mesh)")
        ->required()
        ->type_name("OUT");
    cmd->add_option("--method", o->method,
                    "Solver (queue[0].improve.name): " + method_help())
        ->check(CLI::IsMember(methods))
        ->type_name("NAME");
    cmd->add_option("--iterations", o->iterations,
                    "termination.max_iterations: " + help_of("termination", "termination", "max_iterations"))
        ->type_name("N");
    cmd->add_option("--target", o->target,
                    "termination.target_worst_quality: " + help_of("termination", "termination", "target_worst_quality"))
        ->type_name("Q");
    cmd->add_option("--time-limit", o->time_limit,
                    "termination.max_seconds (and untangle_termination.max_seconds): stop after this many seconds")
        ->type_name("SECONDS");
    cmd->add_flag("--untangle", o->untangle_only,
                  "Only untangle: stop once no element is inverted (improve_shape: false; --method " +
                      solvers_with("untangle") + ")");
    cmd->add_flag("--no-untangle", o->no_untangle, "Do not untangle; only improve a mesh that is already valid (untangle: false)");
    cmd->add_flag("--steepest", o->steepest, "Steepest ascent instead of conjugate gradient directions (direction; global)");
    cmd->add_option("--metric", o->metric, "metric: " + solver_option_help("metric"))
        ->type_name("NAME");
    cmd->add_option("--objective", o->objective, "objective: " + solver_option_help("objective"))
        ->type_name("NAME");
    cmd->add_option("--barrier-shrink", o->barrier_shrink,
                    "objective.barrier_shrink: " + help_of("objective", "log_barrier", "barrier_shrink"))
        ->type_name("X");
    cmd->add_option("--improve-below", o->improve_below, "improve_below (" + solvers_with("improve_below") + "): " + solver_option_help("improve_below"))
        ->type_name("X");
    cmd->add_option("--boundary", o->boundary,
                    "boundary (global, local): fixed, or slide: boundary vertices move on the input's boundary, "
                    "feature curves kept, corners fixed")
        ->type_name("MODE");
    cmd->add_option("--feature-angle", o->feature_angle,
                    "surface.feature_angle (global, local, with --boundary slide): boundary faces meeting at more than this "
                    "angle (degrees; default 40) make a feature curve that stays")
        ->type_name("DEG");
    cmd->add_option("--domain", o->domain,
                    "surface.domain (global, local): the analytic shape a surface mesh's vertices (or, with --boundary "
                    "slide, a tet mesh's boundary vertices) stay on, as a YAML map, e.g. '{shape: sphere, point: [0, 0, "
                    "0], radius: 10}' or '{shape: cylinder, point: [0, 0, 0], direction: [0, 0, 1], radius: 2}'; "
                    "default: the input's own triangles (docs/surfaces.md)")
        ->type_name("MAP");
    cmd->add_option("--keep", o->keep,
                    "targets.keep: what each element keeps of the input, any of size, orientation, aspect, skew (comma "
                    "separated) or all; the rest is made ideal. none: every element is pulled toward the regular "
                    "element; auto (the default): a mesh with cells keeps its aspect, one of tetrahedra or triangles "
                    "and a surface mesh nothing (docs/targets.md)")
        ->type_name("FACTORS");
    cmd->add_option("--size-field", o->size_field,
                    "targets.size_field: a point field of the input, one value per vertex, the edge length wanted there; "
                    "each element is sized by the mean of its vertices' values, its shape as --keep says")
        ->type_name("FIELD");
    if (!morph)
        cmd->add_option("--metric-field", o->metric_field,
                        "targets.metric_field: a point field of the input, the metric wanted at each vertex (6 values: "
                        "xx, yy, zz, xy, yz, xz, or the 9 of the matrix; edges e of unit length where e^T M e = 1); each "
                        "element is made the ideal element in the mean of its vertices' metrics (size, aspect, orientation)")
            ->type_name("FIELD");
    if (morph) {
        cmd->add_option("--displacement", o->displacement,
                        "input.displacement: the point field of IN (three components) that moves its fixed (boundary) "
                        "vertices; IN is the reference: every element's size, aspect and skew are taken from it "
                        "(targets.from_reference; its orientation is not, the motion turns elements)")
            ->required()
            ->type_name("FIELD");
    } else {
        cmd->add_option("--reference", o->reference,
                        "targets.reference: a mesh with the input's connectivity whose elements are the targets (every "
                        "factor --keep does not keep); its coordinates are where the boundary started: when the "
                        "input does not untangle, the boundary's motion is followed from there in steps")
            ->type_name("REF");
    }
    cmd->add_option("--fixed", o->fixed, "input.fixed: auto, boundary, file or none (which vertices stay put)")
        ->type_name("MODE");
    add_orientation_option(*cmd, o->orientation, "input.orientation: ");
    cmd->add_option("--threads", o->threads, "threads: threads of the solver; 0: OpenMP's default. Results do not depend on it")
        ->type_name("N");
    cmd->add_option("--history", o->history, "output.history: write the per-iteration history as CSV")
        ->type_name("FILE");
    cmd->add_option("--summary", o->summary, "output.summary: write the run's summary as JSON")
        ->type_name("FILE");
    cmd->add_option("--table", o->table, "output.table: write one CSV row with the outcome")
        ->type_name("FILE");
    cmd->add_option("--plot", o->plot, "output.plot: plot the worst quality per iteration and over time (SVG)")
        ->type_name("FILE");
    cmd->add_flag("--ascii", o->ascii, "output.ascii: write the mesh as text where the format has a binary form");
    cmd->add_option("--checkpoint", o->checkpoint,
                    "checkpoint.file (global, local): write the solver's state there every --checkpoint-every "
                    "iterations, every 300 s and on Ctrl-C / SIGTERM, to --resume from (docs/robustness.md)")
        ->type_name("FILE");
    cmd->add_option("--checkpoint-every", o->checkpoint_every,
                    "checkpoint.every_iterations: write the checkpoint every N iterations (sweeps for local)")
        ->type_name("N");
    cmd->add_option("--resume", o->resume,
                    "checkpoint.resume: continue from this checkpoint (same input and options) to the result the "
                    "uninterrupted run gives")
        ->type_name("FILE");
    o->report.add_to(*cmd);
    stop_on_signals(*cmd);
    cmd->footer("Exit codes: 0 done, 1 error (including \"could not untangle\"), 2 bad usage, 3 --target not reached "
                "(the mesh is valid), 4 interrupted by Ctrl-C or SIGTERM (the best mesh so far was written).");
    cmd->callback([o, &exit_code, morph] {
        std::vector<config::Override> set;
        auto flag = [&](const std::string& key, const std::string& value, const std::string& source, bool literal = false) {
            set.push_back({key + "=" + value, source, literal});
        };
        const std::string step = "queue[0].improve.";
        std::string method = o->method;
        std::replace(method.begin(), method.end(), '-', '_');
        const std::string solver = method.empty() ? default_solver() : method;
        flag("input.mesh", o->input, "input", true);
        flag("output.mesh", o->output, "--output", true);
        if (!method.empty()) flag(step + "name", method, "--method");
        if (!o->iterations.empty()) flag(step + "termination.max_iterations", o->iterations, "--iterations");
        if (!o->target.empty()) flag(step + "termination.target_worst_quality", o->target, "--target");
        if (!o->time_limit.empty()) {
            flag(step + "termination.max_seconds", o->time_limit, "--time-limit");
            if (solver_has(solver, "untangle_termination"))
                flag(step + "untangle_termination.max_seconds", o->time_limit, "--time-limit");
        }
        if (!solver_has(solver, "untangle") && (o->untangle_only || o->no_untangle))
            throw OptionError(std::string(o->untangle_only ? "--untangle" : "--no-untangle") + ": --method " + method +
                              " does not untangle (it moves vertices whatever is inverted); untangle with --method " +
                              solvers_with("untangle"));
        if (o->untangle_only) flag(step + "improve_shape", "false", "--untangle");
        if (o->no_untangle) flag(step + "untangle", "false", "--no-untangle");
        if (o->steepest) flag(step + "direction", "steepest_ascent", "--steepest");
        if (!o->metric.empty()) flag(step + "metric.name", o->metric, "--metric");
        if (!o->objective.empty()) flag(step + "objective.name", o->objective, "--objective");
        if (!o->barrier_shrink.empty()) flag(step + "objective.barrier_shrink", o->barrier_shrink, "--barrier-shrink");
        if (!o->improve_below.empty()) flag(step + "improve_below", o->improve_below, "--improve-below");
        if (!o->domain.empty()) {
            if (!solver_has(solver, "surface"))
                throw OptionError("--domain: only some solvers keep vertices on a domain (--method " +
                                  solvers_with("surface") + ")");
            flag(step + "surface.domain", o->domain, "--domain");
        }
        if (!o->boundary.empty() || !o->feature_angle.empty()) {
            if (solver_has(solver, "boundary")) {
                if (!o->boundary.empty()) flag(step + "boundary", o->boundary, "--boundary");
                if (!o->feature_angle.empty()) flag(step + "surface.feature_angle", o->feature_angle, "--feature-angle");
            } else if (!o->feature_angle.empty() || o->boundary != "fixed") {
                throw OptionError(std::string(o->feature_angle.empty() ? "--boundary " + o->boundary : "--feature-angle") +
                                  ": only some solvers slide boundary vertices (--method " + solvers_with("boundary") +
                                  "); the " + method + " method keeps the boundary fixed");
            }
        }
        if (!o->keep.empty()) flag("targets.keep", "[" + o->keep + "]", "--keep");
        if (!o->reference.empty()) flag("targets.reference", o->reference, "--reference", true);
        if (!o->size_field.empty()) flag("targets.size_field", o->size_field, "--size-field", true);
        if (!o->metric_field.empty()) flag("targets.metric_field", o->metric_field, "--metric-field", true);
        if (morph) {
            flag("input.displacement", o->displacement, "--displacement", true);
            // Everything but the orientation comes from the input as read (--keep may add it), the
            // size from the size field where one is given.
            flag("targets.from_reference", o->size_field.empty() ? "[size,aspect,skew]" : "[aspect,skew]", "morph");
        }
        if (!o->fixed.empty()) flag("input.fixed", o->fixed, "--fixed");
        if (!o->orientation.empty()) flag("input.orientation", o->orientation, "--orientation");
        if (!o->threads.empty()) flag("threads", o->threads, "--threads");
        if (!o->history.empty()) flag("output.history", o->history, "--history", true);
        if (!o->summary.empty()) flag("output.summary", o->summary, "--summary", true);
        if (!o->table.empty()) flag("output.table", o->table, "--table", true);
        if (!o->plot.empty()) flag("output.plot", o->plot, "--plot", true);
        if (o->ascii) flag("output.ascii", "true", "--ascii");
        // Under `mpirun -n N`, the mesh is split into N parts, one per rank.
        if (const int ranks = MpiSession::size(); ranks > 1)
            flag("partition.parts", std::to_string(ranks), "mpirun -n " + std::to_string(ranks));
        if (!o->checkpoint.empty()) flag(step + "checkpoint.file", o->checkpoint, "--checkpoint", true);
        if (!o->checkpoint_every.empty()) flag(step + "checkpoint.every_iterations", o->checkpoint_every, "--checkpoint-every");
        if (!o->resume.empty()) flag(step + "checkpoint.resume", o->resume, "--resume", true);
        for (const auto& s : o->report.sets) set.push_back({s, "--set"});
        // A bad flag value names the input too (execute() does so for the run's own errors).
        config::RunSpec spec;
        naming_input({o->input}, [&] { spec = config::parse_config("", "improve", set); });
        exit_code = execute(spec, o->report);
    });
}

}  // namespace

void add_improve_command(CLI::App& app, int& exit_code) { add_improving_command(app, exit_code, false); }
void add_morph_command(CLI::App& app, int& exit_code) { add_improving_command(app, exit_code, true); }

}  // namespace paloverde::cli
