#include "sliding_boundary.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "paloverde/core/error.hpp"
#include "paloverde/core/exact_sum.hpp"
#include "paloverde/mesh/orientation.hpp"

namespace paloverde::detail {

namespace {

// A surface mesh's area (of its elements: a quadrilateral's corner triangles count twice), the
// same exact sum on any number of processes.
double area_of(const MeshPart& part) {
    const Mesh& mesh = part.mesh();
    ExactSum area;
    for (ElementId e = 0; e < mesh.num_elements(); ++e) {
        if (!part.counts(e)) continue;
        const auto c = mesh.element(e);
        const Vec3 a = mesh.point(c[0]), b = mesh.point(c[1]), d = mesh.point(c[2]);
        const Vec3 u{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w{d[0] - a[0], d[1] - a[1], d[2] - a[2]};
        area.add(0.5 * std::hypot(u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]));
    }
    return part.reducer().total(area);
}

// The whole mesh's volume (area for triangles), at the input's scale.
double volume_of(const MeshPart& part) {
    const Mesh& mesh = part.mesh();
    if (is_surface_mesh(part)) return area_of(part);
    const auto xyz = mesh.coordinates();
    double largest = 0.0;
    for (double c : xyz) largest = std::max(largest, std::abs(c));
    largest = part.reducer().max(largest);  // one scale on every process
    const int exponent = unit_scale_exponent(std::span<const double>(&largest, 1));
    const SignedMeasure m = signed_measure(mesh, xyz, exponent, part.plane_normal(), part.counted());
    const double total = part.reducer().total(m.total);
    return std::ldexp(total, -exponent * (mesh.kind() == ElementKind::Tetrahedron ? 3 : 2));
}

// The input's boundary: a part's is the whole mesh's, its vertices named by global id.
BoundarySurface surface_of(const MeshPart& part, const SurfaceOptions& options) {
    return part.boundary_surface(is_surface_mesh(part), options);
}

}  // namespace

TerminationCriterion fixed_run_budget(const TerminationCriterion& termination) {
    TerminationCriterion half = termination;
    half.max_iterations = (termination.max_iterations + 1) / 2;
    half.max_seconds = termination.max_seconds / 2.0;
    return half;
}

std::optional<TerminationCriterion> sliding_budget(const TerminationCriterion& termination, Summary& fixed,
                                                   const Reducer& reducer) {
    TerminationCriterion left = termination;
    left.max_iterations -= fixed.iterations - fixed.untangle_iterations;
    if (left.max_seconds > 0.0) left.max_seconds -= reducer.max(fixed.seconds);
    const bool budget_left = left.max_iterations > 0 && (termination.max_seconds == 0.0 || left.max_seconds > 0.0);
    const TerminationReason r = fixed.reason;
    // The sliding run improves shapes only: it starts from a valid mesh.
    const bool valid = fixed.after.inverted == 0 && fixed.after.degenerate == 0;
    const bool go_on = valid && (r == TerminationReason::Converged || r == TerminationReason::NothingToMove ||
                                 r == TerminationReason::NoImprovingStep || r == TerminationReason::GradientVanished ||
                                 r == TerminationReason::IterationLimit || r == TerminationReason::TimeLimit);
    if (go_on && budget_left) return left;
    if (r == TerminationReason::IterationLimit || r == TerminationReason::TimeLimit)
        fixed.message += "; the boundary did not slide (the budget was spent with it fixed)";
    return std::nullopt;
}

std::vector<Vec3> input_surface_normals(const MeshPart& part) {
    const BoundarySurface surface = surface_of(part, SurfaceOptions{});
    return part.normals_of(surface, part.mesh());
}

bool is_surface_mesh(const MeshPart& part) {
    return part.reducer().max(paloverde::is_surface_mesh(part.mesh()) ? 1.0 : 0.0) > 0.0;
}

void check_domain(const MeshPart& part, const SurfaceDomain& domain, bool boundary_slides) {
    if (!domain.analytic()) return;
    const Mesh& mesh = part.mesh();
    if (is_surface_mesh(part)) return;  // every vertex checked as the surface is built
    const bool planar = mesh.kind() == ElementKind::Triangle;
    if (mesh.kind() == ElementKind::Tetrahedron && !mesh.has_cells()) {
        if (!boundary_slides)
            throw OptionError("surface.domain: a tetrahedral mesh's boundary vertices slide on the " + domain.name() +
                              " with boundary: slide only; without it they stay where they are");
        return;  // its boundary vertices are checked as the sliding boundary is built
    }
    if (!planar || domain.shape != SurfaceDomain::Shape::Plane)
        throw OptionError("surface.domain: a " + domain.name() + " is a domain for surface meshes" +
                          (domain.shape == SurfaceDomain::Shape::Plane ? ", planar 2D meshes" : "") +
                          " and the sliding boundary of tetrahedral meshes, not for this mesh");
    // A planar mesh keeps to its own plane: the domain must be that plane, to rounding of the
    // file's coordinates (as Mesh::is_planar allows).
    Vec3 lo{0.0, 0.0, 0.0}, hi{0.0, 0.0, 0.0};
    const auto xyz = mesh.coordinates();
    for (int k = 0; k < 3; ++k) {
        double low = std::numeric_limits<double>::infinity(), high = -low;
        for (std::size_t i = static_cast<std::size_t>(k); i < xyz.size(); i += 3) {
            low = std::min(low, xyz[i]);
            high = std::max(high, xyz[i]);
        }
        lo[k] = -part.reducer().max(-low);
        hi[k] = part.reducer().max(high);
    }
    const double tolerance = 1e-6 * std::hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
    double farthest = 0.0;
    GlobalId which = -1;
    const auto ids = mesh.global_ids();
    for (VertexId v = 0; v < mesh.num_vertices(); ++v) {
        const double off = domain.distance(mesh.point(v));
        if (off > farthest) {
            farthest = off;
            which = ids.empty() ? static_cast<GlobalId>(v) : ids[static_cast<std::size_t>(v)];
        }
    }
    // The same message on every process: the farthest vertex, the lowest id among equals.
    const double worst = part.reducer().max(farthest);
    if (worst <= tolerance) return;
    const double id = -part.reducer().max(farthest == worst ? -static_cast<double>(which) : -1e300);
    throw MeshError(domain.off_message(static_cast<GlobalId>(id), worst) + ": a planar mesh keeps to its own plane");
}

void refuse_on_surfaces(const MeshPart& part) {
    const Mesh& mesh = part.mesh();
    if (!mesh.reference_coordinates().empty())
        throw OptionError("a moved boundary (a reference mesh or a displacement) does not go with surface meshes yet");
}

SlidingBoundary::SlidingBoundary(MeshPart part, const SurfaceOptions& options, bool open_edges_slide)
    : part_(part), mesh_(part.mesh()), surface_(surface_of(part, options)), fixed_(mesh_.fixed().begin(), mesh_.fixed().end()),
      input_(mesh_.coordinates().begin(), mesh_.coordinates().end()), volume_before_(volume_of(part)) {
    if (surface_.is_surface_mesh()) {
        slide_on_surface(open_edges_slide);
        return;
    }
    const auto n = static_cast<std::size_t>(mesh_.num_vertices());
    std::vector<std::uint8_t> on_boundary(n);
    for (std::size_t v = 0; v < n; ++v) on_boundary[v] = surface_.role(static_cast<VertexId>(v)) != BoundaryRole::Interior;
    // Whether the fixed flags are exactly the boundary, on every part.
    const bool boundary_fixed = part.reducer().max(on_boundary == fixed_ ? 0.0 : 1.0) == 0.0;
    slides_.assign(n, 0);
    released_.resize(n);
    for (std::size_t v = 0; v < n; ++v) {
        released_[v] = fixed_[v] ? 0 : 3;
        const BoundaryRole role = surface_.role(static_cast<VertexId>(v));
        if (role != BoundaryRole::Surface && role != BoundaryRole::Curve) continue;
        if (fixed_[v] && !boundary_fixed) continue;  // fixed by the user's own choice
        slides_[v] = 1;
        released_[v] = role == BoundaryRole::Surface ? 2 : 1;
    }
}

// A surface mesh: every vertex lies on the surface. Those not fixed slide on their patch or
// curve; the vertices of the surface's open edges, which the default fixed flags hold (they are
// the mesh's boundary), slide along them too where `open_edges_slide`; corners stay. Each
// triangle is rated and oriented about its normal in the input.
void SlidingBoundary::slide_on_surface(bool open_edges_slide) {
    const auto n = static_cast<std::size_t>(mesh_.num_vertices());
    // The outline from the whole surface (a part's own open edges include where it was cut), and
    // whether the fixed flags are exactly it on every part.
    std::vector<std::uint8_t> open_edges(n);
    for (std::size_t v = 0; v < n; ++v) open_edges[v] = surface_.on_open_edge(static_cast<VertexId>(v));
    const bool boundary_fixed = part_.reducer().max(open_edges == fixed_ ? 0.0 : 1.0) == 0.0;
    slides_.assign(n, 0);
    released_.assign(n, 0);
    for (std::size_t v = 0; v < n; ++v) {
        const BoundaryRole role = surface_.role(static_cast<VertexId>(v));
        if (role != BoundaryRole::Surface && role != BoundaryRole::Curve) continue;
        if (fixed_[v] && !(open_edges_slide && boundary_fixed && open_edges[v])) continue;
        slides_[v] = 1;
        released_[v] = role == BoundaryRole::Surface ? 2 : 1;
    }
    std::vector<Vec3> normals = part_.normals_of(surface_, mesh_);
    turn_targets_to(normals);
    mesh_.set_surface_normals(std::move(normals));
    normals_set_ = true;
}

void SlidingBoundary::turn_targets_to(std::span<const Vec3> normals) {
    // A target is taken in its element's own input plane (targets.cpp), so an element the input
    // turned over would rate valid against it. Where that plane faces against the surface, its
    // frame is turned to the surface's side (its second and third axes reversed: still a
    // rotation): the element then rates inverted until a solver turns it back, and after that
    // against its target's mirror image.
    const auto roots = mesh_.target_metric_roots();
    if (!mesh_.has_targets() || roots.empty()) return;
    std::vector<CornerMap> turned(roots.begin(), roots.end());
    bool any = false;
    for (std::size_t e = 0; e < turned.size(); ++e) {
        CornerMap& r = turned[e];
        if (r[2][0] * normals[e][0] + r[2][1] * normals[e][1] + r[2][2] * normals[e][2] >= 0.0) continue;
        for (int row = 1; row < 3; ++row)
            for (double& c : r[static_cast<std::size_t>(row)]) c = -c;
        any = true;
    }
    if (!any) return;
    mesh_.set_targets({mesh_.target_maps().begin(), mesh_.target_maps().end()},
                      {mesh_.target_volumes().begin(), mesh_.target_volumes().end()}, std::move(turned));
}

SlidingBoundary::~SlidingBoundary() {
    mesh_.set_fixed(fixed_);
    if (normals_set_) mesh_.clear_surface_normals();
}

void SlidingBoundary::release() { mesh_.set_degrees_of_freedom(released_); }

Summary SlidingBoundary::join(Summary fixed, std::optional<Summary> slid) const {
    auto worst_of_all = [](const Summary& s, const QualityReport& r) {
        const MetricReport* m = r.metric(s.quality_metric);
        return m ? m->all.min : (r.metrics.empty() ? 0.0 : r.metrics.front().all.min);
    };
    Summary out = std::move(fixed);
    out.worst_before = worst_of_all(out, out.before);
    if (slid) {
        // The sliding run's own phase: its worst qualities are over the elements it frees.
        for (IterationRecord r : slid->history) {
            r.phase = "slide";
            r.iteration += out.iterations;
            r.seconds += out.seconds;
            out.history.push_back(std::move(r));
        }
        out.iterations += slid->iterations;
        out.quality_passes += slid->quality_passes;
        out.gradient_passes += slid->gradient_passes;
        out.seconds += slid->seconds;
        out.reason = slid->reason;
        out.message = "boundary fixed: " + out.message + "; then sliding: " + slid->message;
        out.after = std::move(slid->after);
    }
    out.worst_after = worst_of_all(out, out.after);
    out.boundary = motion();
    return out;
}

Vec3 SlidingBoundary::project(VertexId v, const Vec3& p) const {
    Vec3 q = surface_.project(v, {std::ldexp(p[0], -exponent_), std::ldexp(p[1], -exponent_), std::ldexp(p[2], -exponent_)});
    for (double& c : q) c = std::ldexp(c, exponent_);
    return q;
}

BoundaryMotion SlidingBoundary::motion() const {
    BoundaryMotion m;
    const auto xyz = mesh_.coordinates();
    double largest = 0.0;
    double sliding = 0.0, moved = 0.0;
    for (std::size_t v = 0; v < slides_.size(); ++v) {
        if (!slides_[v] || !part_.owns(static_cast<VertexId>(v))) continue;
        ++sliding;
        const Vec3 p = {xyz[3 * v], xyz[3 * v + 1], xyz[3 * v + 2]};
        if (!std::equal(p.begin(), p.end(), input_.begin() + static_cast<std::ptrdiff_t>(3 * v))) ++moved;
        largest = std::max(largest, surface_.distance(p));
    }
    const Reducer& reducer = part_.reducer();
    m.sliding = static_cast<decltype(m.sliding)>(reducer.total(sliding));
    m.moved = static_cast<decltype(m.moved)>(reducer.total(moved));
    largest = reducer.max(largest);
    const double diagonal = surface_.bounding_box_diagonal();
    m.largest_distance = diagonal > 0.0 ? largest / diagonal : 0.0;
    m.volume_before = volume_before_;
    m.volume_after = volume_of(part_);
    return m;
}

Summary fixed_then_sliding(MeshPart part, const SurfaceOptions& surface, const TerminationCriterion& termination,
                           bool slide, const CheckpointSettings& checkpoints, const SlidingRun& run) {
    // The input's boundary, which the boundary-fixed run leaves where it is.
    SlidingBoundary sliding(part, surface);
    Checkpointer checkpointer(checkpoints.options, checkpoints.solver,
                              checkpoints.options_text + OptionsText()("surface", surface).text(), part,
                              CheckpointKind::Sliding);
    RunCheckpoints runs(part, checkpoints.options);
    Mesh& mesh = part.mesh();
    const auto n = static_cast<std::size_t>(mesh.num_vertices());
    std::optional<Summary> fixed;  // the boundary-fixed run's, once it is done
    if (checkpointer.resumes()) {
        Summary work;
        const SolverState state = checkpointer.resume(work);
        if (state.number("fixed_run_done") != 0.0) {
            fixed = restored_outcome(state, "fixed_run");
            take_work(*fixed, std::move(work));
            fixed->seconds = state.number("seconds");
            const std::vector<double>& left = state.vertex_field("fixed_run_mesh", n);
            std::copy(left.begin(), left.end(), mesh.coordinates().begin());
        }
    }
    if (!fixed) {
        if (runs.writes_now()) {
            runs.forget();
            SolverState state;
            state.numbers = {{"fixed_run_done", 0.0}};
            checkpointer.save(Summary{}, state, 0.0);
        }
        fixed = run(fixed_run_budget(termination), nullptr, runs.next_run());
    }
    const auto budget = sliding_budget(termination, *fixed, part.reducer());
    if (!budget || !slide) return sliding.join(std::move(*fixed), std::nullopt);
    if (runs.writes_now()) {
        runs.forget();
        SolverState state;
        state.numbers = {{"fixed_run_done", 1.0}, {"seconds", fixed->seconds}};
        state.vertex_fields = {{"fixed_run_mesh", {mesh.coordinates().begin(), mesh.coordinates().end()}}};
        store_outcome(state, "fixed_run", *fixed);
        checkpointer.save(*fixed, state, fixed->seconds);
    }
    sliding.release();
    Summary slid = run(*budget, &sliding, runs.next_run());
    return sliding.join(std::move(*fixed), std::move(slid));
}

}  // namespace paloverde::detail
