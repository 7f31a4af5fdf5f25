#include "energy_untangle.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>

#include "core/exact_sums.hpp"
#include "paloverde/metrics/quality_metric.hpp"
#include "iteration_start.hpp"
#include "local_untangle.hpp"

namespace paloverde::detail {

namespace {

// Steps of limited-memory BFGS per value of eps, and the pairs it remembers.
constexpr int kStepsPerEpsilon = 30;
constexpr std::size_t kMemory = 7;
// Steps without a better valid iterate that end the round after the first valid one.
constexpr int kSettlePatience = 5;

// The checkpoint's name of the k-th remembered step ('s') or gradient change ('y').
std::string pair_field(char which, std::size_t k) {
    std::string name(1, which);
    name += std::to_string(k);
    return name;
}

// Where the smallest scale-free volume stands, over every process.
struct Volumes {
    double worst = 0.0;  // smallest det J
    long bad = 0;        // elements with det J <= 0
};

class EnergyUntangler {
public:
    EnergyUntangler(Workspace& work, std::vector<double>& xyz, Summary& summary, const IterationObserver& observer,
                    Clock::time_point start, const SlidingVertices* sliding)
        : work_(work), x_(xyz), summary_(summary), observer_(observer), start_(start), sliding_(sliding),
          reference_(work.local_reference_volumes()), volume_(make_metric("scaled_volume")) {
        // Sizes measured against each element's neighbourhood, as in the hybrid metric: a graded
        // mesh keeps its grading, and the energy does not depend on the mesh's units.
        scale_ = work.scale();
        scale_.element_reference_volume = reference_;
        volume_->set_scale(scale_);
        const std::size_t m = static_cast<std::size_t>(work.movable_elements());
        q_.resize(m);
        ones_.assign(m, 1.0);
        g_.assign(x_.size(), 0.0);
        // The energy is scale-free per element, so its curvature at a vertex goes as the sum of
        // 1 / (element size)^2 over the vertex's elements: its inverse is the vertex's step scale.
        const Mesh& mesh = work.mesh();
        const double power = mesh.kind() == ElementKind::Tetrahedron ? -2.0 / 3.0 : -1.0;
        step_scale_.assign(static_cast<std::size_t>(mesh.num_vertices()), 0.0);
        for (ElementId e = 0; e < work.movable_elements(); ++e) {
            const double stiffness = std::pow(reference_[static_cast<std::size_t>(e)], power);
            for (VertexId v : mesh.element(e)) step_scale_[v] += stiffness;
        }
        for (double& h : step_scale_) h = h > 0.0 ? 1.0 / h : 0.0;
    }

    EnergyUntangling run(int max_iterations, double max_seconds, Checkpointer& checkpointer, const SolverState* resume);

private:
    Volumes volumes(std::span<const double> x);
    double energy(const QualityMetric& metric, std::span<const double> x);
    // The energy's gradient (the metric is its negative, so the sign flips).
    void energy_gradient(const QualityMetric& metric, std::span<const double> x, std::vector<double>& g);
    double dot(const std::vector<double>& a, const std::vector<double>& b) const { return owned_dot(work_, a, b); }
    double largest_move(const std::vector<double>& d) const;
    void record(const Volumes& now, const Volumes& best, double epsilon, double energy, double step, double gain);
    bool untangled() const { return detail::untangled(work_, x_); }
    // A round: limited-memory BFGS at one epsilon, from a fresh memory.
    void start_round();
    void remember(std::vector<double> s, std::vector<double> y);
    void direction(std::vector<double>& d) const;
    void save(Checkpointer& checkpointer) const;
    void restore(const SolverState& state);

    Workspace& work_;
    std::vector<double>& x_;
    Summary& summary_;
    const IterationObserver& observer_;
    Clock::time_point start_;
    const SlidingVertices* sliding_;  // a surface mesh's vertices, which slide on it
    std::vector<double> reference_;
    MetricScale scale_;
    std::unique_ptr<QualityMetric> volume_;
    std::vector<double> q_, ones_, counted_;
    std::vector<double> step_scale_;  // per vertex
    // The iteration's state (saved in checkpoints, with what it implies).
    double epsilon_ = kFirstUntangleEpsilon;
    double e_ = 0.0, e_start_ = 0.0;  // the energy now and at the round's start
    int inner_ = 0;                   // steps taken in this round
    int steps_ = 0;
    bool valid_found_ = false;        // an iterate was valid: best_ and best_x_ are the best valid one
    int rounds_valid_ = 0;            // rounds that ended with a valid iterate found
    int since_best_ = 0;              // steps since the best iterate last changed
    Volumes now_, best_;
    std::vector<double> best_x_, g_;
    std::deque<std::vector<double>> s_history_, y_history_;
    std::deque<double> rho_;
    std::unique_ptr<QualityMetric> metric_;
};

Volumes EnergyUntangler::volumes(std::span<const double> x) {
    work_.evaluate(*volume_, x, q_);
    ++summary_.quality_passes;
    Volumes out{std::numeric_limits<double>::infinity(), 0};
    for (double v : work_.counted(q_, counted_)) {
        out.worst = std::min(out.worst, std::isnan(v) ? -std::numeric_limits<double>::infinity() : v);
        out.bad += !(v > 0.0);
    }
    out.worst = work_.reducer().min(out.worst);
    out.bad = static_cast<long>(work_.reducer().total(static_cast<double>(out.bad)));
    return out;
}

double EnergyUntangler::energy(const QualityMetric& metric, std::span<const double> x) {
    work_.evaluate(metric, x, q_);
    ++summary_.quality_passes;
    const auto q = work_.counted(q_, counted_);
    double largest = 0.0;
    for (double v : q) largest = std::max(largest, std::abs(v));
    largest = work_.reducer().max(largest);
    auto sums = bounded_sums<1>(q.size(), {largest}, [&](std::size_t i, auto& acc) { acc[0].add(-q[i]); });
    work_.reducer().sum(sums);
    return sums[0].value();
}

void EnergyUntangler::energy_gradient(const QualityMetric& metric, std::span<const double> x, std::vector<double>& g) {
    work_.gradient(metric, x, ones_, g);
    ++summary_.gradient_passes;
    for (double& v : g) v = -v;
    // A sliding vertex descends along its surface or curve: the memory then learns that space.
    if (sliding_) sliding_->tangent(g);
}

double EnergyUntangler::largest_move(const std::vector<double>& d) const {
    double largest = 0.0;
    const auto owned = work_.owned();
    for (std::size_t v = 0; v < owned.size(); ++v)
        if (owned[v]) largest = std::max(largest, std::hypot(d[3 * v], d[3 * v + 1], d[3 * v + 2]));
    return work_.reducer().max(largest);
}

// The phase hands back its best iterate, so a row's count and best worst are the best iterate's
// (an iterate may invert elements on its way); the worst quality is this iterate's.
void EnergyUntangler::record(const Volumes& now, const Volumes& best, double epsilon, double energy, double step,
                             double gain) {
    IterationRecord r;
    r.iteration = summary_.iterations;
    r.phase = "untangle_energy";
    r.worst_quality = now.worst;
    r.best_worst_quality = best.worst;
    r.inverted = best.bad;
    r.mu = epsilon;
    r.objective = energy;
    r.step = step;
    r.gain = gain;
    r.seconds = seconds_since(start_);
    summary_.history.push_back(std::move(r));
    if (observer_) observer_(summary_.history.back());
}

void EnergyUntangler::start_round() {
    metric_ = make_untangle_energy(epsilon_, kUntangleTheta);
    metric_->set_scale(scale_);
    e_ = energy(*metric_, x_);
    energy_gradient(*metric_, x_, g_);
    s_history_.clear();
    y_history_.clear();
    rho_.clear();
}

void EnergyUntangler::remember(std::vector<double> s, std::vector<double> y) {
    const double sy = dot(s, y);
    if (!(sy > 0.0)) return;  // no curvature along the step: nothing to learn
    s_history_.push_back(std::move(s));
    y_history_.push_back(std::move(y));
    rho_.push_back(1.0 / sy);
    if (s_history_.size() > kMemory) {
        s_history_.pop_front();
        y_history_.pop_front();
        rho_.pop_front();
    }
}

// d = -H g by the two-loop recursion, H the inverse Hessian the remembered pairs imply, starting
// from gamma * diag(step scale): vertices of small elements take small steps.
void EnergyUntangler::direction(std::vector<double>& d) const {
    const std::size_t n3 = d.size();
    for (std::size_t i = 0; i < n3; ++i) d[i] = -g_[i];
    std::vector<double> alpha(s_history_.size());
    for (std::size_t k = s_history_.size(); k-- > 0;) {
        alpha[k] = rho_[k] * dot(s_history_[k], d);
        for (std::size_t i = 0; i < n3; ++i) d[i] -= alpha[k] * y_history_[k][i];
    }
    double gamma = 1.0;
    if (!s_history_.empty()) {
        const auto& y = y_history_.back();
        const double yhy = owned_sums<1>(work_, [&](std::size_t v, auto& acc) {
            acc[0].add(step_scale_[v] * (y[3 * v] * y[3 * v] + y[3 * v + 1] * y[3 * v + 1] + y[3 * v + 2] * y[3 * v + 2]));
        })[0];
        gamma = dot(s_history_.back(), y) / yhy;
    }
    for (std::size_t i = 0; i < n3; ++i) d[i] *= gamma * step_scale_[i / 3];
    for (std::size_t k = 0; k < s_history_.size(); ++k) {
        const double beta = rho_[k] * dot(y_history_[k], d);
        for (std::size_t i = 0; i < n3; ++i) d[i] += (alpha[k] - beta) * s_history_[k][i];
    }
}

void EnergyUntangler::save(Checkpointer& checkpointer) const {
    SolverState state;
    state.numbers = {{"untangling", 1.0},
                     {"energy", 1.0},
                     {"round", 0.0},
                     {"epsilon", epsilon_},
                     {"energy_at_round_start", e_start_},
                     {"inner", inner_},
                     {"steps", steps_},
                     {"valid_found", valid_found_ ? 1.0 : 0.0},
                     {"rounds_valid", rounds_valid_},
                     {"since_best", since_best_},
                     {"best_bad", static_cast<double>(best_.bad)},
                     {"best_worst", best_.worst},
                     {"pairs", static_cast<double>(s_history_.size())}};
    state.vertex_fields = {{"x", x_}, {"best_x", best_x_}};
    for (std::size_t k = 0; k < s_history_.size(); ++k) {
        state.vertex_fields[pair_field('s', k)] = s_history_[k];
        state.vertex_fields[pair_field('y', k)] = y_history_[k];
    }
    checkpointer.save(summary_, state, seconds_since(start_));
}

// Everything else is a function of these: the energy and its gradient of x at epsilon, and each
// pair's rho, come out bit for bit as they were.
void EnergyUntangler::restore(const SolverState& state) {
    // The passes that recompute the state were counted by the run that saved it.
    const long quality_passes = summary_.quality_passes, gradient_passes = summary_.gradient_passes;
    const std::size_t n = x_.size() / 3;
    x_ = state.vertex_field("x", n);
    best_x_ = state.vertex_field("best_x", n);
    epsilon_ = state.number("epsilon");
    inner_ = static_cast<int>(state.number("inner"));
    steps_ = static_cast<int>(state.number("steps"));
    valid_found_ = state.number("valid_found") != 0.0;
    rounds_valid_ = static_cast<int>(state.number("rounds_valid"));
    since_best_ = static_cast<int>(state.number("since_best"));
    best_ = {state.number("best_worst"), static_cast<long>(state.number("best_bad"))};
    start_round();
    e_start_ = state.number("energy_at_round_start");
    const auto pairs = static_cast<std::size_t>(state.number("pairs"));
    for (std::size_t k = 0; k < pairs; ++k)
        remember(state.vertex_field(pair_field('s', k), n), state.vertex_field(pair_field('y', k), n));
    now_ = volumes(x_);
    summary_.quality_passes = quality_passes;
    summary_.gradient_passes = gradient_passes;
}

EnergyUntangling EnergyUntangler::run(int max_iterations, double max_seconds, Checkpointer& checkpointer,
                                      const SolverState* resume) {
    const std::size_t n3 = x_.size();
    const double length = work_.reference_length();
    const Reducer& reducer = work_.reducer();
    auto finish = [&](TerminationReason reason, std::string message) {
        x_.swap(best_x_);
        return EnergyUntangling{reason, std::move(message)};
    };
    if (resume) {
        restore(*resume);
    } else {
        now_ = volumes(x_);
        best_x_ = x_;
        best_ = now_;
        record(now_, best_, epsilon_, 0.0, 0.0, 0.0);
        if (now_.bad == 0 && untangled()) return finish(TerminationReason::TargetReached, "untangled");
    }

    TerminationCriterion budget;
    budget.max_iterations = max_iterations;
    budget.max_seconds = max_seconds;
    IterationStart top(budget, reducer, start_, "iterations", &checkpointer);
    std::vector<double> g_new(n3), d(n3), trial(n3);
    bool new_round = !resume;  // restore() has set up the round it resumes
    for (int idle = 0;;) {
        if (new_round) {
            start_round();
            e_start_ = e_;
            new_round = false;
        }
        // Checkpoints and stops at the top of an iteration, where the state is complete. Its
        // budget counts steps; a spent one ends the untangling where a valid iterate was found.
        if (auto stop = top(steps_ + 1, summary_.iterations, [&] { save(checkpointer); })) {
            if (stop->reason != TerminationReason::Interrupted && valid_found_)
                return finish(TerminationReason::TargetReached, "untangled");
            return finish(stop->reason, std::move(stop->message));
        }
        if (idle > kStepsPerEpsilon)  // rounds in a row without a step: the energy cannot go on
            return finish(valid_found_ ? TerminationReason::TargetReached : TerminationReason::CannotUntangle,
                          valid_found_ ? "untangled" : "the untangling energy found no more steps");

        direction(d);
        if (sliding_) sliding_->tangent(d);  // the projected steps' pairs are not tangent quite
        double slope = dot(g_, d);
        if (!(slope < 0.0)) {  // not a descent direction: start the memory afresh
            for (std::size_t i = 0; i < n3; ++i) d[i] = -step_scale_[i / 3] * g_[i];
            s_history_.clear();
            y_history_.clear();
            rho_.clear();
            slope = dot(g_, d);
        }
        work_.halo().update(d, 3);
        const double move = largest_move(d);
        bool round_over = !(move > 0.0) || !(slope < 0.0);  // converged at this epsilon
        if (!round_over) {
            // Without curvature pairs yet, the first trial moves the farthest vertex a tenth of
            // the reference length; then the quasi-Newton step 1 is the natural first trial.
            // Steps that throw a vertex further than a few reference lengths are never needed.
            // A sliding vertex goes at most one: its tangent plane says little about the surface
            // farther away, and the projection of a far point lands anywhere.
            const double farthest = (sliding_ ? 1.0 : 4.0) * length / move;
            double step = std::min(s_history_.empty() ? std::min(1.0, 0.1 * length / move) : 1.0, farthest);
            double e_trial = e_;
            bool accepted = false;
            for (int attempt = 0; attempt < 40 && !accepted; ++attempt) {
                if (attempt > 0) step *= 0.5;
                for (std::size_t i = 0; i < n3; ++i) trial[i] = x_[i] + step * d[i];
                if (sliding_) sliding_->project(work_.mesh(), trial);
                e_trial = energy(*metric_, trial);
                accepted = e_trial < e_ && e_trial <= e_ + 1e-4 * step * slope;
            }
            ++steps_;
            ++summary_.iterations;
            ++summary_.untangle_iterations;
            ++inner_;
            if (accepted) {
                idle = 0;
                x_.swap(trial);
                energy_gradient(*metric_, x_, g_new);
                std::vector<double> s(n3), y(n3);
                for (std::size_t i = 0; i < n3; ++i) {
                    s[i] = sliding_ ? x_[i] - trial[i] : step * d[i];  // (trial: the iterate before)
                    y[i] = g_new[i] - g_[i];
                }
                remember(std::move(s), std::move(y));
                g_.swap(g_new);
                const double e_before = e_;
                e_ = e_trial;
                now_ = volumes(x_);
                // Validity is decided exactly (only for an iterate that would be the best valid
                // one: the check costs a pass); among valid iterates the best has the largest
                // smallest volume.
                const bool valid = now_.bad == 0 && (!valid_found_ || now_.worst > best_.worst) && untangled();
                const bool better = valid || (!valid_found_ && (now_.bad < best_.bad ||
                                                                (now_.bad == best_.bad && now_.worst > best_.worst)));
                if (better) {
                    best_ = now_;
                    best_x_ = x_;
                }
                const bool first_valid = valid && !valid_found_;
                valid_found_ = valid_found_ || valid;
                since_best_ = better ? 0 : since_best_ + 1;
                record(now_, best_, epsilon_, e_, step * move / length, e_before - e_);
                // The round after the first valid iterate ends once the best has not risen for a
                // few steps: the rises come early, and the steps after them rarely add any.
                round_over = first_valid || e_before - e_ <= 1e-6 * std::abs(e_) || inner_ == kStepsPerEpsilon ||
                             (valid_found_ && since_best_ >= kSettlePatience);
            } else {
                record(now_, best_, epsilon_, e_, 0.0, 0.0);
                round_over = true;
            }
        }
        if (!round_over) continue;
        if (inner_ == 0) ++idle;
        inner_ = 0;
        new_round = true;
        // The first valid iterate ends its round. It can be barely valid (a collapsed element
        // that flipped back by a hair): one more round at the next epsilon, whose barrier pushes
        // such elements open, and the phase ends on its best valid iterate.
        if (valid_found_ && ++rounds_valid_ == 2) return finish(TerminationReason::TargetReached, "untangled");
        epsilon_ = next_epsilon(epsilon_, e_start_, e_, now_.worst);
        if (!(epsilon_ > 1e-300) || !std::isfinite(epsilon_))
            return finish(TerminationReason::NumericalFailure, "the untangling energy's epsilon left the numbers");
    }
}

}  // namespace

EnergyUntangling energy_untangle(Workspace& work, std::vector<double>& xyz, int max_iterations, double max_seconds,
                                 Summary& summary, const IterationObserver& observer, Clock::time_point start,
                                 Checkpointer& checkpointer, const SolverState* resume,
                                 const SlidingVertices* sliding) {
    return EnergyUntangler(work, xyz, summary, observer, start, sliding)
        .run(max_iterations, max_seconds, checkpointer, resume);
}

}  // namespace paloverde::detail
