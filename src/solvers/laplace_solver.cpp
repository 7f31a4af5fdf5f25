#include "paloverde/solvers/laplace_solver.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "paloverde/core/error.hpp"
#include "paloverde/mesh/orientation.hpp"
#include "paloverde/mesh/renumber.hpp"
#include "iteration_start.hpp"
#include "run_support.hpp"

namespace paloverde {

void LaplaceSolverOptions::validate() const {
    metric_options.validate();
    termination.validate();
    make_metric(metric, metric_options);
    if (threads < 0) throw OptionError("threads must be >= 0 (0: the OpenMP default)");
}

LaplaceSolver::LaplaceSolver(LaplaceSolverOptions options) : options_(std::move(options)) { options_.validate(); }

Summary LaplaceSolver::improve(MeshPart part) {
    if (!part.whole())
        throw OptionError("'" + std::string(name()) + "' has no distributed version: smooth the whole mesh serially");
    Mesh& mesh = part.mesh();
    detail::ThreadScope threads(options_.threads);
    detail::SolverRun run(part, std::string(name()), options_.metric, shared_reports());
    Summary& summary = run.summary;
    const auto start = run.start();
    const bool smart = options_.smart;

    if (auto nothing = run.nothing_to_move()) return *nothing;
    const std::vector<ElementId> movable = detail::movable_elements(mesh);

    auto metric = make_metric(options_.metric, options_.metric_options);
    metric->set_scale(MetricScale::of(mesh));
    const VertexGraph graph = vertex_graph(mesh);
    double edge_sum = 0.0;
    std::int64_t edge_count = 0;
    std::vector<double> xyz(mesh.coordinates().begin(), mesh.coordinates().end());
    for (VertexId v = 0; v < mesh.num_vertices(); ++v)
        for (auto i = graph.offsets[v]; i < graph.offsets[v + 1]; ++i) {
            const VertexId w = graph.neighbours[i];
            edge_sum += std::hypot(xyz[3 * w] - xyz[3 * v], xyz[3 * w + 1] - xyz[3 * v + 1], xyz[3 * w + 2] - xyz[3 * v + 2]);
            ++edge_count;
        }
    const double mean_edge = edge_count > 0 ? edge_sum / static_cast<double>(edge_count) : 0.0;

    // Plain Laplace is Jacobi over all free vertices; smart Laplace goes color by color, so a
    // vertex's test sees its neighbours where they are.
    std::vector<std::vector<VertexId>> groups;
    std::string colors;
    if (smart) {
        const VertexColoring coloring = color_vertices(part, options_.coloring);
        groups = coloring.classes();
        colors = " (" + std::to_string(coloring.count) + " colors)";
    } else {
        groups.emplace_back();
        for (VertexId v = 0; v < mesh.num_vertices(); ++v)
            if (mesh.can_move(v)) groups.back().push_back(v);
    }

    auto done = [&](TerminationReason reason, std::string message) {
        std::copy(xyz.begin(), xyz.end(), mesh.coordinates().begin());
        // An interrupted run says so, whatever the mesh (smart Laplace never makes it worse).
        const bool interrupted = reason == TerminationReason::Interrupted;
        if (!interrupted && summary.before.inverted_frozen > 0) {
            reason = TerminationReason::CannotUntangle;
            message = std::to_string(summary.before.inverted_frozen) +
                      " inverted elements have all their vertices fixed; no smoother can move them";
        } else if (!interrupted && summary.before.inverted > 0) {
            reason = TerminationReason::CannotUntangle;
            message = "the mesh is tangled and Laplace smoothing does not untangle; use the local or global solver";
        }
        Summary result = run.finish(reason, message + colors, smart);
        if (!smart && result.after.inverted > result.before.inverted)
            result.message += "; plain Laplace inverted " + std::to_string(result.after.inverted - result.before.inverted) +
                              " elements (smart Laplace never does)";
        return result;
    };

    std::vector<double> scratch, target;
    std::vector<double> displacement;
    auto record = [&](int moved, double best) {
        const detail::SweepStats s = detail::sweep_stats(*metric, mesh, xyz, movable, scratch);
        ++summary.quality_passes;
        IterationRecord r;
        r.iteration = summary.iterations;
        r.phase = "shape";
        r.worst_quality = s.worst;
        r.best_worst_quality = std::max(best, s.worst);
        r.mean_quality = s.mean;
        r.inverted = detail::count_not_positive(mesh, xyz, movable);
        r.moved = moved;
        r.seconds = detail::seconds_since(start);
        add_record(summary, std::move(r));
        return s;
    };

    const TerminationCriterion& stop = options_.termination;
    double best = record(0, -1e300).worst;
    detail::IterationStart top(stop, part.reducer(), start, "sweeps");  // no checkpoints
    for (int s = 1;; ++s) {
        if (auto ended = top(s, summary.iterations, [] {}, best)) return done(ended->reason, std::move(ended->message));
        int moved = 0;
        double largest = 0.0;
        for (const auto& members : groups) {
            const auto count = static_cast<std::ptrdiff_t>(members.size());
            target.resize(3 * members.size());
            displacement.assign(members.size(), 0.0);
#pragma omp parallel for schedule(static) if (count >= 256)
            for (std::ptrdiff_t i = 0; i < count; ++i) {
                const VertexId v = members[static_cast<std::size_t>(i)];
                double sum[3] = {0, 0, 0};
                const auto degree = graph.offsets[v + 1] - graph.offsets[v];
                for (auto j = graph.offsets[v]; j < graph.offsets[v + 1]; ++j)
                    for (int c = 0; c < 3; ++c) sum[c] += xyz[3 * static_cast<std::size_t>(graph.neighbours[j]) + c];
                for (int c = 0; c < 3; ++c) target[3 * i + c] = degree > 0 ? sum[c] / static_cast<double>(degree) : xyz[3 * v + c];
            }
#pragma omp parallel for schedule(dynamic, 64) reduction(+ : moved) if (count >= 256)
            for (std::ptrdiff_t i = 0; i < count; ++i) {
                const VertexId v = members[static_cast<std::size_t>(i)];
                double* p = &xyz[3 * static_cast<std::size_t>(v)];
                const double old[3] = {p[0], p[1], p[2]};
                const double* t = &target[3 * i];
                const double distance = std::hypot(t[0] - old[0], t[1] - old[1], t[2] - old[2]);
                if (!(distance > 0.0)) continue;
                if (smart) {
                    // The whole patch is read and only v written: safe within a color.
                    const double before = detail::patch_minimum(*metric, mesh, xyz, v);
                    std::vector<std::uint8_t> positive;
                    for (ElementId e : mesh.elements_of(v)) positive.push_back(element_orientation(mesh, xyz, e) > 0);
                    for (int c = 0; c < 3; ++c) p[c] = t[c];
                    bool keep = detail::patch_minimum(*metric, mesh, xyz, v) >= before;
                    std::size_t k = 0;
                    for (ElementId e : mesh.elements_of(v))
                        if (keep && positive[k++] && element_orientation(mesh, xyz, e) <= 0) keep = false;
                    if (!keep) {
                        for (int c = 0; c < 3; ++c) p[c] = old[c];
                        continue;
                    }
                    displacement[i] = distance;
                    ++moved;
                } else {
                    displacement[i] = distance;
                    ++moved;
                }
            }
            if (!smart) {
                // Jacobi: every target was computed from the old positions.
                for (std::ptrdiff_t i = 0; i < count; ++i)
                    for (int c = 0; c < 3; ++c)
                        xyz[3 * static_cast<std::size_t>(members[i]) + c] = target[3 * i + c];
            }
            for (double d : displacement) largest = std::max(largest, d);
        }
        ++summary.iterations;
        best = std::max(best, record(moved, best).worst);
        if (moved == 0)
            return done(TerminationReason::Converged, smart ? "no vertex can move without harming its worst element"
                                                            : "every vertex is at the mean of its neighbours");
        if (largest <= stop.min_progress * mean_edge)
            return done(TerminationReason::Converged, "the vertices stopped moving");
    }
}

}  // namespace paloverde
