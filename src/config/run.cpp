#include "paloverde/config/run.hpp"

#include <algorithm>
#include <chrono>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "config/partitioned_run.hpp"
#include "config/plot.hpp"
#include "config/registry_internal.hpp"
#include "paloverde/io/atomic_file.hpp"
#include "paloverde/mesh/boundary_surface.hpp"
#include "paloverde/solvers/stop.hpp"
#include "solvers/run_support.hpp"
#include "solvers/sliding_boundary.hpp"

namespace paloverde::config {

std::string_view to_string(RunStatus status) {
    switch (status) {
        case RunStatus::Done: return "done";
        case RunStatus::Failed: return "failed";
        case RunStatus::TargetNotReached: return "target_not_reached";
        case RunStatus::Interrupted: return "interrupted";
    }
    return "unknown";
}

namespace detail {

namespace {
// An assess step's assessor (`metrics: []` stands for QualityAssessor()'s set).
QualityAssessor assessor_of(const AssessSpec& a) {
    return QualityAssessor(a.metrics.empty() ? QualityAssessor::default_metrics() : a.metrics, a.histogram_bins);
}

// What a method's before and after reports measure: the default set and output.metric.
QualityAssessor report_assessor(const std::string& metric) {
    std::vector<std::string> names = QualityAssessor::default_metrics();
    if (std::find(names.begin(), names.end(), metric) == names.end()) names.push_back(metric);
    return QualityAssessor(names);
}

// The solver of an untangle or improve step, with `threads`, and its target_worst_quality.
struct BuiltSolver {
    std::unique_ptr<Solver> solver;
    std::optional<double> target;
};
BuiltSolver build_solver(const StepSpec& step, int threads) {
    const auto* kind = find_solver(step.name);
    if (!kind) describe("solver", step.name);  // throws, listing the solvers
    SolverOptions options = step.options;
    kind->options->set_threads(options, threads);
    if (step.kind == StepSpec::Kind::Untangle) {
        if (!kind->options->untangles)
            throw OptionError("an untangle step runs a solver that untangles, such as global or local (got '" +
                              step.name + "')");
        kind->options->untangle_only(options);
    }
    return {kind->make(options), kind->target(options)};
}

}  // namespace

std::string origin(const RunSpec& spec, const std::string& key) {
    const auto it = spec.origins.find(key);
    return it == spec.origins.end() ? std::string() : it->second;
}

void set_run_targets(const RunSpec& spec, Mesh& mesh, ReadOptions read, bool flipped, const std::string& name,
                     const Mesh* reference) {
    // keep: auto keeps the aspect of cells in a plane or in space, not of a surface's
    // quadrilaterals: recombined on a curved surface, their stretch is more often noise than
    // intent (docs/surfaces.md, "Targets on surfaces"); --keep aspect asks for it.
    const TargetOptions targets = spec.targets.options(mesh.has_cells() && !is_surface_mesh(mesh), reference != nullptr);
    const std::string& path = spec.targets.reference;
    std::optional<MeshFile> file;
    if (!path.empty()) {
        // Held the way the input is, so that its corners are the input's.
        read.orientation = flipped ? OrientationMode::Flipped : OrientationMode::AsIs;
        file = read_mesh(path, read);
        reference = &file->mesh;
    }
    try {
        if (targets.any()) set_targets(mesh, targets, reference);
        else if (reference) check_reference(mesh, *reference);
        if (reference) mesh.set_reference_coordinates({reference->coordinates().begin(), reference->coordinates().end()});
    } catch (const MeshError& e) {
        throw MeshError("'" + (path.empty() ? name : path) + "': " + e.what());
    }
}

namespace {
// Morphing (input.displacement): the point field `name` moves the fixed vertices; the mesh as it
// was is handed back, the reference.
// The point field `name` of `file`, read from `path` to `purpose`; MeshError naming the fields it
// has when it has no such field.
std::vector<Field>::iterator point_field(MeshFile& file, const std::string& name, const std::string& path,
                                         const std::string& purpose) {
    const auto field = std::find_if(file.point_fields.begin(), file.point_fields.end(),
                                    [&](const Field& f) { return f.name == name; });
    std::string names;
    for (const Field& f : file.point_fields) names += (names.empty() ? "" : ", ") + f.name;
    if (field == file.point_fields.end())
        throw MeshError("'" + path + "' has no point field '" + name + "' " + purpose + " (its point fields: " +
                        (names.empty() ? std::string("none") : names) + ")");
    return field;
}

// targets.size_field: the point field `name` gives the edge length wanted at each vertex.
void set_edge_lengths(MeshFile& file, const std::string& name, const std::string& path) {
    const auto field = point_field(file, name, path, "to size the elements by");
    if (field->components != 1)
        throw MeshError("'" + path + "': the size field '" + name + "' has " + std::to_string(field->components) +
                        " components per point; a size field has 1 (the edge length wanted there)");
    try {
        file.mesh.set_target_edge_lengths(field->values);
    } catch (const MeshError& e) {
        throw MeshError("'" + path + "': the size field '" + name + "': " + e.what());
    }
}

// targets.metric_field: the point field `name` gives the metric wanted at each vertex, as the six
// values of a symmetric matrix (xx, yy, zz, xy, yz, xz) or the nine of the whole matrix.
void set_metrics(MeshFile& file, const std::string& name, const std::string& path) {
    const auto field = point_field(file, name, path, "to shape and size the elements by");
    const std::string what = "'" + path + "': the metric field '" + name + "'";
    std::vector<double> metrics;
    if (field->components == Mesh::kMetricValues) {
        metrics = field->values;
    } else if (field->components == 9) {
        metrics.reserve(field->values.size() / 9 * Mesh::kMetricValues);
        for (std::size_t v = 0; v < field->values.size() / 9; ++v) {
            const double* m = field->values.data() + 9 * v;  // row by row
            for (const auto& [i, j] : {std::pair{0, 1}, std::pair{0, 2}, std::pair{1, 2}})
                if (std::abs(m[3 * i + j] - m[3 * j + i]) > 1e-12 * (std::abs(m[3 * i + j]) + std::abs(m[3 * j + i])))
                    throw MeshError(what + " is not symmetric at vertex " + std::to_string(v));
            for (int k : {0, 4, 8, 1, 5, 2}) metrics.push_back(m[k]);
        }
    } else {
        throw MeshError(what + " has " + std::to_string(field->components) +
                        " components per point; a metric has 6 (xx, yy, zz, xy, yz, xz) or 9 (the whole matrix)");
    }
    try {
        file.mesh.set_target_metrics(std::move(metrics));
    } catch (const MeshError& e) {
        throw MeshError(what + ": " + e.what());
    }
}

Mesh displace_fixed_vertices(MeshFile& file, const std::string& name, const std::string& path) {
    const auto field = point_field(file, name, path, "to displace it by");
    Mesh& mesh = file.mesh;
    if (field->components != 3)
        throw MeshError("'" + path + "': the displacement field '" + name + "' has " + std::to_string(field->components) +
                        " components per point; a displacement has 3 (x, y, z)");
    Mesh reference = mesh;
    auto xyz = mesh.coordinates();
    for (VertexId v = 0; v < mesh.num_vertices(); ++v) {
        const auto i = 3 * static_cast<std::size_t>(v);
        for (std::size_t c = i; c < i + 3; ++c)
            if (!std::isfinite(field->values[c]))
                throw MeshError("'" + path + "': the displacement field '" + name + "' is not finite at vertex " +
                                std::to_string(v));
        if (mesh.fixed()[static_cast<std::size_t>(v)])
            for (std::size_t c = i; c < i + 3; ++c) xyz[c] += field->values[c];
    }
    // The output is the moved mesh: a displacement written with it would move it again.
    file.point_fields.erase(field);
    return reference;
}
}  // namespace

MeshFile read_input(const RunSpec& spec) {
    const InputSpec& in = spec.input;
    ReadOptions read;
    read.format = in.format;
    read.fix_boundary = in.fixed != FixedVertices::None;
    read.orientation = in.orientation;
    MeshFile file = read_mesh(in.mesh, read);
    Mesh& mesh = file.mesh;
    switch (in.fixed) {
        case FixedVertices::Auto: break;
        case FixedVertices::Boundary: mesh.fix_boundary(); break;
        case FixedVertices::File:
            if (!file.fixed_from_file)
                throw ConfigError(origin(spec, "input.fixed"), "input.fixed",
                                  "'" + in.mesh + "' has no `fixed` point field; use fixed: auto or fixed: boundary");
            break;
        case FixedVertices::None: mesh.set_fixed(std::vector<std::uint8_t>(static_cast<std::size_t>(mesh.num_vertices()), 0)); break;
    }
    if (!in.fixed_vertices.empty()) {
        std::vector<std::uint8_t> fixed(mesh.fixed().begin(), mesh.fixed().end());
        for (long long v : in.fixed_vertices) {
            if (v < 0 || v >= mesh.num_vertices())
                throw ConfigError(origin(spec, "input.fixed_vertices"), "input.fixed_vertices",
                                  "vertex " + std::to_string(v) + " does not exist: '" + in.mesh + "' has " +
                                      std::to_string(mesh.num_vertices()) + " vertices (ids 0 to " +
                                      std::to_string(mesh.num_vertices() - 1) + ")");
            fixed[static_cast<std::size_t>(v)] = 1;
        }
        mesh.set_fixed(std::move(fixed));
    }
    // The flags written with the output are the ones used, not the file's.
    std::erase_if(file.point_fields, [](const Field& f) { return f.name == "fixed"; });
    if (!spec.targets.size_field.empty()) set_edge_lengths(file, spec.targets.size_field, in.mesh);
    if (!spec.targets.metric_field.empty()) set_metrics(file, spec.targets.metric_field, in.mesh);
    if (in.displacement.empty()) {
        set_run_targets(spec, mesh, read, file.orientation.flipped, in.mesh);
    } else {
        const Mesh reference = displace_fixed_vertices(file, in.displacement, in.mesh);
        set_run_targets(spec, mesh, read, file.orientation.flipped, in.mesh, &reference);
    }
    return file;
}

std::string replace_method(std::string path, const std::string& method) {
    for (std::size_t at = path.find("{method}"); at != std::string::npos; at = path.find("{method}", at + method.size()))
        path.replace(at, 8, method);
    return path;
}

namespace {
void worst_and_mean(const QualityReport& report, const std::string& metric, double& worst, double& mean) {
    const MetricReport* m = report.metric(metric);
    if (!m) return;
    worst = m->movable.count > 0 ? m->movable.min : m->all.min;
    mean = m->all.mean;
}

// Once queue, before and after are set: worst and mean, iterations, status and message
// (`targets`: per improver of the queue, in order).
void finish_method(MethodResult& result, const std::vector<std::optional<double>>& targets) {
    worst_and_mean(result.before, result.metric, result.worst_before, result.mean_before);
    worst_and_mean(result.after, result.metric, result.worst_after, result.mean_after);
    std::size_t improver = 0;
    for (const auto& step : result.queue.steps) {
        const auto* summary = std::get_if<Summary>(&step.outcome);
        if (!summary) continue;
        result.iterations += summary->iterations;
        result.untangle_iterations += summary->untangle_iterations;
        const auto target = improver < targets.size() ? targets[improver] : std::nullopt;
        ++improver;
        if (target && result.status == RunStatus::Done && summary->reason != TerminationReason::TargetReached &&
            !(summary->worst_after >= *target)) {
            result.status = RunStatus::TargetNotReached;
            std::ostringstream why;
            why << "'" << step.label << "' stopped (" << to_string(summary->reason) << ") with the worst "
                << summary->quality_metric << " at " << summary->worst_after << ", below its target " << *target;
            result.message = why.str();
        }
    }
    if (!result.queue.success) {
        result.status = RunStatus::Failed;
        result.message = result.queue.message;
        const auto* last = result.queue.steps.empty() ? nullptr : std::get_if<Summary>(&result.queue.steps.back().outcome);
        if (last && last->reason == TerminationReason::Interrupted) result.status = RunStatus::Interrupted;
    }
}

// The run's status: the worst of its methods'.
void settle_status(RunResult& result) {
    for (const auto& m : result.methods) {
        if (m.status == RunStatus::Interrupted || result.status == RunStatus::Interrupted) result.status = RunStatus::Interrupted;
        else if (m.status == RunStatus::Failed) result.status = RunStatus::Failed;
        else if (m.status == RunStatus::TargetNotReached && result.status == RunStatus::Done)
            result.status = RunStatus::TargetNotReached;
    }
}

}  // namespace

BuiltQueue build_queue_of(std::span<const StepSpec> steps, int threads) {
    BuiltQueue b;
    for (const StepSpec& step : steps) {
        switch (step.kind) {
            case StepSpec::Kind::Assess: b.queue.assess(step.label, assessor_of(step.assess)); break;
            case StepSpec::Kind::Untangle:
            case StepSpec::Kind::Improve: {
                auto built = build_solver(step, threads);
                b.queue.improve(step.label, std::move(built.solver));
                b.targets.push_back(built.target);
                break;
            }
            case StepSpec::Kind::Wrapper: {
                const auto* kind = find_wrapper(step.name);
                if (!kind) describe("wrapper", step.name);
                SolverOptions options = step.options;
                kind->options->set_threads(options, threads);
                b.queue.append(kind->make(options));
                for (const auto& t : kind->targets(options)) b.targets.push_back(t);
                break;
            }
        }
    }
    return b;
}

void run_methods(const RunSpec& spec, const RunHooks& hooks, MeshPart part, std::vector<BuiltQueue>& queues,
                 const std::function<void(MethodResult&)>& write_outputs, RunResult& result) {
    const paloverde::detail::ThreadScope threads(spec.threads);  // the assessments' threads too
    const auto methods = spec.methods();
    const QualityAssessor assessor = report_assessor(spec.output.metric);
    const std::vector<double> input(part.mesh().coordinates().begin(), part.mesh().coordinates().end());
    // A surface mesh is reported as its solvers rate it, about the input surface's normals (what
    // the input turned over counts as inverted), before and after alike.
    const std::vector<Vec3> normals = paloverde::detail::is_surface_mesh(part)
                                          ? paloverde::detail::input_surface_normals(part)
                                          : std::vector<Vec3>{};
    auto report = [&] {
        if (normals.empty()) return assessor.assess(part);
        part.mesh().set_surface_normals(normals);
        QualityReport out = assessor.assess(part);
        part.mesh().clear_surface_normals();
        return out;
    };
    for (std::size_t m = 0; m < methods.size(); ++m) {
        const MethodSpec& method = methods[m];
        BuiltQueue& built = queues[m];
        // Every method starts from the input.
        if (m > 0) std::copy(input.begin(), input.end(), part.mesh().coordinates().begin());
        if (hooks.on_iteration)
            built.queue.observe(
                [&](std::string_view step, const IterationRecord& r) { hooks.on_iteration(method.name, step, r); });
        MethodResult r;
        r.name = method.name;
        r.metric = spec.output.metric;
        r.before = report();
        // Shared with the queue's solvers, which take their report of the input from it and make
        // the report of the result with their own (a surface mesh's is about normals the solver
        // sets itself).
        const auto shared = normals.empty() ? std::make_shared<RunReports>(RunReports{assessor, r.before, std::nullopt})
                                            : nullptr;
        part.reducer().max(0.0);  // the ranks start the clock together
        const auto start = std::chrono::steady_clock::now();
        r.queue = built.queue.run(part, shared);
        r.seconds = part.reducer().max(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
        r.after = shared && shared->output ? std::move(*shared->output) : report();
        finish_method(r, built.targets);
        write_outputs(r);
        result.methods.push_back(std::move(r));
        if (hooks.on_method_done) hooks.on_method_done(result.methods.back());
        // Interrupted (SIGINT, SIGTERM): the methods not yet run are skipped, on every rank alike.
        if (stop_requested_anywhere(part.reducer())) break;
    }
    settle_status(result);
}

}  // namespace detail

namespace {

std::string solver_names(const MethodResult& m) {
    std::string names;
    for (const auto& step : m.queue.steps)
        if (const auto* s = std::get_if<Summary>(&step.outcome)) names += (names.empty() ? "" : "+") + s->solver;
    return names;
}

std::string last_termination(const MethodResult& m) {
    std::string reason;
    for (const auto& step : m.queue.steps)
        if (const auto* s = std::get_if<Summary>(&step.outcome)) reason = std::string(to_string(s->reason));
    return reason;
}

std::string csv_field(const std::string& s) {
    if (s.find_first_of(",\"\n") == std::string::npos) return s;
    std::string out = "\"";
    for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
    return out + "\"";
}

nlohmann::json method_json(const MethodResult& m) {
    using nlohmann::json;
    json steps = json::array();
    for (const auto& step : m.queue.steps) {
        if (const auto* report = std::get_if<QualityReport>(&step.outcome))
            steps.push_back({{"label", step.label}, {"kind", "assess"}, {"report", json::parse(report->to_json())}});
        else
            steps.push_back({{"label", step.label},
                             {"kind", "improve"},
                             {"summary", json::parse(std::get<Summary>(step.outcome).to_json())}});
    }
    return {{"name", m.name},
            {"status", std::string(to_string(m.status))},
            {"exit_code", static_cast<int>(m.status)},
            {"message", m.message},
            {"success", m.status == RunStatus::Done || m.status == RunStatus::TargetNotReached},
            {"valid", m.after.inverted == 0},
            {"solver", solver_names(m)},
            {"termination", last_termination(m)},
            {"seconds", m.seconds},
            {"iterations", m.iterations},
            {"untangle_iterations", m.untangle_iterations},
            {"metric", m.metric},
            {"worst_before", m.worst_before},
            {"worst_after", m.worst_after},
            {"mean_before", m.mean_before},
            {"mean_after", m.mean_after},
            {"inverted_before", m.before.inverted},
            {"inverted_after", m.after.inverted},
            {"mesh", m.mesh_written},
            {"before", json::parse(m.before.to_json())},
            {"after", json::parse(m.after.to_json())},
            {"steps", steps}};
}

detail::PlotSeries series_of(const MethodResult& m) {
    detail::PlotSeries s;
    s.name = m.name;
    double iterations = 0.0, seconds = 0.0;
    for (const auto& step : m.queue.steps) {
        const auto* summary = std::get_if<Summary>(&step.outcome);
        if (!summary) continue;
        for (const auto& r : summary->history) {
            s.left.emplace_back(iterations + r.iteration, r.worst_quality);
            s.right.emplace_back(seconds + r.seconds, r.worst_quality);
        }
        if (!summary->history.empty()) iterations += summary->history.back().iteration + 1;
        seconds += summary->seconds;
    }
    return s;
}

}  // namespace

std::string to_json(const OrientationDecision& o) {
    return nlohmann::json{{"mode", std::string(to_string(o.mode))},
                          {"flipped", o.flipped},
                          {"oriented", o.oriented},
                          {"sign", o.sign},
                          {"share", o.share}}
        .dump();
}

InstructionQueue build_queue(std::span<const StepSpec> steps, int threads) {
    return detail::build_queue_of(steps, threads).queue;
}

// Under mpirun every rank runs the spec: a serial run on each would write the same files at once.
bool runs_distributed(const RunSpec& spec) { return spec.partitioned() || detail::world_size() > 1; }

RunResult run(const RunSpec& spec, const RunHooks& hooks) {
    spec.check_runnable();
    if (runs_distributed(spec)) return detail::run_partitioned(spec, hooks);
    std::vector<detail::BuiltQueue> queues;  // every option checked before the mesh is read
    for (const auto& m : spec.methods()) queues.push_back(detail::build_queue_of(m.queue, spec.threads));

    MeshFile file = detail::read_input(spec);
    RunResult result;
    result.input = spec.input.mesh;
    result.kind = file.mesh.kind();
    result.orientation = file.orientation;
    WriteOptions write;
    write.encoding = spec.output.ascii ? Encoding::Ascii : Encoding::Binary;
    // A serial run is the one-part case: the part is the whole mesh.
    detail::run_methods(spec, hooks, file.mesh, queues, [&](MethodResult& r) {
        if (spec.output.mesh.empty()) return;
        r.mesh_written = detail::replace_method(spec.output.mesh, r.name);
        write_mesh(r.mesh_written, file.mesh, write, file.point_fields, file.cell_fields);
    }, result);
    detail::write_reports(spec, result);
    return result;
}

RunResult run(Mesh& mesh, const RunSpec& spec, const RunHooks& hooks) {
    if (runs_distributed(spec))
        throw ConfigError(detail::origin(spec, "partition.parts"), "partition.parts",
                          "a mesh in memory is improved serially; partitioned runs read their input from files");
    std::vector<detail::BuiltQueue> queues;
    for (const auto& m : spec.methods()) queues.push_back(detail::build_queue_of(m.queue, spec.threads));
    if (mesh.num_elements() == 0) throw MeshError("the mesh has no elements");
    if (!spec.input.displacement.empty())
        throw ConfigError(detail::origin(spec, "input.displacement"), "input.displacement",
                          "a mesh in memory has no point fields: move its boundary and give the undeformed mesh's "
                          "coordinates as its reference (Mesh::set_reference_coordinates) instead");
    // Its own targets (set from C++) are kept; the spec's replace them for the run only.
    const std::vector<CornerMap> maps(mesh.target_maps().begin(), mesh.target_maps().end());
    const std::vector<double> volumes(mesh.target_volumes().begin(), mesh.target_volumes().end());
    const std::vector<CornerMap> roots(mesh.target_metric_roots().begin(), mesh.target_metric_roots().end());
    const std::vector<double> reference(mesh.reference_coordinates().begin(), mesh.reference_coordinates().end());
    const auto put_back = [&] {
        maps.empty() ? mesh.clear_targets() : mesh.set_targets(maps, volumes, roots);
        reference.empty() ? mesh.clear_reference_coordinates() : mesh.set_reference_coordinates(reference);
    };
    detail::set_run_targets(spec, mesh, ReadOptions{}, mesh.elements_flipped(), "the mesh");
    RunResult result;
    result.input = "(in memory)";
    result.kind = mesh.kind();
    try {
        detail::run_methods(spec, hooks, mesh, queues, [&](MethodResult& r) {
            if (spec.output.mesh.empty()) return;
            r.mesh_written = detail::replace_method(spec.output.mesh, r.name);
            write_mesh(r.mesh_written, mesh, WriteOptions{.encoding = spec.output.ascii ? Encoding::Ascii : Encoding::Binary});
        }, result);
    } catch (...) {
        put_back();
        throw;
    }
    put_back();
    detail::write_reports(spec, result);
    return result;
}

void detail::write_reports(const RunSpec& spec, const RunResult& result) {
    const OutputSpec& out = spec.output;
    if (!out.history.empty()) write_text_file(out.history, result.history_csv());
    if (!out.table.empty()) write_text_file(out.table, result.table_csv());
    if (!out.summary.empty()) write_text_file(out.summary, result.to_json() + "\n");
    if (!out.plot.empty()) {
        std::vector<detail::PlotSeries> series;
        for (const auto& m : result.methods) series.push_back(series_of(m));
        write_text_file(out.plot, detail::svg_plot(series, {"Worst element: " + result.input,
                                                            "worst quality (untangling: hybrid metric)",
                                                            "iteration", "seconds"}));
    }
}

std::string RunResult::report() const {
    std::ostringstream out;
    const OrientationDecision& o = orientation;
    if (o.flipped || o.mode != OrientationMode::Auto || (o.oriented && o.sign == 0))
        out << "input: " << o.describe(kind) << "\n";
    const bool study = methods.size() > 1;
    for (const auto& m : methods) {
        if (study) out << "=== method " << m.name << "\n";
        const auto& steps = m.queue.steps;
        if (steps.empty() || !std::holds_alternative<QualityReport>(steps.front().outcome))
            out << "before:\n" << m.before.to_text();
        out << m.queue.report();
        if (steps.empty() || !std::holds_alternative<QualityReport>(steps.back().outcome) || !m.queue.success)
            out << "after:\n" << m.after.to_text();
        out << std::setprecision(6) << (study ? m.name : std::string("result")) << ": " << to_string(m.status) << "; worst " << m.metric << " "
            << m.worst_before << " -> " << m.worst_after << ", inverted " << m.before.inverted << " -> "
            << m.after.inverted << ", " << m.iterations << " iterations, " << std::setprecision(3) << m.seconds << " s\n";
        if (!m.message.empty() && m.status != RunStatus::Done) out << "  " << m.message << "\n";
        if (!m.mesh_written.empty()) out << "  mesh written to " << m.mesh_written << "\n";
        if (study) out << "\n";
    }
    if (study) {
        std::size_t width = 9;
        for (const auto& m : methods) width = std::max(width, m.name.size() + 2);
        const auto& first = methods.front();
        out << "method comparison (" << first.metric << "; worst over elements with a free vertex):\n" << std::left
            << std::setw(static_cast<int>(width)) << "method" << std::setw(20) << "status" << std::right << std::setw(10)
            << "worst" << std::setw(10) << "mean" << std::setw(10) << "inverted" << std::setw(12) << "iterations"
            << std::setw(10) << "seconds" << "\n"
            << std::left << std::setw(static_cast<int>(width)) << "(input)" << std::setw(20) << "" << std::right
            << std::fixed << std::setprecision(4) << std::setw(10) << first.worst_before << std::setw(10)
            << first.mean_before << std::setw(10) << first.before.inverted << "\n";
        for (const auto& m : methods)
            out << std::left << std::setw(static_cast<int>(width)) << m.name << std::setw(20) << to_string(m.status)
                << std::right << std::setprecision(4) << std::setw(10) << m.worst_after << std::setw(10) << m.mean_after
                << std::setw(10) << m.after.inverted << std::setw(12) << m.iterations << std::setprecision(2)
                << std::setw(10) << m.seconds << "\n";
    }
    if (parallel) {
        const ParallelReport& p = *parallel;
        out << std::defaultfloat << std::setprecision(3) << "parallel: " << p.ranks << (p.ranks == 1 ? " rank" : " ranks")
            << ", " << p.vertices << " vertices, " << p.elements << " elements, "
            << (p.from_pieces ? "read from pieces" : "split by rank 0") << ", " << p.exchange << " exchange\n"
            << "  whole mesh on rank 0: " << p.whole_mesh_on_rank_0 << "\n"
            << "  seconds: read " << p.read_seconds << ", partition " << p.partition_seconds << ", distribute "
            << p.distribute_seconds << ", schedule " << p.schedule_seconds << ", solve " << p.solve_seconds << ", write "
            << p.write_seconds << "\n"
            << "  per exchange: " << p.ghost_copies << " ghost copies, " << p.messages << " messages, " << p.colors
            << (p.colors == 1 ? " color" : " colors") << "\n";
    }
    return out.str();
}

std::string RunResult::to_json() const {
    using nlohmann::json;
    json j{{"input", input},
           {"input_orientation", json::parse(config::to_json(orientation))},
           {"status", std::string(to_string(status))},
           {"exit_code", exit_code()}};
    json list = json::array();
    for (const auto& m : methods) list.push_back(method_json(m));
    if (methods.size() == 1)
        for (const auto& [key, value] : list[0].items())
            if (!j.contains(key)) j[key] = value;
    j["methods"] = std::move(list);
    if (parallel) {
        const ParallelReport& p = *parallel;
        j["parallel"] = {{"ranks", p.ranks},
                         {"exchange", p.exchange},
                         {"from_pieces", p.from_pieces},
                         {"whole_mesh_on_rank_0", p.whole_mesh_on_rank_0},
                         {"vertices", p.vertices},
                         {"elements", p.elements},
                         {"colors", p.colors},
                         {"ghost_copies", p.ghost_copies},
                         {"messages_per_exchange", p.messages},
                         {"seconds",
                          {{"read", p.read_seconds},
                           {"partition", p.partition_seconds},
                           {"distribute", p.distribute_seconds},
                           {"schedule", p.schedule_seconds},
                           {"solve", p.solve_seconds},
                           {"write", p.write_seconds}}}};
    }
    return j.dump(2);
}

std::string RunResult::table_csv() const {
    std::ostringstream out;
    out << "method,status,solver,termination,seconds,iterations,untangle_iterations,metric,worst_before,worst_after,"
           "mean_before,mean_after,inverted_before,inverted_after,mesh\n"
        << std::setprecision(17);
    for (const auto& m : methods)
        out << csv_field(m.name) << ',' << to_string(m.status) << ',' << solver_names(m) << ',' << last_termination(m)
            << ',' << m.seconds << ',' << m.iterations << ',' << m.untangle_iterations << ',' << m.metric << ','
            << m.worst_before << ',' << m.worst_after << ',' << m.mean_before << ',' << m.mean_after << ','
            << m.before.inverted << ',' << m.after.inverted << ',' << csv_field(m.mesh_written) << '\n';
    return out.str();
}

std::string RunResult::history_csv() const {
    const std::string empty = Summary{}.history_csv();
    std::string out = "method,improver," + empty;
    for (const auto& m : methods)
        for (const auto& step : m.queue.steps) {
            const auto* summary = std::get_if<Summary>(&step.outcome);
            if (!summary) continue;
            const std::string csv = summary->history_csv();
            const std::string prefix = csv_field(m.name) + "," + csv_field(step.label) + ",";
            std::size_t line = csv.find('\n') + 1;  // after the header
            while (line < csv.size()) {
                const std::size_t end = csv.find('\n', line);
                out += prefix + csv.substr(line, end - line + 1);
                line = end + 1;
            }
        }
    return out;
}

}  // namespace paloverde::config
