#pragma once
// What every vertex-moving solver does around its iterations: the before/after reports, the
// worst quality over the movable elements, the never-worse safety net, threads and timing; and
// the small per-patch helpers the local solvers share.
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>
#include <span>
#include <string>
#include <vector>

#include "paloverde/assess/quality_assessor.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/mesh/cell_types.hpp"
#include "paloverde/mesh/orientation.hpp"
#include "paloverde/metrics/quality_metric.hpp"
#include "paloverde/parallel/mesh_part.hpp"
#include "paloverde/solvers/solver.hpp"
#include "paloverde/solvers/summary.hpp"

namespace paloverde::detail {

using Clock = std::chrono::steady_clock;

inline double seconds_since(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

// Sets the OpenMP thread count for a solver's run (0: leave it) and restores it afterwards.
class ThreadScope {
public:
    explicit ThreadScope(int threads) : saved_(omp_get_max_threads()) {
        if (threads > 0) omp_set_num_threads(threads);
    }
    ~ThreadScope() { omp_set_num_threads(saved_); }
    ThreadScope(const ThreadScope&) = delete;
    ThreadScope& operator=(const ThreadScope&) = delete;

private:
    int saved_;
};

// The frame of one solver run: reports before and after, and the Summary.
class SolverRun {
public:
    // Solvers run at unit scale (an exact power-of-two rescaling, undone by finish() or, if the
    // run throws, by the destructor): volumes of coordinates near 1e300 or 1e-300 would overflow or
    // underflow. The reports before and after are of the mesh at its own scale, as its caller's
    // are: a metric is scale-free, but its cube roots may round otherwise at another scale. On a
    // distributed part (collective), reports and decisions are the whole mesh's, on every rank.
    // `shared`: the run's reports (Solver::shared_reports), which the first report is taken from
    // and the report of the result is made for.
    SolverRun(MeshPart part, std::string solver, std::string metric, SharedReports shared = {})
        : part_(part), mesh_(part.mesh()), start_(Clock::now()), shared_(shared),
          original_(mesh_.coordinates().begin(), mesh_.coordinates().end()) {
        double largest = 0.0;
        for (double c : mesh_.coordinates()) largest = std::max(largest, std::abs(c));
        largest = part.reducer().max(largest);
        exponent_ = unit_scale_exponent(std::span<const double>(&largest, 1));
        begin(std::move(solver), std::move(metric));
    }
    ~SolverRun() {
        if (finished_) return;
        if (at_unit_scale_) mesh_.scale(-exponent_);  // the target volumes
        std::copy(original_.begin(), original_.end(), mesh_.coordinates().begin());
    }
    SolverRun(const SolverRun&) = delete;
    SolverRun& operator=(const SolverRun&) = delete;

    Clock::time_point start() const { return start_; }
    // A resumed run: its clock goes on from the checkpointed run's elapsed seconds (time limits
    // count the whole run).
    void add_elapsed(double seconds) {
        start_ -= std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
    }
    // The mesh's coordinates, at unit scale until finish().
    std::span<double> coordinates() { return mesh_.coordinates(); }
    // Unit scale is the input's coordinates times 2^scale_exponent().
    int scale_exponent() const { return exponent_; }

    // The checks every solver makes before moving anything: a finished Summary when there is
    // nothing to move (no elements, no free vertex, no element with one); a MeshError for a
    // triangle mesh that is not planar and is not being smoothed as a surface (its vertices
    // sliding on it, with their triangles' normals: the global and local solvers), which free
    // vertex moves would leave.
    std::optional<Summary> nothing_to_move() {
        if (summary.before.elements == 0) return finish(TerminationReason::NothingToMove, "the mesh has no elements");
        if (summary.before.free_vertices == 0)
            return finish(TerminationReason::NothingToMove, "every vertex is fixed: nothing can move");
        const bool off_plane = mesh_.kind() == ElementKind::Triangle && !mesh_.is_planar() && !mesh_.has_surface_normals();
        if (part_.reducer().min(off_plane ? 0.0 : 1.0) == 0.0)
            throw MeshError(std::string(mesh_.has_cells() ? "the 2D cells" : "the triangles") +
                            " do not lie in one plane: surfaces are smoothed by the global and local solvers");
        if (summary.before.frozen_elements == summary.before.elements)
            return finish(TerminationReason::NothingToMove, "no element has a free vertex: nothing can move");
        return std::nullopt;
    }

    // With `safety_net`, a result with more inverted elements or (as many and) a lower worst
    // quality is replaced by the input: the sweeps never accept such moves, but floating point
    // and the exact predicate may disagree.
    Summary finish(TerminationReason reason, std::string message, bool safety_net = true) {
        summary.reason = reason;
        summary.message = std::move(message);
        mesh_.scale(-exponent_);
        at_unit_scale_ = false;
        std::optional<QualityReport> result;  // the run's report of it
        if (output_assessor_) {
            const QualityReport both = output_assessor_->assess(part_);
            result = shared_.output->assessor.taken_from(both, *output_assessor_);
            summary.after = *assessor_.taken_from(both, *output_assessor_);
        } else {
            summary.after = assess();
        }
        summary.worst_after = worst_movable(summary.after);
        const bool worse = summary.after.inverted > summary.before.inverted ||
                           (summary.after.inverted == summary.before.inverted && summary.worst_after < summary.worst_before);
        const double jacobian_before = worst_scaled_jacobian(summary.before), jacobian_after = worst_scaled_jacobian(summary.after);
        if (safety_net && worse) {
            hand_back_input("the result was worse than the input");
        } else if (safety_net && jacobian_after < jacobian_before) {
            std::ostringstream why;
            why << "the result lowered the minimum scaled Jacobian from " << jacobian_before << " to " << jacobian_after;
            hand_back_input(why.str());
        } else if (shared_.output) {
            shared_.output->output = std::move(result);
        }
        finished_ = true;
        summary.seconds = seconds_since(start_);
        return summary;
    }

    Summary summary;

private:
    void begin(std::string solver, std::string metric) {
        summary.solver = std::move(solver);
        // The solver's own metric (and the aspect ratio, which rates every element kind): a run's
        // full report is the caller's to make (config::run assesses every metric around the
        // queue), and on a large mesh every metric assessed costs several passes over the elements.
        std::vector<std::string> metrics{metric};
        if (metric != "aspect_ratio") metrics.push_back("aspect_ratio");
        if (guards_scaled_jacobian()) metrics.push_back("scaled_jacobian");
        assessor_ = QualityAssessor(metrics);
        summary.quality_metric = std::move(metric);
        std::optional<QualityReport> known;
        if (shared_.input) known = assessor_.taken_from(shared_.input->input, shared_.input->assessor);
        summary.before = known ? std::move(*known) : assess();
        // The report of the result, where the run's is made here too: both in one assessment.
        if (shared_.output && shared_.output->assessor.histogram_bins() == assessor_.histogram_bins()) {
            std::vector<std::string> both = shared_.output->assessor.metric_names();
            for (const auto& name : metrics)
                if (std::find(both.begin(), both.end(), name) == both.end()) both.push_back(name);
            output_assessor_ = QualityAssessor(both, shared_.output->assessor.histogram_bins());
        }
        summary.worst_before = worst_movable(summary.before);
        mesh_.scale(exponent_);
        at_unit_scale_ = true;
    }
    QualityReport assess() const { return assessor_.assess(part_); }
    // A mesh of cells with targets (the command line's default for cells), or a surface of cells,
    // is judged by its users' measure too: a valid input's minimum corner scaled Jacobian over its
    // cells (hexahedra, wedges, pyramids, quadrilaterals; a mixed mesh's simplices are rated by the
    // solver's metric) is never lowered. -inf where it does not apply (no cells, neither targets
    // nor a surface, an inverted input).
    bool guards_scaled_jacobian() const {
        return mesh_.has_cells() && (mesh_.has_targets() || mesh_.has_surface_normals());
    }
    double worst_scaled_jacobian(const QualityReport& report) const {
        if (summary.before.inverted > 0) return -INFINITY;
        double worst = INFINITY;
        for (const QualityReport::TypeReport& type : report.by_type) {
            if (type.type == cell_info(CellType::Tetrahedron).name || type.type == cell_info(CellType::Triangle).name) continue;
            for (const auto& [metric, value] : type.worst)
                if (metric == "scaled_jacobian") worst = std::min(worst, value);
        }
        return std::isfinite(worst) ? worst : -INFINITY;
    }
    void hand_back_input(const std::string& why) {
        std::copy(original_.begin(), original_.end(), mesh_.coordinates().begin());
        summary.after = summary.before;
        summary.worst_after = summary.worst_before;
        summary.message += " (" + why + ", so the input is handed back unchanged)";
    }
    double worst_movable(const QualityReport& report) const {
        const MetricReport* r = report.metric(summary.quality_metric);
        if (!r) r = &report.metrics.front();
        return r->movable.count > 0 ? r->movable.min : r->all.min;
    }

    MeshPart part_;
    Mesh& mesh_;
    Clock::time_point start_;
    SharedReports shared_;
    QualityAssessor assessor_;
    std::optional<QualityAssessor> output_assessor_;  // the run's metrics and the solver's
    std::vector<double> original_;  // the input, at its own scale
    int exponent_ = 0;
    bool at_unit_scale_ = false;
    bool finished_ = false;
};

// Elements with at least one free vertex: the only ones a vertex mover changes.
inline std::vector<ElementId> movable_elements(const Mesh& mesh) {
    std::vector<ElementId> out;
    for (ElementId e = 0; e < mesh.num_elements(); ++e)
        if (mesh.element_can_move(e)) out.push_back(e);
    return out;
}

// Orientation <= 0, decided exactly, among `elements`.
inline long count_not_positive(const Mesh& mesh, std::span<const double> xyz, std::span<const ElementId> elements) {
    long count = 0;
#pragma omp parallel for schedule(static) reduction(+ : count) if (elements.size() >= 4096)
    for (std::size_t i = 0; i < elements.size(); ++i) count += element_orientation(mesh, xyz, elements[i]) <= 0;
    return count;
}

struct SweepStats {
    double worst = 0.0, mean = 0.0;
};
// Worst and mean quality over `elements`; the sum runs in element order, so it does not depend
// on the thread count.
inline SweepStats sweep_stats(const QualityMetric& metric, const Mesh& mesh, std::span<const double> xyz,
                              std::span<const ElementId> elements, std::vector<double>& scratch) {
    scratch.resize(elements.size());
#pragma omp parallel for schedule(static) if (elements.size() >= 4096)
    for (std::size_t i = 0; i < elements.size(); ++i)
        metric.evaluate(mesh, xyz, elements[i], elements[i] + 1, &scratch[i]);
    SweepStats s{std::numeric_limits<double>::infinity(), 0.0};
    for (double q : scratch) {
        s.worst = std::min(s.worst, q);
        s.mean += q;
    }
    if (elements.empty()) s.worst = 0.0;
    s.mean /= static_cast<double>(std::max<std::size_t>(1, elements.size()));
    return s;
}

// Smallest quality among the elements of vertex v.
inline double patch_minimum(const QualityMetric& metric, const Mesh& mesh, std::span<const double> xyz, VertexId v) {
    double worst = std::numeric_limits<double>::infinity();
    for (ElementId e : mesh.elements_of(v)) {
        double q;
        metric.evaluate(mesh, xyz, e, e + 1, &q);
        worst = std::min(worst, q);
    }
    return worst;
}

// The mean edge length at v: the natural unit for how far it may move.
inline double local_length(const Mesh& mesh, std::span<const double> xyz, VertexId v) {
    double sum = 0.0;
    int count = 0;
    for (ElementId e : mesh.elements_of(v))
        for (VertexId w : mesh.element(e))
            if (w != v) {
                sum += std::hypot(xyz[3 * static_cast<std::size_t>(w)] - xyz[3 * static_cast<std::size_t>(v)],
                                  xyz[3 * static_cast<std::size_t>(w) + 1] - xyz[3 * static_cast<std::size_t>(v) + 1],
                                  xyz[3 * static_cast<std::size_t>(w) + 2] - xyz[3 * static_cast<std::size_t>(v) + 2]);
                ++count;
            }
    return count > 0 ? sum / count : 0.0;
}

}  // namespace paloverde::detail
