#include "paloverde/solvers/local_solver.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <vector>

#include "core/exact_sums.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/mesh/orientation.hpp"
#include "boundary_motion.hpp"
#include "checkpointer.hpp"
#include "iteration_start.hpp"
#include "local_untangle.hpp"
#include "run_support.hpp"
#include "sliding_boundary.hpp"
#include "stopping.hpp"

namespace paloverde {

void LocalSolverOptions::validate() const {
    if (!(smallest_motion_step > 0.0 && smallest_motion_step <= 1.0))
        throw OptionError("smallest_motion_step must be in (0, 1] (got " + std::to_string(smallest_motion_step) + ")");
    metric_options.validate();
    termination.validate();
    untangle_termination.validate();
    auto m = make_metric(metric, metric_options);
    if (!m->has_gradient())
        throw OptionError("metric '" + metric + "' has no gradient; choose aspect_ratio, mean_ratio, "
                          "inverse_condition or edge_ratio");
    surface.validate();
    if (threads < 0) throw OptionError("threads must be >= 0 (0: the OpenMP default)");
    if (ascent_steps < 1) throw OptionError("ascent_steps must be >= 1");
    if (!(active_tolerance >= 0.0 && active_tolerance < 1.0)) throw OptionError("active_tolerance must lie in [0, 1)");
    if (!(improve_below > 0.0)) throw OptionError("improve_below must be > 0 (1 or more: every vertex moves)");
    checkpoint.validate();
}

namespace {

using detail::Clock;
using detail::seconds_since;

double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// Everything that changes the result, for the checkpoint's fingerprint.
std::string options_text(const LocalSolverOptions& o) {
    detail::OptionsText t;
    t("metric", o.metric)("hybrid_sharpness", o.metric_options.hybrid_sharpness)("untangle", o.untangle)
        ("improve_shape", o.improve_shape)
        ("untangling", o.untangling == LocalSolverOptions::Untangling::Energy ? "energy" : "volume")
        ("termination", o.termination)("untangle_termination", o.untangle_termination)
        ("coloring", o.coloring == ColoringOrder::SmallestLast ? "smallest_last" : "greedy")
        ("ascent_steps", o.ascent_steps)("active_tolerance", o.active_tolerance)("improve_below", o.improve_below)
        ("boundary", o.boundary == LocalSolverOptions::Boundary::Slide ? "slide" : "fixed")
        ("feature_angle", o.surface.feature_angle);
    return t.text();
}

// The point of smallest norm in the convex hull of `points` (Gilbert's algorithm: Frank-Wolfe
// with exact line search). It stops once every point p has <x, p> >= (1 - 1e-3) |x|^2, which is
// all the ascent needs: then x raises every active quality at a rate of almost |x|^2.
Vec3 min_norm_point(const std::vector<Vec3>& points) {
    Vec3 x = points.front();
    for (int iteration = 0; iteration < 200; ++iteration) {
        const double xx = dot(x, x);
        if (xx == 0.0) break;
        std::size_t best = 0;
        double lowest = std::numeric_limits<double>::infinity();
        for (std::size_t i = 0; i < points.size(); ++i)
            if (const double d = dot(x, points[i]); d < lowest) lowest = d, best = i;
        if (lowest >= (1.0 - 1e-3) * xx) break;
        const Vec3 diff = {x[0] - points[best][0], x[1] - points[best][1], x[2] - points[best][2]};
        const double dd = dot(diff, diff);
        if (!(dd > 0.0)) break;
        const double t = std::clamp((xx - lowest) / dd, 0.0, 1.0);
        for (int c = 0; c < 3; ++c) x[c] -= t * diff[c];
    }
    return x;
}

// Raises the smallest quality of v's elements by active-set ascent (nonsmooth max-min). A step
// is accepted only if it raises that minimum and leaves no element that was positively oriented
// non-positive (decided exactly). Returns whether v moved. Only v's coordinates are written,
// and only v's elements are read: vertices of one color can run this at the same time.
// A vertex that slides (`sliding`) ascends along its surface or curve: the gradients are
// projected on its tangent space, and each trial point back onto the surface before it is rated.
class VertexAscent {
public:
    VertexAscent(const Mesh& mesh, const QualityMetric& metric, const LocalSolverOptions& options,
                 const detail::SlidingBoundary* sliding = nullptr)
        : mesh_(mesh), metric_(metric), options_(options), sliding_(sliding) {}

    bool improve(std::span<double> xyz, VertexId v) {
        const auto elements = mesh_.elements_of(v);
        const std::size_t k = elements.size();
        if (k == 0) return false;
        q_.resize(k);
        trial_q_.resize(k);
        gradient_.resize(k);
        positive_.resize(k);
        for (std::size_t i = 0; i < k; ++i) positive_[i] = element_orientation(mesh_, xyz, elements[i]) > 0;
        double* p = &xyz[3 * static_cast<std::size_t>(v)];
        const double length = detail::local_length(mesh_, xyz, v);
        const bool slides = sliding_ && mesh_.slides(v);
        double worst = evaluate(xyz, v, true, slides);
        bool moved = false;
        for (int step = 0; step < options_.ascent_steps; ++step) {
            const double tolerance = options_.active_tolerance * std::max(std::abs(worst), 1e-3);
            active_.clear();
            for (std::size_t i = 0; i < k; ++i)
                if (q_[i] <= worst + tolerance) active_.push_back(gradient_[i]);
            Vec3 d = min_norm_point(active_);
            if (mesh_.kind() == ElementKind::Triangle && mesh_.is_planar()) {
                // The gradients lie in the plane up to rounding; keep the vertex exactly in it.
                const Vec3& n = mesh_.plane_normal();
                const double along = dot(d, n);
                for (int c = 0; c < 3; ++c) d[c] -= along * n[c];
            }
            const double dd = dot(d, d);
            const double norm = std::sqrt(dd);
            if (!(norm > 0.0) || !(length > 0.0)) break;
            // Linearized, the minimum rises at rate |d|^2 until an inactive element, rising more
            // slowly, meets it: the first such meeting is the natural step.
            double alpha = 0.5 * length / norm;
            for (std::size_t i = 0; i < k; ++i) {
                const double rate = dot(gradient_[i], d);
                if (q_[i] > worst + tolerance && rate < dd) alpha = std::min(alpha, (q_[i] - worst) / (dd - rate));
            }
            const Vec3 origin = {p[0], p[1], p[2]};
            bool accepted = false;
            double trial_worst = worst;
            for (int attempt = 0; attempt < 30 && !accepted; ++attempt, alpha *= 0.5) {
                Vec3 trial = {origin[0] + alpha * d[0], origin[1] + alpha * d[1], origin[2] + alpha * d[2]};
                if (slides) trial = sliding_->project(v, trial);
                for (int c = 0; c < 3; ++c) p[c] = trial[c];
                trial_worst = evaluate(xyz, v, false, slides);
                if (!(trial_worst > worst)) continue;
                accepted = true;
                for (std::size_t i = 0; i < k && accepted; ++i)
                    if (positive_[i] && element_orientation(mesh_, xyz, elements[i]) <= 0) accepted = false;
            }
            if (!accepted) {
                for (int c = 0; c < 3; ++c) p[c] = origin[c];
                break;
            }
            moved = true;
            const double gain = trial_worst - worst;
            worst = evaluate(xyz, v, true, slides);
            if (gain <= 1e-12 * std::max(std::abs(worst), 1e-3)) break;
        }
        return moved;
    }

private:
    // Qualities of v's elements into q_ (or trial_q_), and with `gradient` each one's gradient
    // with respect to v (on its tangent space when it slides). Returns their minimum. The metric
    // rates the star in one call (a star of tetrahedra in blocks: the same bits as one by one).
    double evaluate(std::span<const double> xyz, VertexId v, bool gradient, bool slides) {
        const auto elements = mesh_.elements_of(v);
        double worst = std::numeric_limits<double>::infinity();
        if (!gradient) {
            metric_.element_values(mesh_, xyz, elements, trial_q_.data(), nullptr);
            for (std::size_t i = 0; i < elements.size(); ++i) worst = std::min(worst, trial_q_[i]);
            return worst;
        }
        const std::size_t stride = 3 * static_cast<std::size_t>(mesh_.corners());
        star_gradients_.resize(stride * elements.size());
        metric_.element_values(mesh_, xyz, elements, q_.data(), star_gradients_.data());
        for (std::size_t i = 0; i < elements.size(); ++i) {
            const double* g = star_gradients_.data() + stride * i + 3 * corner_of(elements[i], v);
            gradient_[i] = {g[0], g[1], g[2]};
            if (slides) gradient_[i] = sliding_->tangent(v, gradient_[i]);
            worst = std::min(worst, q_[i]);
        }
        return worst;
    }

    // Where v is among element e's corners.
    int corner_of(ElementId e, VertexId v) const {
        const auto element = mesh_.element(e);
        int slot = 0;
        for (int j = 0; j < mesh_.corners(); ++j)
            if (element[j] == v) slot = j;
        return slot;
    }

    const Mesh& mesh_;
    const QualityMetric& metric_;
    const LocalSolverOptions& options_;
    const detail::SlidingBoundary* sliding_;
    std::vector<double> q_, trial_q_;
    std::vector<Vec3> gradient_, active_;
    std::vector<std::uint8_t> positive_;
    std::vector<double> star_gradients_;
};

// The metric scale. A part's is the whole mesh's: its mean element volume summed over the ranks,
// its plane the whole mesh's.
MetricScale whole_mesh_scale(const MeshPart& part) {
    const Mesh& mesh = part.mesh();
    MetricScale scale = MetricScale::of(mesh);
    if (part.whole()) return scale;
    auto volume = make_metric("scaled_volume");
    MetricScale unit = scale;
    unit.reference_volume = 1.0;
    unit.plane_normal = part.plane_normal();
    volume->set_scale(unit);
    ExactSum sums[2];
    double v = 0.0;
    for (ElementId e = 0; e < mesh.num_elements(); ++e)
        if (part.counts(e)) {
            volume->evaluate(mesh, mesh.coordinates(), e, e + 1, &v);
            sums[0].add(std::abs(v));
            sums[1].add(1.0);
        }
    part.reducer().sum(sums);
    if (sums[0].value() > 0.0 && std::isfinite(sums[0].value())) scale.reference_volume = sums[0].value() / sums[1].value();
    scale.plane_normal = part.plane_normal();
    return scale;
}

}  // namespace

LocalSolver::LocalSolver(LocalSolverOptions options) : options_(std::move(options)) { options_.validate(); }

Summary LocalSolver::improve(MeshPart whole_or_part) {
    detail::ThreadScope threads(options_.threads);
    detail::check_domain(whole_or_part, options_.surface.domain, options_.boundary == LocalSolverOptions::Boundary::Slide);
    if (options_.untangle && detail::has_boundary_motion(whole_or_part)) {
        // The time limit bounds the steps together: each run gets what is left of it.
        return detail::follow_boundary_motion(whole_or_part, options_.smallest_motion_step,
                                              options_.termination.max_seconds,
                                              {options_.checkpoint, std::string(name()), options_text(options_)},
                                              [&](double seconds, const CheckpointOptions& checkpoint,
                                                  detail::MotionRunKind kind) {
                                                  LocalSolver within(
                                                      detail::for_motion_run(options_, kind, checkpoint, seconds));
                                                  within.set_observer(observer());
                                                  return within.run_once(whole_or_part);
                                              },
                                              false);  // every sweep moves every vertex
    }
    return run_once(whole_or_part);
}

Summary LocalSolver::run_once(MeshPart whole_or_part) {
    if (detail::is_surface_mesh(whole_or_part)) {
        // Untangling slides too: each vertex of a turned-over triangle moves on its patch or curve.
        const bool open_edges_slide = options_.boundary == LocalSolverOptions::Boundary::Slide;
        return detail::on_surface(whole_or_part, options_.surface, open_edges_slide,
                                  [&](detail::SlidingBoundary* sliding) { return improve_part(whole_or_part, sliding); });
    }
    if (options_.boundary != LocalSolverOptions::Boundary::Slide) return improve_part(whole_or_part, nullptr, shared_reports());
    return detail::fixed_then_sliding(whole_or_part, options_.surface, options_.termination, true,
                                      {options_.checkpoint, std::string(name()), options_text(options_)},
                                      [&](const TerminationCriterion& budget, detail::SlidingBoundary* sliding,
                                          const CheckpointOptions& checkpoint) {
                                          LocalSolverOptions run = options_;
                                          run.termination = budget;
                                          run.checkpoint = checkpoint;
                                          LocalSolver solver(run);
                                          solver.set_observer(observer());
                                          return solver.improve_part(whole_or_part, sliding);
                                      });
}

Summary LocalSolver::improve_part(MeshPart whole_or_part, detail::SlidingBoundary* sliding, SharedReports shared) {
    detail::SolverRun run(whole_or_part, std::string(name()), options_.metric, shared);
    if (sliding) sliding->set_scale_exponent(run.scale_exponent());
    if (auto nothing = run.nothing_to_move()) return *nothing;
    // A run whose vertices slide depends on the surface they keep to.
    const std::string surface = sliding ? detail::OptionsText()("surface", options_.surface).text() : "";
    detail::Checkpointer checkpointer(options_.checkpoint, std::string(name()), options_text(options_) + surface,
                                      whole_or_part);
    const Mesh& mesh = whole_or_part.mesh();
    // A rank moves only the vertices it owns, and sums over the elements it counts.
    std::vector<ElementId> counted;
    for (ElementId e : detail::movable_elements(mesh))
        if (whole_or_part.counts(e)) counted.push_back(e);
    VertexColoring coloring = color_vertices(whole_or_part, options_.coloring);
    for (VertexId v = 0; v < mesh.num_vertices(); ++v)
        if (!whole_or_part.owns(v)) coloring.color[v] = -1;
    Domain domain{mesh, std::move(counted), whole_or_part.reducer(), whole_or_part.halo(), std::move(coloring),
                  whole_mesh_scale(whole_or_part)};
    return sweep_colors(run, domain, checkpointer, sliding);
}

Summary LocalSolver::sweep_colors(detail::SolverRun& run, const Domain& domain, detail::Checkpointer& checkpointer,
                                  const detail::SlidingBoundary* sliding) {
    const Mesh& mesh = domain.mesh;
    const Reducer& reducer = domain.reducer;
    Summary& summary = run.summary;
    // A resumed run continues at the sweep boundary it was checkpointed at.
    std::optional<detail::SolverState> resume;
    if (checkpointer.resumes()) resume = checkpointer.resume(summary, run);
    const auto start = run.start();
    const std::vector<ElementId>& movable = domain.counted_movable;
    const VertexColoring& coloring = domain.coloring;
    const auto classes = coloring.classes();
    const std::string colors = " (" + std::to_string(coloring.count) + " colors)";
    const MetricScale& scale = domain.scale;
    auto metric = make_metric(options_.metric, options_.metric_options);
    metric->set_scale(scale);
    // The untangling ascent maximizes the smallest signed volume, which is linear in the vertex.
    auto volume = make_metric("scaled_volume", options_.metric_options);
    volume->set_scale(scale);
    // Whole-mesh figures: every process stops at the same sweep.
    auto count_inverted = [&](std::span<const double> at) {
        return static_cast<long>(reducer.total(static_cast<double>(detail::count_not_positive(mesh, at, movable))));
    };
    // Untangling by the energy: each element measured against its neighbourhood's size at the
    // input (the global solver's local reference volumes), and the schedule's epsilon.
    const bool by_energy = options_.untangling == LocalSolverOptions::Untangling::Energy;
    std::vector<double> reference;
    double epsilon = detail::kFirstUntangleEpsilon;
    MetricScale local_scale = scale;
    if (by_energy) {
        reference = detail::local_reference_volumes(mesh, mesh.coordinates(), scale, domain.halo, mesh.num_elements());
        local_scale.element_reference_volume = reference;
    }
    auto local_volume = make_metric("scaled_volume");
    local_volume->set_scale(local_scale);

    const std::size_t n = static_cast<std::size_t>(mesh.num_vertices());
    std::vector<double> xyz(mesh.coordinates().begin(), mesh.coordinates().end());
    std::vector<double> scratch;
    // The best sweep of the current phase by the rule "fewer inverted elements, then a higher worst
    // quality" (of the phase's metric), and the latest one. A move never lowers the smallest
    // quality of its vertex's elements nor inverts one, so the latest is the best; should rounding
    // ever disagree, the run still ends on the best.
    std::vector<double> best_xyz;  // empty until the phase's first record
    long best_inverted = 0, now_inverted = 0;
    double best_worst = -std::numeric_limits<double>::infinity(), now_worst = best_worst;
    auto keep_best = [&](long inverted, double worst) {
        now_inverted = inverted;
        now_worst = worst;
        if (best_xyz.empty() || detail::better_iterate(inverted, worst, best_inverted, best_worst)) {
            best_inverted = inverted;
            best_worst = worst;
            best_xyz = xyz;
        }
    };
    auto record = [&](const char* phase, const QualityMetric& m, long inverted, int moved, double best) {
        detail::SweepStats s = detail::sweep_stats(m, mesh, xyz, movable, scratch);
        ExactSum sums[2];
        for (double q : scratch) sums[0].add(q);
        sums[1].add(static_cast<double>(scratch.size()));
        reducer.sum(sums);
        s.worst = reducer.min(scratch.empty() ? std::numeric_limits<double>::infinity() : s.worst);
        s.mean = sums[0].value() / std::max(1.0, sums[1].value());
        ++summary.quality_passes;
        IterationRecord r;
        r.iteration = summary.iterations;
        r.phase = phase;
        r.worst_quality = s.worst;
        r.best_worst_quality = std::max(best, s.worst);
        r.mean_quality = s.mean;
        r.inverted = inverted;
        r.moved = moved;
        r.seconds = seconds_since(start);
        add_record(summary, std::move(r));
        keep_best(inverted, s.worst);
        return s;
    };
    auto done = [&](TerminationReason reason, std::string message) {
        if (detail::better_iterate(best_inverted, best_worst, now_inverted, now_worst)) {
            xyz = best_xyz;
            message += "; the best sweep is handed back";
        }
        std::copy(xyz.begin(), xyz.end(), run.coordinates().begin());
        if (summary.before.inverted_frozen > 0 && reason != TerminationReason::CannotUntangle &&
            reason != TerminationReason::Interrupted)
            return run.finish(TerminationReason::CannotUntangle,
                              std::to_string(summary.before.inverted_frozen) +
                                  " inverted elements have all their vertices fixed; no smoother can move them" + colors);
        return run.finish(reason, message + colors);
    };
    // One pass over the colors; within a color every vertex's update reads only vertices of
    // other colors, so the parallel loop gives the same result for any thread count. After each
    // color, ghosts take their owners' new positions.
    auto sweep = [&](auto&& visit) {
        int moved = 0;
        for (std::size_t c = 0; c < static_cast<std::size_t>(coloring.count); ++c) {
            static const std::vector<VertexId> none;
            const auto& members = c < classes.size() ? classes[c] : none;
            const auto count = static_cast<std::ptrdiff_t>(members.size());
#pragma omp parallel reduction(+ : moved) if (count >= 256)
            {
                VertexAscent shape(mesh, *metric, options_, sliding), untangle(mesh, *volume, options_, sliding);
                detail::VertexEnergy energy(mesh, reference, scale, epsilon, sliding);
#pragma omp for schedule(dynamic, 64)
                for (std::ptrdiff_t i = 0; i < count; ++i)
                    moved += visit(members[static_cast<std::size_t>(i)], shape, untangle, energy);
            }
            domain.halo.update(xyz, 3);
        }
        return static_cast<int>(reducer.total(static_cast<double>(moved)));
    };

    // What the sweeps carry over, saved in checkpoints at sweep boundaries.
    long inverted = 0;
    std::vector<double> inverted_history, worst_history;  // untangling
    double best = -1e300;                                 // shape: best worst quality so far
    std::vector<double> best_history;
    auto save = [&](bool untangling, int next_sweep) {
        detail::SolverState state;
        state.numbers = {{"untangling", untangling ? 1.0 : 0.0}, {"sweep", next_sweep},
                         {"inverted", static_cast<double>(inverted)}, {"best", best},
                         {"best_inverted", static_cast<double>(best_inverted)}, {"best_worst", best_worst},
                         {"now_inverted", static_cast<double>(now_inverted)}, {"now_worst", now_worst},
                         {"epsilon", epsilon}};
        state.lists = {{"inverted_history", inverted_history}, {"worst_history", worst_history}, {"best_history", best_history}};
        state.vertex_fields = {{"x", xyz}, {"best_x", best_xyz}};
        checkpointer.save(summary, state, seconds_since(start));
    };
    // The whole mesh's energy at the current epsilon (exact sums: the same on any rank count).
    auto total_energy = [&] {
        auto energy = make_untangle_energy(epsilon, detail::kUntangleTheta);
        energy->set_scale(local_scale);
        detail::sweep_stats(*energy, mesh, xyz, movable, scratch);
        ExactSum sum;
        for (double q : scratch) sum.add(-q);
        return reducer.total(sum);
    };
    // A sweep of the energy over the vertices within two rings of an inverted element (the
    // others' elements are valid, and their moves would only smooth), then the next epsilon.
    std::vector<double> near(n);
    auto energy_sweep = [&] {
        const double start_energy = total_energy();
        std::fill(near.begin(), near.end(), 0.0);
        // Every local element, counted here or not: an owned vertex sees all of its elements, a
        // ghost takes its owner's mark.
        for (ElementId e = 0; e < mesh.num_elements(); ++e)
            if (element_orientation(mesh, xyz, e) <= 0)
                for (VertexId w : mesh.element(e)) near[w] = 1.0;
        domain.halo.update(near, 1);
        const int moved = sweep([&](VertexId v, VertexAscent&, VertexAscent&, detail::VertexEnergy& energy) {
            bool close = false;
            for (ElementId e : mesh.elements_of(v))
                for (VertexId w : mesh.element(e)) close = close || near[w] != 0.0;
            return close && energy.improve(xyz, v) ? 1 : 0;
        });
        const double end_energy = total_energy();
        const double worst = detail::sweep_stats(*local_volume, mesh, xyz, movable, scratch).worst;
        const double next = detail::next_epsilon(epsilon, start_energy, end_energy,
                                                 reducer.min(movable.empty() ? std::numeric_limits<double>::infinity() : worst));
        // Below 1e-12 of an element's size the barrier is as sharp as it can usefully be.
        epsilon = std::isfinite(next) ? std::max(next, 1e-12) : epsilon;
        return moved;
    };
    int first_sweep = 1;
    bool resume_untangling = false;
    if (resume) {
        xyz = resume->vertex_field("x", n);
        best_xyz = resume->vertex_field("best_x", n);
        resume_untangling = resume->number("untangling") != 0.0;
        first_sweep = static_cast<int>(resume->number("sweep"));
        inverted = static_cast<long>(resume->number("inverted"));
        best = resume->number("best");
        best_inverted = static_cast<long>(resume->number("best_inverted"));
        best_worst = resume->number("best_worst");
        now_inverted = static_cast<long>(resume->number("now_inverted"));
        now_worst = resume->number("now_worst");
        epsilon = resume->number("epsilon");
        inverted_history = resume->list("inverted_history");
        worst_history = resume->list("worst_history");
        best_history = resume->list("best_history");
    } else {
        inverted = count_inverted(xyz);
    }

    if (!resume && inverted > 0 && !options_.untangle)
        return done(TerminationReason::CannotUntangle, "the mesh is tangled and untangling was turned off");
    if (resume ? resume_untangling : inverted > 0) {
        const TerminationCriterion& stop = options_.untangle_termination;
        if (!resume) {
            inverted_history = {static_cast<double>(inverted)};
            worst_history = {record("untangle", *volume, inverted, 0, -1e300).worst};
        }
        detail::IterationStart top(stop, reducer, start, "sweeps", &checkpointer, "while untangling");
        for (int s = resume ? first_sweep : 1; inverted > 0; ++s) {
            if (auto ended = top(s, summary.iterations, [&] { save(true, s); })) {
                // Out of sweeps with elements inverted: the mesh cannot be untangled locally.
                if (ended->reason == TerminationReason::IterationLimit)
                    return done(TerminationReason::CannotUntangle, "untangling stopped after " +
                                                                       std::to_string(stop.max_iterations) +
                                                                       " sweeps with elements still inverted");
                return done(ended->reason, std::move(ended->message));
            }
            const int moved = by_energy ? energy_sweep() : sweep([&](VertexId v, VertexAscent&, VertexAscent& ascent, auto&) {
                    bool touches_inverted = false;
                for (ElementId e : mesh.elements_of(v))
                    if (element_orientation(mesh, xyz, e) <= 0) touches_inverted = true;
                if (!touches_inverted) return 0;
                // The linear program finds a position where every element is valid when there
                // is one; otherwise the ascent at least raises the smallest volume.
                if (detail::untangle_vertex(mesh, xyz, v, scale, sliding).moved) return 1;
                return ascent.improve(xyz, v) ? 1 : 0;
            });
            ++summary.iterations;
            ++summary.untangle_iterations;
            inverted = count_inverted(xyz);
            const double worst = record("untangle", *volume, inverted, moved, worst_history.back()).worst;
            inverted_history.push_back(static_cast<double>(inverted));
            worst_history.push_back(std::max(worst, worst_history.back()));
            if (inverted == 0) break;
            const detail::StallWindow progress(stop, worst_history.back());
            if (moved == 0 || (progress.did_not_fall(inverted_history) && progress.rose_too_little(worst_history)))
                return done(TerminationReason::CannotUntangle,
                            std::to_string(inverted) + " elements are still inverted and local moves no longer help");
        }
        resume.reset();
    }
    if (!options_.improve_shape)
        return done(TerminationReason::TargetReached, "no element is inverted (improve_shape: false, no shape sweeps)");

    const TerminationCriterion& stop = options_.termination;
    if (!resume) {
        // A new phase, with a new metric: its best starts here.
        best_xyz.clear();
        best = record("shape", *metric, 0, 0, -1e300).worst;
        best_history = {best};
    }
    detail::IterationStart top(stop, reducer, start, "sweeps", &checkpointer);
    for (int s = resume ? first_sweep : 1;; ++s) {
        if (auto ended = top(s, summary.iterations, [&] { save(false, s); }, best))
            return done(ended->reason, std::move(ended->message));
        const double threshold = best + options_.improve_below * (metric->ideal_value() - best);
        const int moved = sweep([&](VertexId v, VertexAscent& ascent, VertexAscent&, auto&) {
            if (!(detail::patch_minimum(*metric, mesh, xyz, v) < threshold)) return 0;
            return ascent.improve(xyz, v) ? 1 : 0;
        });
        ++summary.iterations;
        const detail::SweepStats st = record("shape", *metric, count_inverted(xyz), moved, best);
        best = std::max(best, st.worst);
        best_history.push_back(best);
        if (moved == 0) return done(TerminationReason::Converged, "no vertex can raise its worst element any more");
        if (detail::StallWindow(stop, best).rose_too_little(best_history))
            return done(TerminationReason::Converged, "the worst quality stopped improving");
    }
}

}  // namespace paloverde
