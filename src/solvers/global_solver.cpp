#include "paloverde/solvers/global_solver.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "core/blocked_sum.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/mesh/orientation.hpp"
#include "local_untangle.hpp"
#include "run_support.hpp"
#include "workspace.hpp"

namespace paloverde {

void GlobalSolverOptions::validate() const {
    objective_options.validate();
    metric_options.validate();
    termination.validate();
    untangle_termination.validate();
    make_objective(objective, objective_options);
    auto metric = make_metric(shape_metric, metric_options);
    if (!metric->has_gradient())
        throw OptionError("shape_metric '" + shape_metric + "' has no gradient; choose aspect_ratio, mean_ratio, "
                          "inverse_condition or edge_ratio");
    if (threads < 0) throw OptionError("threads must be >= 0 (0: the OpenMP default)");
    if (steps_per_mu < 1) throw OptionError("steps_per_mu must be >= 1");
    if (local_untangle_rounds < 0) throw OptionError("local_untangle_rounds must be >= 0");
    if (max_failed_searches < 1) throw OptionError("max_failed_searches must be >= 1");
}

namespace {

using detail::Clock;
using detail::seconds_since;
const Reducer kSerial;

struct PhaseResult {
    TerminationReason reason;
    std::string message;
};

// One phase (untangle or shape) of the barrier ascent over the workspace's movable elements.
// Steps are accepted when they raise the objective (Armijo), stay in its domain and do not add
// non-positive elements; the worst quality of an iterate may dip while the barrier rebalances,
// so the phase keeps the best iterate (highest worst quality) and ends on it.
class Phase {
public:
    Phase(detail::Workspace& work, std::vector<double>& xyz, const QualityMetric& metric, ObjectiveFunction& objective,
          const TerminationCriterion& stop, const GlobalSolverOptions& options, bool untangling, Summary& summary,
          const IterationObserver& observer, Clock::time_point start)
        : work_(work), x_(xyz), metric_(metric), objective_(objective), stop_(stop), options_(options),
          untangling_(untangling), summary_(summary), observer_(observer), start_(start) {}

    PhaseResult run();

private:
    struct Stats {
        double worst, mean;
        long bad;  // non-positive qualities
    };
    Stats stats(std::span<const double> q) const;
    bool line_search(double objective, double max_direction);
    void apply_preconditioner();
    bool untangled() const;
    void record(const Stats& s, double objective, double step, double gain);
    PhaseResult end(TerminationReason reason, std::string message);

    detail::Workspace& work_;
    std::vector<double>& x_;
    const QualityMetric& metric_;
    ObjectiveFunction& objective_;
    const TerminationCriterion& stop_;
    const GlobalSolverOptions& options_;
    bool untangling_;
    Summary& summary_;
    const IterationObserver& observer_;
    Clock::time_point start_;

    std::vector<double> q_, trial_q_, weight_, trial_x_, gradient_, direction_, previous_gradient_, best_x_;
    std::vector<double> curvature_weight_, curvature_, preconditioned_, previous_preconditioned_;
    std::vector<double> damping_;                  // per vertex: fraction of the step it takes
    std::vector<int> stamp_;                       // per vertex: damped in this round
    std::vector<std::uint32_t> element_stamp_;     // per element: re-evaluated in this round
    std::uint32_t element_stamp_round_ = 0;
    double best_worst_ = -std::numeric_limits<double>::infinity();
    long best_bad_ = 0;
    double step_ = 0.05;  // largest vertex displacement of the next trial step, in reference lengths
    double gain_ = 0.0;   // objective increase of the last accepted step (at its mu and t)
};

Phase::Stats Phase::stats(std::span<const double> q) const {
    Stats s{std::numeric_limits<double>::infinity(), 0.0, 0};
    for (double v : q) {
        s.worst = std::min(s.worst, v);
        s.bad += v <= 0.0;
    }
    s.mean = detail::blocked_sums<1>(q.size(), [&](std::size_t i, auto& acc) { acc[0] += q[i]; })[0] /
             static_cast<double>(std::max<std::size_t>(1, q.size()));
    return s;
}

bool Phase::untangled() const {
    const SimplexMesh& mesh = work_.mesh();
    for (ElementId e = 0; e < work_.movable_elements(); ++e)
        if (element_orientation(mesh, x_, e) <= 0) return false;
    return true;
}

void Phase::record(const Stats& s, double objective, double step, double gain) {
    IterationRecord r;
    r.iteration = summary_.iterations;
    r.phase = untangling_ ? "untangle" : "shape";
    r.worst_quality = s.worst;
    r.best_worst_quality = best_worst_;
    r.mean_quality = s.mean;
    r.inverted = s.bad;
    if (const auto* barrier = dynamic_cast<const LogBarrier*>(&objective_)) {
        r.mu = barrier->mu();
        r.t = barrier->t();
    }
    r.objective = objective;
    r.step = step;
    r.gain = gain;
    r.seconds = seconds_since(start_);
    summary_.history.push_back(std::move(r));
    if (observer_) observer_(summary_.history.back());
}

bool Phase::line_search(double objective, double max_direction) {
    const SimplexMesh& mesh = work_.mesh();
    const VertexId n = mesh.num_vertices();
    const ElementId movable = work_.movable_elements();
    const double length = work_.reference_length();
    // An element blocks a step when it leaves the objective's domain or becomes non-positive
    // although it was positive. Rather than shrinking the whole step for it, the step of its
    // vertices is damped until it no longer blocks: one tangle does not freeze the mesh.
    auto blocks = [&](ElementId e) {
        return !objective_.admissible(trial_q_[e], static_cast<std::size_t>(e)) || (trial_q_[e] <= 0.0 && q_[e] > 0.0);
    };
    std::vector<VertexId> damped;
    for (int attempt = 0; attempt < 40; ++attempt, step_ *= 0.5) {
        const double s = step_ * length / max_direction;
        std::fill(damping_.begin(), damping_.end(), 1.0);
#pragma omp parallel for schedule(static) if (static_cast<std::size_t>(movable) > detail::kParallelThreshold)
        for (VertexId v = 0; v < n; ++v)
            for (int c = 0; c < 3; ++c) trial_x_[3 * v + c] = x_[3 * v + c] + s * direction_[3 * v + c];
        work_.evaluate(metric_, trial_x_, trial_q_);
        ++summary_.quality_passes;
        bool blocked = true;
        for (int round = 0; round < 64 && blocked; ++round) {
            damped.clear();
            for (ElementId e = 0; e < movable; ++e)
                if (blocks(e))
                    for (VertexId v : mesh.element(e))
                        if (!mesh.fixed()[v] && stamp_[v] != round + 1) {
                            stamp_[v] = round + 1;
                            damped.push_back(v);
                        }
            blocked = !damped.empty();
            if (!blocked) break;
            ++element_stamp_round_;
            for (VertexId v : damped) {
                damping_[v] *= 0.25;
                for (int c = 0; c < 3; ++c) trial_x_[3 * v + c] = x_[3 * v + c] + damping_[v] * s * direction_[3 * v + c];
            }
            for (VertexId v : damped)
                for (ElementId e : mesh.elements_of(v)) {
                    if (e >= movable || element_stamp_[e] == element_stamp_round_) continue;
                    element_stamp_[e] = element_stamp_round_;
                    metric_.evaluate(mesh, trial_x_, e, e + 1, &trial_q_[e]);
                }
        }
        std::fill(stamp_.begin(), stamp_.end(), 0);
        if (blocked) continue;
        // The Armijo test uses the slope of the damped step actually taken.
        const double slope = detail::blocked_sums<1>(static_cast<std::size_t>(n), [&](std::size_t v, auto& acc) {
            for (int c = 0; c < 3; ++c) acc[0] += gradient_[3 * v + c] * damping_[v] * direction_[3 * v + c];
        })[0];
        if (!(slope > 0.0)) continue;
        const double trial_objective = objective_.value(trial_q_, kSerial);
        if (trial_objective > objective + 1e-4 * s * slope) {
            gain_ = trial_objective - objective;
            x_.swap(trial_x_);
            q_.swap(trial_q_);
            return true;
        }
    }
    return false;
}

// preconditioned = M^-1 gradient, M per vertex the 3x3 Gauss-Newton block of the objective
// (curvature), regularized: a Newton step for each vertex as if its neighbours stood still. It
// evens out the very different scales of elements and barrier weights.
void Phase::apply_preconditioner() {
    const std::size_t n = x_.size() / 3;
    double trace_sum = 0.0;
    std::size_t counted = 0;
    for (std::size_t v = 0; v < n; ++v) {
        const double* m = &curvature_[6 * v];
        const double trace = m[0] + m[3] + m[5];
        if (trace > 0.0) trace_sum += trace, ++counted;
    }
    if (counted == 0) {
        preconditioned_ = gradient_;
        return;
    }
    const double floor = 1e-8 * trace_sum / static_cast<double>(counted);
#pragma omp parallel for schedule(static) if (n > detail::kParallelThreshold)
    for (std::size_t v = 0; v < n; ++v) {
        const double* m = &curvature_[6 * v];
        const double lambda = 1e-3 * (m[0] + m[3] + m[5]) / 3.0 + floor;
        const double a = m[0] + lambda, b = m[1], c = m[2], d = m[3] + lambda, e = m[4], f = m[5] + lambda;
        // Symmetric [[a b c] [b d e] [c e f]]: inverse by cofactors (positive definite here).
        const double A = d * f - e * e, B = c * e - b * f, C = b * e - c * d;
        const double det = a * A + b * B + c * C;
        const double* g = &gradient_[3 * v];
        double* z = &preconditioned_[3 * v];
        if (!(det > 0.0)) {
            for (int k = 0; k < 3; ++k) z[k] = 0.0;
            continue;
        }
        const double D = a * f - c * c, E = b * c - a * e, F = a * d - b * b;
        z[0] = (A * g[0] + B * g[1] + C * g[2]) / det;
        z[1] = (B * g[0] + D * g[1] + E * g[2]) / det;
        z[2] = (C * g[0] + E * g[1] + F * g[2]) / det;
    }
}

PhaseResult Phase::end(TerminationReason reason, std::string message) {
    x_.swap(best_x_);  // the best iterate, which may be the current one
    return {reason, std::move(message)};
}

PhaseResult Phase::run() {
    const std::size_t m = static_cast<std::size_t>(work_.movable_elements());
    const std::size_t n3 = x_.size();
    q_.resize(m);
    trial_q_.resize(m);
    weight_.resize(m);
    trial_x_.resize(n3);
    gradient_.assign(n3, 0.0);
    direction_.assign(n3, 0.0);
    previous_gradient_.assign(n3, 0.0);
    best_x_ = x_;
    damping_.assign(n3 / 3, 1.0);
    curvature_weight_.assign(m, 0.0);
    curvature_.assign(2 * n3, 0.0);
    preconditioned_.assign(n3, 0.0);
    previous_preconditioned_.assign(n3, 0.0);
    stamp_.assign(n3 / 3, 0);
    element_stamp_.assign(m, 0);

    work_.evaluate(metric_, x_, q_);
    ++summary_.quality_passes;
    objective_.update(q_, kSerial);
    Stats s = stats(q_);
    best_worst_ = s.worst;
    best_bad_ = s.bad;
    std::vector<double> best_history{best_worst_};
    std::vector<double> measure_history{objective_.progress_measure()};
    std::vector<long> bad_history{s.bad};
    // The objective and its weights at the current iterate, for the history and the next step.
    double objective = objective_.value_and_weights(q_, weight_, kSerial);
    record(s, objective, 0.0, 0.0);
    if (untangling_ && s.bad == 0 && untangled()) return end(TerminationReason::TargetReached, "untangled");

    const bool precondition = untangling_ && options_.precondition_untangling;
    double first_gradient_norm = -1.0;
    bool restart = true;  // next direction is steepest ascent
    int failures = 0;     // line searches in a row that found no step
    int steps_at_mu = 0;
    for (int iteration = 1;; ++iteration) {
        if (iteration > stop_.max_iterations)
            return end(TerminationReason::IterationLimit, "stopped after " + std::to_string(stop_.max_iterations) + " iterations");
        if (stop_.max_seconds > 0.0 && seconds_since(start_) > stop_.max_seconds)
            return end(TerminationReason::TimeLimit, "time limit reached");

        if (precondition) {
            objective_.curvature_weights(q_, curvature_weight_);
            work_.gradient(metric_, x_, weight_, gradient_, curvature_weight_, curvature_);
        } else {
            work_.gradient(metric_, x_, weight_, gradient_);
        }
        ++summary_.gradient_passes;
        const double g2 = detail::blocked_sums<1>(n3, [&](std::size_t i, auto& acc) { acc[0] += gradient_[i] * gradient_[i]; })[0];
        const double gradient_norm = std::sqrt(g2);
        if (first_gradient_norm < 0.0) first_gradient_norm = gradient_norm;
        if (!(gradient_norm > stop_.gradient_tolerance * first_gradient_norm))
            return end(TerminationReason::GradientVanished, "the objective's gradient vanished");
        if (precondition) apply_preconditioner();
        else preconditioned_ = gradient_;

        // Polak-Ribiere+ conjugate gradient (preconditioned), restarted whenever the objective
        // changes (mu) or the direction stops ascending.
        double beta = 0.0;
        if (options_.direction == GlobalSolverOptions::Direction::ConjugateGradient && !restart) {
            const auto sums = detail::blocked_sums<2>(n3, [&](std::size_t i, auto& acc) {
                acc[0] += preconditioned_[i] * (gradient_[i] - previous_gradient_[i]);
                acc[1] += previous_preconditioned_[i] * previous_gradient_[i];
            });
            beta = sums[1] > 0.0 ? std::max(0.0, sums[0] / sums[1]) : 0.0;
        }
        for (std::size_t i = 0; i < n3; ++i) direction_[i] = preconditioned_[i] + beta * direction_[i];
        const double slope = detail::blocked_sums<1>(n3, [&](std::size_t i, auto& acc) { acc[0] += gradient_[i] * direction_[i]; })[0];
        if (!(slope > 0.0)) direction_ = preconditioned_;
        previous_gradient_ = gradient_;
        previous_preconditioned_ = preconditioned_;
        double max_direction = 0.0;
        for (std::size_t v = 0; v < n3; v += 3)
            max_direction = std::max(max_direction, std::hypot(direction_[v], direction_[v + 1], direction_[v + 2]));

        const bool accepted = line_search(objective, max_direction);
        const double step = accepted ? step_ : 0.0;
        ++summary_.iterations;
        if (untangling_) ++summary_.untangle_iterations;
        // mu stays fixed for a few steps, so that conjugate directions make sense, and shrinks
        // once they are taken or when no step was found (weighting the worst elements more).
        failures = accepted ? 0 : failures + 1;
        restart = !accepted;
        // Steps may grow far beyond the mesh's size: an untangled vertex can have been thrown far
        // out (two_tets.vtk) and must be able to come back.
        if (accepted) step_ = std::min(2.0 * step_, 1e6);
        else step_ = 0.05;
        if (!accepted || ++steps_at_mu >= options_.steps_per_mu) {
            objective_.advance();
            steps_at_mu = 0;
            restart = true;
        }
        objective_.update(q_, kSerial);
        s = stats(q_);
        // Better: fewer non-positive elements, then a higher worst quality.
        if (s.bad < best_bad_ || (s.bad == best_bad_ && s.worst > best_worst_)) {
            best_bad_ = s.bad;
            best_worst_ = s.worst;
            best_x_ = x_;
        }
        objective = objective_.value_and_weights(q_, weight_, kSerial);
        record(s, objective, step, accepted ? gain_ : 0.0);
        best_history.push_back(best_worst_);
        measure_history.push_back(objective_.progress_measure());
        bad_history.push_back(s.bad);

        if (untangling_ && s.bad == 0 && untangled()) {
            best_x_ = x_;
            return end(TerminationReason::TargetReached, "untangled");
        }
        if (!untangling_ && stop_.target_worst_quality && best_worst_ >= *stop_.target_worst_quality)
            return end(TerminationReason::TargetReached, "the worst quality reached the target");
        bool stalled = failures >= options_.max_failed_searches;
        const auto window = static_cast<std::size_t>(stop_.progress_window);
        if (!stalled && best_history.size() > window) {
            const double tolerance = stop_.min_progress * std::max(std::abs(best_worst_), 1e-3);
            const std::size_t then = best_history.size() - 1 - window;
            stalled = best_worst_ - best_history[then] <= tolerance &&
                      measure_history.back() - measure_history[then] <= tolerance &&
                      bad_history.back() >= bad_history[then];
        }
        if (failures >= options_.max_failed_searches)
            return end(TerminationReason::NoImprovingStep, "no step along the search direction raises the objective");
        if (stalled) return end(TerminationReason::Converged, "the worst quality stopped improving");
    }
}

// Sweeps over the free vertices of non-positive elements, untangling each locally, until a sweep
// moves none (or ten sweeps); records one history entry. Returns the vertices moved.
int local_untangle_sweeps(detail::Workspace& work, std::vector<double>& xyz, const QualityMetric& hybrid,
                          Summary& summary, const IterationObserver& observer, Clock::time_point start) {
    const SimplexMesh& mesh = work.mesh();
    const auto m = static_cast<std::size_t>(work.movable_elements());
    std::vector<double> q(m);
    int moved = 0;
    for (int sweep = 0; sweep < 10; ++sweep) {
        work.evaluate(hybrid, xyz, q);
        std::vector<VertexId> candidates;
        for (std::size_t e = 0; e < m; ++e)
            if (q[e] <= 0.0)
                for (VertexId v : mesh.element(static_cast<ElementId>(e)))
                    if (!mesh.fixed()[v]) candidates.push_back(v);
        std::sort(candidates.begin(), candidates.end());
        candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
        int moved_now = 0;
        for (VertexId v : candidates) moved_now += detail::untangle_vertex(mesh, xyz, v, work.scale()).moved;
        moved += moved_now;
        if (moved_now == 0) break;
    }
    work.evaluate(hybrid, xyz, q);
    ++summary.quality_passes;
    IterationRecord r;
    r.iteration = summary.iterations;
    r.phase = "untangle_local";
    r.worst_quality = q.empty() ? 0.0 : *std::min_element(q.begin(), q.end());
    r.best_worst_quality = r.worst_quality;
    r.inverted = std::count_if(q.begin(), q.end(), [](double v) { return v <= 0.0; });
    r.mean_quality = std::accumulate(q.begin(), q.end(), 0.0) / static_cast<double>(std::max<std::size_t>(1, m));
    r.moved = moved;
    r.seconds = seconds_since(start);
    summary.history.push_back(std::move(r));
    if (observer) observer(summary.history.back());
    return moved;
}

}  // namespace

GlobalSolver::GlobalSolver(GlobalSolverOptions options) : options_(std::move(options)) { options_.validate(); }

Summary GlobalSolver::improve(SimplexMesh& mesh) {
    detail::ThreadScope threads(options_.threads);
    detail::SolverRun run(mesh, std::string(name()), options_.shape_metric);
    Summary& summary = run.summary;
    const auto start = run.start();
    auto finish = [&](TerminationReason reason, std::string message) { return run.finish(reason, std::move(message)); };

    if (auto nothing = run.nothing_to_move()) return *nothing;
    detail::Workspace work(mesh, options_.renumber);
    std::vector<double> xyz(work.mesh().coordinates().begin(), work.mesh().coordinates().end());

    PhaseResult result{TerminationReason::TargetReached, ""};
    const bool tangled = summary.before.inverted - summary.before.inverted_frozen > 0 ||
                         summary.before.degenerate > 0;
    if (tangled && options_.untangle) {
        auto hybrid = make_metric("untangle_hybrid", options_.metric_options);
        // Volumes measured against the size of each element's neighbourhood, so that a graded
        // mesh's small inverted elements weigh as much as its large ones.
        const std::vector<double> local_volumes = MetricScale::local_reference_volumes(work.mesh());
        MetricScale hybrid_scale = work.scale();
        hybrid_scale.element_reference_volume = local_volumes;
        hybrid->set_scale(hybrid_scale);
        // The global barrier ascent untangles most of a mesh; where it stalls on a few elements
        // (a local maximum of the worst quality), local steps move single vertices to where
        // their elements' smallest volume is largest, and the barrier ascent resumes.
        for (int round = 0;; ++round) {
            TerminationCriterion stop = options_.untangle_termination;
            stop.max_iterations = std::max(0, stop.max_iterations - summary.untangle_iterations);
            // Hybrid qualities start negative: only the barrier (any t below them) is defined there.
            auto objective = make_objective("log_barrier", options_.objective_options);
            result = Phase(work, xyz, *hybrid, *objective, stop, options_, true, summary, observer(), start).run();
            if (result.reason == TerminationReason::TargetReached) break;
            const bool out_of_budget =
                result.reason == TerminationReason::IterationLimit || result.reason == TerminationReason::TimeLimit;
            if (out_of_budget || round == options_.local_untangle_rounds ||
                local_untangle_sweeps(work, xyz, *hybrid, summary, observer(), start) == 0) {
                work.copy_back(xyz, mesh);
                return finish(TerminationReason::CannotUntangle,
                              "untangling stopped (" + result.message + ") with elements still inverted");
            }
        }
    }
    const bool still_tangled = !options_.untangle && tangled;
    if (options_.improve_shape && !still_tangled) {
        auto metric = make_metric(options_.shape_metric, options_.metric_options);
        metric->set_scale(work.scale());
        auto objective = make_objective(options_.objective, options_.objective_options);
        result = Phase(work, xyz, *metric, *objective, options_.termination, options_, false, summary, observer(), start).run();
    }
    work.copy_back(xyz, mesh);
    if (summary.before.inverted_frozen > 0)
        return finish(TerminationReason::CannotUntangle,
                      std::to_string(summary.before.inverted_frozen) +
                          " inverted elements have all their vertices fixed; no smoother can move them");
    if (still_tangled)
        return finish(TerminationReason::CannotUntangle, "the mesh is tangled and untangling was turned off");
    return finish(result.reason, result.message);
}

}  // namespace paloverde
