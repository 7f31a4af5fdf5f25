#include "paloverde/solvers/global_solver.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <omp.h>

#include "core/blocked_sum.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/mesh/orientation.hpp"
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
    if (max_failed_searches < 1) throw OptionError("max_failed_searches must be >= 1");
}

namespace {

using Clock = std::chrono::steady_clock;
const Reducer kSerial;

double seconds_since(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

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
          Clock::time_point start)
        : work_(work), x_(xyz), metric_(metric), objective_(objective), stop_(stop), options_(options),
          untangling_(untangling), summary_(summary), start_(start) {}

    PhaseResult run();

private:
    struct Stats {
        double worst, mean;
        long bad;  // non-positive qualities
    };
    Stats stats(std::span<const double> q) const;
    bool line_search(double objective, double slope, double max_direction);
    bool untangled() const;
    void record(const Stats& s, double step, double gain);
    PhaseResult end(TerminationReason reason, std::string message);

    detail::Workspace& work_;
    std::vector<double>& x_;
    const QualityMetric& metric_;
    ObjectiveFunction& objective_;
    const TerminationCriterion& stop_;
    const GlobalSolverOptions& options_;
    bool untangling_;
    Summary& summary_;
    Clock::time_point start_;

    std::vector<double> q_, trial_q_, weight_, trial_x_, gradient_, direction_, previous_gradient_, best_x_;
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

void Phase::record(const Stats& s, double step, double gain) {
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
    r.objective = objective_.value(q_, kSerial);
    r.step = step;
    r.gain = gain;
    r.seconds = seconds_since(start_);
    summary_.history.push_back(std::move(r));
}

bool Phase::line_search(double objective, double slope, double max_direction) {
    const auto n = x_.size();
    const double length = work_.reference_length();
    for (int attempt = 0; attempt < 40; ++attempt, step_ *= 0.5) {
        const double s = step_ * length / max_direction;
#pragma omp parallel for schedule(static)
        for (std::size_t i = 0; i < n; ++i) trial_x_[i] = x_[i] + s * direction_[i];
        work_.evaluate(metric_, trial_x_, trial_q_);
        ++summary_.quality_passes;
        double trial_worst = std::numeric_limits<double>::infinity();
        long new_bad = 0, fixed_bad = 0;
        for (std::size_t e = 0; e < trial_q_.size(); ++e) {
            trial_worst = std::min(trial_worst, trial_q_[e]);
            new_bad += trial_q_[e] <= 0.0 && q_[e] > 0.0;
            fixed_bad += trial_q_[e] > 0.0 && q_[e] <= 0.0;
        }
        // Untangling may flip a valid element only while it fixes at least as many inverted
        // ones (demanding none would lock vertices between two tangled neighbours); once the
        // mesh is valid, no element may become non-positive.
        const bool more_bad = untangling_ ? new_bad > fixed_bad : new_bad > 0;
        if (more_bad || !objective_.admissible(trial_worst)) continue;
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

    work_.evaluate(metric_, x_, q_);
    ++summary_.quality_passes;
    objective_.update(q_, kSerial);
    Stats s = stats(q_);
    best_worst_ = s.worst;
    best_bad_ = s.bad;
    std::vector<double> best_history{best_worst_};
    std::vector<double> measure_history{objective_.progress_measure()};
    record(s, 0.0, 0.0);
    if (untangling_ && s.bad == 0 && untangled()) return end(TerminationReason::TargetReached, "untangled");

    double first_gradient_norm = -1.0;
    bool restart = true;  // next direction is steepest ascent
    int failures = 0;     // line searches in a row that found no step
    int steps_at_mu = 0;
    for (int iteration = 1;; ++iteration) {
        if (iteration > stop_.max_iterations)
            return end(TerminationReason::IterationLimit, "stopped after " + std::to_string(stop_.max_iterations) + " iterations");
        if (stop_.max_seconds > 0.0 && seconds_since(start_) > stop_.max_seconds)
            return end(TerminationReason::TimeLimit, "time limit reached");

        const double objective = objective_.value_and_weights(q_, weight_, kSerial);
        work_.gradient(metric_, x_, weight_, gradient_);
        ++summary_.gradient_passes;
        const double g2 = detail::blocked_sums<1>(n3, [&](std::size_t i, auto& acc) { acc[0] += gradient_[i] * gradient_[i]; })[0];
        const double gradient_norm = std::sqrt(g2);
        if (first_gradient_norm < 0.0) first_gradient_norm = gradient_norm;
        if (!(gradient_norm > stop_.gradient_tolerance * first_gradient_norm))
            return end(TerminationReason::GradientVanished, "the objective's gradient vanished");

        // Polak-Ribiere+ conjugate gradient, restarted whenever the objective changes (mu) or
        // the direction stops ascending.
        double beta = 0.0;
        if (options_.direction == GlobalSolverOptions::Direction::ConjugateGradient && !restart) {
            const auto sums = detail::blocked_sums<2>(n3, [&](std::size_t i, auto& acc) {
                acc[0] += gradient_[i] * (gradient_[i] - previous_gradient_[i]);
                acc[1] += previous_gradient_[i] * previous_gradient_[i];
            });
            beta = sums[1] > 0.0 ? std::max(0.0, sums[0] / sums[1]) : 0.0;
        }
        for (std::size_t i = 0; i < n3; ++i) direction_[i] = gradient_[i] + beta * direction_[i];
        double slope = detail::blocked_sums<1>(n3, [&](std::size_t i, auto& acc) { acc[0] += gradient_[i] * direction_[i]; })[0];
        if (!(slope > 0.0)) {
            direction_ = gradient_;
            slope = g2;
        }
        previous_gradient_ = gradient_;
        double max_direction = 0.0;
        for (std::size_t v = 0; v < n3; v += 3)
            max_direction = std::max(max_direction, std::hypot(direction_[v], direction_[v + 1], direction_[v + 2]));

        const bool accepted = line_search(objective, slope, max_direction);
        const double step = accepted ? step_ : 0.0;
        ++summary_.iterations;
        if (untangling_) ++summary_.untangle_iterations;
        // mu stays fixed for a few steps, so that conjugate directions make sense, and shrinks
        // once they are taken or when no step was found (weighting the worst elements more).
        failures = accepted ? 0 : failures + 1;
        restart = !accepted;
        if (accepted) step_ = std::min(2.0 * step_, 1.0);
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
        record(s, step, accepted ? gain_ : 0.0);
        best_history.push_back(best_worst_);
        measure_history.push_back(objective_.progress_measure());

        if (untangling_ && s.bad == 0 && untangled()) {
            best_x_ = x_;
            return end(TerminationReason::TargetReached, "untangled");
        }
        if (!untangling_ && stop_.target_worst_quality && best_worst_ >= *stop_.target_worst_quality)
            return end(TerminationReason::TargetReached, "the worst quality reached the target");
        if (failures >= options_.max_failed_searches)
            return end(TerminationReason::NoImprovingStep, "no step along the search direction raises the objective");
        const auto window = static_cast<std::size_t>(stop_.progress_window);
        if (best_history.size() > window) {
            const double tolerance = stop_.min_progress * std::max(std::abs(best_worst_), 1e-3);
            const std::size_t then = best_history.size() - 1 - window;
            if (best_worst_ - best_history[then] <= tolerance &&
                measure_history.back() - measure_history[then] <= tolerance)
                return end(TerminationReason::Converged, "the worst quality stopped improving");
        }
    }
}

// Restores the caller's threads setting when done.
class ThreadScope {
public:
    explicit ThreadScope(int threads) : saved_(omp_get_max_threads()) {
        if (threads > 0) omp_set_num_threads(threads);
    }
    ~ThreadScope() { omp_set_num_threads(saved_); }

private:
    int saved_;
};

}  // namespace

GlobalSolver::GlobalSolver(GlobalSolverOptions options) : options_(std::move(options)) { options_.validate(); }

Summary GlobalSolver::improve(SimplexMesh& mesh) {
    const auto start = Clock::now();
    ThreadScope threads(options_.threads);
    Summary summary;
    summary.solver = std::string(name());
    summary.quality_metric = options_.shape_metric;
    QualityAssessor assessor;
    summary.before = assessor.assess(mesh);
    const auto worst_movable = [&](const QualityReport& report) {
        const MetricReport* r = report.metric(options_.shape_metric);
        if (!r) r = &report.metrics.front();
        return r->movable.count > 0 ? r->movable.min : r->all.min;
    };
    summary.worst_before = worst_movable(summary.before);
    const std::vector<double> original(mesh.coordinates().begin(), mesh.coordinates().end());
    auto finish = [&](TerminationReason reason, std::string message) {
        summary.reason = reason;
        summary.message = std::move(message);
        summary.after = assessor.assess(mesh);
        summary.worst_after = worst_movable(summary.after);
        // The phases only accept steps that keep both from getting worse; this is the guarantee
        // should floating point and the exact predicate ever disagree.
        const bool worse = summary.after.inverted > summary.before.inverted ||
                           (summary.after.inverted == summary.before.inverted && summary.worst_after < summary.worst_before);
        if (worse) {
            std::copy(original.begin(), original.end(), mesh.coordinates().begin());
            summary.after = summary.before;
            summary.worst_after = summary.worst_before;
            summary.message += " (the result was worse than the input, which is handed back unchanged)";
        }
        summary.seconds = seconds_since(start);
        return summary;
    };

    if (mesh.num_elements() == 0) return finish(TerminationReason::NothingToMove, "the mesh has no elements");
    if (mesh.num_free_vertices() == 0)
        return finish(TerminationReason::NothingToMove, "every vertex is fixed: nothing can move");
    if (mesh.kind() == ElementKind::Triangle && !mesh.is_planar())
        throw MeshError("the triangles do not lie in one plane: Paloverde smooths planar triangle meshes and "
                        "tetrahedral meshes, not surfaces");

    detail::Workspace work(mesh, options_.renumber);
    if (work.movable_elements() == 0)
        return finish(TerminationReason::NothingToMove, "no element has a free vertex: nothing can move");
    std::vector<double> xyz(work.mesh().coordinates().begin(), work.mesh().coordinates().end());

    PhaseResult result{TerminationReason::TargetReached, ""};
    const bool tangled = summary.before.inverted - summary.before.inverted_frozen > 0 ||
                         summary.before.degenerate > 0;
    if (tangled && options_.untangle) {
        MetricOptions hybrid_options = options_.metric_options;
        auto hybrid = make_metric("untangle_hybrid", hybrid_options);
        hybrid->set_scale(work.scale());
        // Hybrid qualities start negative: only the barrier (any t below them) is defined there.
        auto objective = make_objective("log_barrier", options_.objective_options);
        result = Phase(work, xyz, *hybrid, *objective, options_.untangle_termination, options_, true, summary, start).run();
        if (result.reason != TerminationReason::TargetReached) {
            work.copy_back(xyz, mesh);
            return finish(TerminationReason::CannotUntangle,
                          "untangling stopped (" + result.message + ") with elements still inverted");
        }
    }
    const bool still_tangled = !options_.untangle && tangled;
    if (options_.improve_shape && !still_tangled) {
        auto metric = make_metric(options_.shape_metric, options_.metric_options);
        metric->set_scale(work.scale());
        auto objective = make_objective(options_.objective, options_.objective_options);
        result = Phase(work, xyz, *metric, *objective, options_.termination, options_, false, summary, start).run();
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
