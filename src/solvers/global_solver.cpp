#include "paloverde/solvers/global_solver.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <limits>
#include <optional>
#include <sstream>

#include "core/blocked_sum.hpp"
#include "core/exact_sums.hpp"
#include "core/extremes.hpp"
#include "core/fast_log.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/solvers/vertex_coloring.hpp"
#include "checkpointer.hpp"
#include "energy_untangle.hpp"
#include "local_untangle.hpp"
#include "newton_direction.hpp"
#include "run_support.hpp"
#include "sliding_boundary.hpp"
#include "stopping.hpp"
#include "workspace.hpp"

namespace paloverde {

void GlobalSolverOptions::validate() const {
    objective_options.validate();
    metric_options.validate();
    termination.validate();
    untangle_termination.validate();
    const auto made = make_objective(objective, objective_options);
    auto metric = make_metric(shape_metric, metric_options);
    if (!metric->has_gradient())
        throw OptionError("shape_metric '" + shape_metric + "' has no gradient; choose aspect_ratio, mean_ratio, "
                          "inverse_condition or edge_ratio");
    if (threads < 0) throw OptionError("threads must be >= 0 (0: the OpenMP default)");
    if (steps_per_mu < 1) throw OptionError("steps_per_mu must be >= 1");
    if (!(gain_tolerance >= 0.0) || !std::isfinite(gain_tolerance))
        throw OptionError("gain_tolerance must be a number >= 0 (0: mu shrinks after steps_per_mu steps)");
    if (!(focus_band > 0.0 && focus_band <= 1.0)) throw OptionError("focus_band must be in (0, 1]");
    if (!(finish_band > 0.0 && finish_band <= 1.0)) throw OptionError("finish_band must be in (0, 1]");
    if (!(newton_tolerance > 0.0) || !std::isfinite(newton_tolerance))
        throw OptionError("newton_tolerance must be a positive number");
    if (newton_cg_iterations < 1) throw OptionError("newton_cg_iterations must be >= 1");
    if (direction == Direction::Newton && improve_shape && !made->is_continuation())
        throw OptionError("direction newton needs the log_barrier objective (its curvature), not '" + objective + "'");
    if (local_untangle_rounds < 0) throw OptionError("local_untangle_rounds must be >= 0");
    if (max_failed_searches < 1) throw OptionError("max_failed_searches must be >= 1");
    surface.validate();
    if (boundary == Boundary::Slide) {
        detail::validate_sliding(checkpoint);
        if (direction == Direction::Newton)
            throw OptionError("direction newton does not go with boundary: slide yet (its Hessian solves know nothing "
                              "of the surface the boundary slides on); use conjugate_gradient or steepest_ascent");
    }
    checkpoint.validate();
}

namespace {

using detail::Clock;
using detail::seconds_since;

// Newton steps at one mu before its subproblem counts as out of reach.
constexpr int kNewtonStepsAtOneMu = 50;
// The finish starts a fresh barrier where the worst quality rose this many times the gap to t it
// began with above t.
constexpr double kLostGap = 4.0;

// A shape phase the Newton finish follows hands over once its worst quality and t rose by less
// than this many times min_progress over three progress windows (docs/global_solver.md, "The
// handover"): conjugate gradients that creep that slowly are slower than Newton steps (tire: the
// local smoother's worst at iteration 196 instead of 384).
constexpr double kHandoverProgress = 100.0;
// And sooner, at ten times that pace, where the steps of those windows also gained less than
// kCalmGain mu each on average: the barrier's subproblems are solved at every step and only the
// worst element creeps (tire: the local smoother's worst at iteration 152 instead of 196). Where
// the steps still gain far more, the conjugate gradients are working a plateau that they leave
// later: on fandisk-9M with barrier_initial_active 10% higher the worst stands within 0.03% for
// 30 iterations whose steps gain 1,500 mu each on average (tire's creep: 0.33), and handing over
// there ended on 0.168, not 0.191.
constexpr double kCalmHandoverProgress = 1000.0;
constexpr double kCalmGain = 1.0;
// And after a single progress window where its worst quality and t rose by less than
// kQuickHandoverProgress times min_progress while the steps gained less than kQuickGain mu each:
// a subproblem that is close to solved but whose gains stay above gain_tolerance holds mu (and
// the rules above wait for a smaller one) while only the bulk of the focus moves. On
// cub_wedge_like one mu held from iteration 55 to 89, the worst within 2e-5 from 75 on with
// steps gaining 5 mu each; handed over at 87 the finish reached the local smoother's worst at 94
// instead of 120. Steps that still gain thousands of mu (fandisk-9M above) do not hand over.
constexpr double kQuickHandoverProgress = 30.0;
constexpr double kQuickGain = 10.0;
// The shape phase's subproblem at one mu also counts as solved, for the max-min problem, once the
// worst element has held less than this share of the barrier's weight for a whole progress
// window: mu is then so large that t sits far below the worst, the steps work the many elements
// above t (each a term like the worst) and trade the worst ones for them. On cub_wedge_like one mu
// held for 60 iterations with the worst element's weight near 1/2900 (docs/global_solver.md, "A
// barrier that let its worst element go"); the next mu put t within six mu of the worst, which
// then rose fast. On a phase's first mu, which the automatic start placed to weigh many elements
// alike, only while the worst also stands farther above t than where the phase began (its weight
// below mu / first gap): the worst rose away from a t that stayed. On cube-clip-5 the first mu
// held 16 steps while the worst's gap grew from 0.030 to 0.103 (weight 1/700 to 1/2,600);
// cut at 10, the local smoother's worst came at iteration 42 instead of 59.
constexpr double kLeastWorstWeight = 0.01;

struct PhaseResult {
    TerminationReason reason;
    std::string message;
    // The Newton finish found its barrier's subproblem out of reach: a fresh barrier should follow.
    bool recenter = false;
    // The mean quality of the iterate handed back (the polish, which keeps the best mean).
    double mean = std::numeric_limits<double>::quiet_NaN();
};

// Where solve() stands, for checkpoints: the phase and, while untangling, the round; `finish`:
// the Newton finish of the shape phase, which goes on counting from the `iterations_before` of the
// phase before it; `fresh`: the finish's second part, on a fresh barrier; `newton_follows`: a
// shape phase the finish will follow; `polish`: the mean's polish after them all, which ends once
// the mean quality exceeds `mean_goal` (polish auto: the input's), and `shape_reason` why the
// shape phases before it stopped (GlobalSolverOptions::polish).
struct Stage {
    bool untangling = false;
    int round = 0;
    bool finish = false;
    bool newton_follows = false;
    int iterations_before = 0;
    bool fresh = false;
    bool polish = false;
    double mean_goal = std::numeric_limits<double>::infinity();
    TerminationReason shape_reason = TerminationReason::Converged;
};

// The mean's polish holds still the vertices of the elements in this lowest fraction of
// worst..ideal quality; the others stay above its top (GlobalSolverOptions::polish).
constexpr double kPolishBand = 0.03;
// Its barrier's mu, as a fraction of the gap between the mean quality and that top: an element
// weighs twice once it comes within mu of the top, so the elements the sum would push down stop
// well before they crowd there.
constexpr double kPolishMu = 0.01;

// Whole-mesh figures of the movable elements' qualities, the same on every process.
struct Stats {
    double worst, mean;
    long bad;  // non-positive qualities
    long nan;  // qualities that are not numbers
};

// The elements a focused phase holds still (global figures, fixed while the focus lasts).
struct Frozen {
    double worst = std::numeric_limits<double>::infinity();
    double sum = 0.0, count = 0.0;
    long bad = 0;
};

// Figures of the qualities `counted` (of counted elements) that are not +infinity.
Frozen frozen_stats(const Reducer& reducer, std::span<const double> counted) {
    constexpr double kOut = std::numeric_limits<double>::infinity();
    Frozen f;
    std::int64_t count = 0, bad = 0;  // counted as integers, then summed exactly like the qualities
    double largest = 0.0;
    for (double q : counted) {
        if (q == kOut) continue;
        f.worst = std::min(f.worst, q);
        largest = std::max(largest, std::abs(q));
        ++count;
        bad += q <= 0.0;
    }
    largest = reducer.max(largest);
    // The qualities' sum as quality_stats takes it (only the mean reports it).
    std::array<ExactSum, 3> sums{detail::bounded_block_sums<1>(
        counted.size(), {largest}, [&](std::size_t first, std::size_t length, const auto& terms) {
            for (std::size_t i = 0; i < length; ++i) {
                const double q = counted[first + i];
                terms[0][i] = q != kOut ? q : 0.0;  // a zero term adds nothing
            }
        })[0]};
    sums[1].add(static_cast<double>(count));
    sums[2].add(static_cast<double>(bad));
    reducer.sum(sums);
    f.worst = reducer.min(f.worst);
    f.sum = sums[0].value();
    f.count = sums[1].value();
    f.bad = static_cast<long>(sums[2].value());
    return f;
}

// With `frozen`, the figures of the whole: the qualities given and the frozen elements.
Stats quality_stats(const detail::Workspace& work, std::span<const double> all, std::vector<double>& buffer,
                    const Frozen& frozen = {}) {
    const Reducer& reducer = work.reducer();
    const auto q = work.counted(all, buffer);
    const detail::Extremes range = detail::extremes(q);  // NaN passed over
    Stats s{range.least, 0.0, 0, 0};
    double largest = range.least <= range.greatest ? std::max(std::abs(range.least), std::abs(range.greatest)) : 0.0;
    for (double v : q) {
        s.nan += std::isnan(v);
        s.bad += v <= 0.0;
    }
    largest = reducer.max(largest);
    // The qualities' sum, then the two counts: one reduction for all three.
    std::array<ExactSum, 3> sums{
        detail::bounded_block_sums<1>(q.size(), {largest}, [&](std::size_t first, std::size_t count, const auto& terms) {
            for (std::size_t i = 0; i < count; ++i) terms[0][i] = std::isnan(q[first + i]) ? 0.0 : q[first + i];
        })[0]};
    sums[1].add(static_cast<double>(s.bad));
    sums[2].add(static_cast<double>(s.nan));
    reducer.sum(sums);
    s.worst = std::min(reducer.min(s.worst), frozen.worst);
    s.bad = static_cast<long>(sums[1].value()) + frozen.bad;
    s.nan = static_cast<long>(sums[2].value());
    sums[0].add(frozen.sum);
    s.mean = sums[0].value() / std::max(1.0, work.global_movable() + frozen.count);
    return s;
}

// The worst of the qualities `all` that this process counts (NaN skipped), over all processes:
// quality_stats' worst alone.
double worst_counted(const detail::Workspace& work, std::span<const double> all, std::vector<double>& buffer) {
    return work.reducer().min(detail::extremes(work.counted(all, buffer)).least);
}

// Everything that changes the result, for the checkpoint's fingerprint.
std::string options_text(const GlobalSolverOptions& o) {
    detail::OptionsText t;
    const char* direction = o.direction == GlobalSolverOptions::Direction::SteepestAscent ? "steepest_ascent"
                            : o.direction == GlobalSolverOptions::Direction::Newton       ? "newton"
                                                                                          : "conjugate_gradient";
    t("direction", direction)
        ("objective", o.objective)("barrier_shrink", o.objective_options.barrier_shrink)
        ("initial_mu", o.objective_options.initial_mu)("barrier_initial_active", o.objective_options.barrier_initial_active)
        ("p", o.objective_options.p)("shape_metric", o.shape_metric)("hybrid_sharpness", o.metric_options.hybrid_sharpness)
        ("untangle", o.untangle)("improve_shape", o.improve_shape)("termination", o.termination)
        ("untangle_termination", o.untangle_termination)("precondition_untangling", o.precondition_untangling)
        ("untangling", o.untangling == GlobalSolverOptions::Untangling::Energy ? "energy" : "barrier")
        ("local_untangle_rounds", o.local_untangle_rounds)("steps_per_mu", o.steps_per_mu)
        ("gain_tolerance", o.gain_tolerance)("damped_vertex_ascent", o.damped_vertex_ascent)
        ("max_failed_searches", o.max_failed_searches)("renumber", o.renumber);
    if (o.focus_band < 1.0) t("focus_band", o.focus_band);
    if (o.polish != GlobalSolverOptions::Polish::Auto)
        t("polish", o.polish == GlobalSolverOptions::Polish::Off ? "off" : "always");
    const bool finish = o.finish == GlobalSolverOptions::Finish::Newton;
    if (finish) t("finish", "newton")("finish_band", o.finish_band);
    if (o.direction == GlobalSolverOptions::Direction::Newton || finish)
        t("newton_tolerance", o.newton_tolerance)("newton_cg_iterations", o.newton_cg_iterations);
    return t.text();
}

// The workspace's vertices that slide on the input's boundary (boundary: slide), and how their
// moves stay on it: gradients and directions keep their tangential part, trial positions are
// projected back onto each vertex's patch or curve. The SlidingBoundary speaks the caller's ids.
class SlidingVertices {
public:
    SlidingVertices(const detail::Workspace& work, const detail::SlidingBoundary& boundary) : boundary_(boundary) {
        const VertexId n = work.mesh().num_vertices();
        caller_.assign(static_cast<std::size_t>(n), -1);
        for (VertexId v = 0; v < n; ++v)
            if (work.mesh().slides(v)) {
                caller_[v] = work.caller_vertex(v);
                vertices_.push_back(v);
            }
    }

    // Replaces each sliding vertex's part of `field` (3 doubles per vertex) by its tangential part.
    void tangent(std::span<double> field) const {
#pragma omp parallel for schedule(static) if (vertices_.size() > detail::kParallelThreshold)
        for (std::size_t i = 0; i < vertices_.size(); ++i) {
            double* d = &field[3 * static_cast<std::size_t>(vertices_[i])];
            const Vec3 t = boundary_.tangent(caller_[vertices_[i]], {d[0], d[1], d[2]});
            for (int c = 0; c < 3; ++c) d[c] = t[c];
        }
    }
    // Every sliding vertex that `mesh` lets move, back onto its patch or curve.
    void project(const Mesh& mesh, std::span<double> xyz) const {
#pragma omp parallel for schedule(static) if (vertices_.size() > detail::kParallelThreshold / 16)
        for (std::size_t i = 0; i < vertices_.size(); ++i)
            if (mesh.can_move(vertices_[i])) project(vertices_[i], xyz);
    }
    // Vertex v back onto its patch or curve, if it slides.
    void project(VertexId v, std::span<double> xyz) const {
        const VertexId id = caller_[v];
        if (id < 0) return;
        double* p = &xyz[3 * static_cast<std::size_t>(v)];
        const Vec3 q = boundary_.project(id, {p[0], p[1], p[2]});
        for (int c = 0; c < 3; ++c) p[c] = q[c];
    }

private:
    const detail::SlidingBoundary& boundary_;
    std::vector<VertexId> caller_;    // per workspace vertex: its id in the caller's mesh if it slides, else -1
    std::vector<VertexId> vertices_;  // the workspace's sliding vertices
};

// One phase (untangle or shape) of the barrier ascent over the workspace's movable elements.
// Steps are accepted when they raise the objective (Armijo), stay in its domain and do not add
// non-positive elements; the worst quality of an iterate may dip while the barrier rebalances,
// so the phase keeps the best iterate (highest worst quality) and ends on it.
class Phase {
public:
    Phase(detail::Workspace& work, std::vector<double>& xyz, const QualityMetric& metric, ObjectiveFunction& objective,
          const TerminationCriterion& stop, const GlobalSolverOptions& options, Stage stage, Summary& summary,
          const IterationObserver& observer, Clock::time_point start, detail::Checkpointer& checkpointer,
          const SlidingVertices* sliding = nullptr)
        : work_(work), x_(xyz), metric_(metric), objective_(objective), stop_(stop), options_(options),
          untangling_(stage.untangling), stage_(stage), summary_(summary), observer_(observer), start_(start),
          checkpointer_(checkpointer), sliding_(sliding) {}

    // From the phase's start, or from a checkpoint's state at an iteration boundary.
    PhaseResult run(const detail::SolverState* resume = nullptr);

private:
    Stats stats(std::span<const double> q) { return quality_stats(work_, q, counted_, frozen_); }
    double objective_value(std::span<const double> q) { return objective_.value(work_.counted(q, counted_), reducer_); }
    void damp_like_owners(std::vector<VertexId>& damped);
    bool line_search(double objective, double max_direction);
    // A trial element blocks the step when it leaves the objective's domain (above floor) or
    // becomes non-positive although it was positive.
    bool blocks(ElementId e, double floor) const {
        return !(trial_q_[e] > floor) || (trial_q_[e] <= 0.0 && q_[e] > 0.0);
    }
    // Damps each vertex's share of the trial step (s times the direction) fourfold and rates
    // its elements again (into reevaluated_).
    void damp(const std::vector<VertexId>& vertices, double s);
    // The trial's damped vertices are damped again while their own elements' barrier terms are
    // lower than at the iterate. False when that makes an element block (the trial fails).
    bool damp_where_barrier_falls(std::vector<VertexId>& once_damped, double s, double t);
    void note_barrier_changes(std::span<const ElementId> elements, double t);
    void apply_preconditioner();
    bool untangled() const { return detail::untangled(work_, x_); }
    void record(const Stats& s, double objective, double step, double gain);
    PhaseResult end(TerminationReason reason, std::string message);
    // Every number the next iteration needs is finite (a NaN ends the phase on its best iterate).
    bool sound(const Stats& s, double objective) const;
    void save_checkpoint(int iteration);
    int restore(const detail::SolverState& state, double& objective);
    void size_element_arrays();
    // Focus on the elements below the band above the whole mesh's worst quality (focus_band).
    void refocus();
    // The finish's fresh barrier weighs its focus alone: there t and mu come from the few worst
    // elements. On fandisk-9M the still elements' terms (9.4 million) held t far below the worst
    // elements, which the steps then traded for the rest, or after one shrink of mu within 2e-7 of
    // the worst, where the steps crept (docs/global_solver.md, "The fresh barrier weighs its focus
    // alone").
    bool focus_alone() const { return focusing_ && stage_.fresh; }
    // The mean's polish: holds still the vertices of the elements below kPolishBand and sets
    // the objective's floor at its top (q_ rates the whole mesh at x_).
    void hold_near_worst();
    // A distributed run: ghosts take their owners' flags in moving_ (each owner holds every
    // element of its vertices, so its decision is complete).
    void moving_like_owners();
    // The progress the stall windows watch: the barrier's t, or in the polish the mean quality.
    double measure(const Stats& s) const { return stage_.polish ? s.mean : objective_.progress_measure(); }
    // Focus on the elements around the vertices flagged in moving_ (frozen_: the others).
    // whole_rated: whole_q_ holds the whole mesh's qualities at x_ already (refocus).
    void focus_on_moving(bool whole_rated = false);
    // best_x_ = x_. Within one focus only its free vertices move, so only they can differ: a
    // small focus of a large mesh does not copy the mesh at every better iterate.
    void keep_best();

    detail::Workspace& work_;
    std::vector<double>& x_;
    const QualityMetric& metric_;
    ObjectiveFunction& objective_;
    const TerminationCriterion& stop_;
    const GlobalSolverOptions& options_;
    bool untangling_;
    Stage stage_;
    Summary& summary_;
    const IterationObserver& observer_;
    Clock::time_point start_;
    detail::Checkpointer& checkpointer_;
    const SlidingVertices* sliding_;  // the boundary vertices that slide, if any
    const Reducer& reducer_ = work_.reducer();

    std::vector<double> q_, trial_q_, weight_, trial_x_, gradient_, direction_, previous_gradient_, best_x_;
    std::vector<double> curvature_weight_, curvature_, preconditioned_, previous_preconditioned_;
    std::vector<double> damping_;                  // per vertex: fraction of the step it takes
    std::vector<int> stamp_;                       // per vertex: damped in this round
    std::vector<double> mark_;                     // per vertex: damped by its owner (distributed runs)
    std::vector<std::uint8_t> once_damped_mark_;   // per vertex: damped by the trial (damp_where_barrier_falls)
    std::vector<double> counted_;                  // scratch: the qualities this process counts
    std::vector<std::uint32_t> element_stamp_;     // per element: re-evaluated in this round
    std::uint32_t element_stamp_round_ = 0;
    std::vector<ElementId> reevaluated_;           // line search: the elements of the last damped vertices
    std::vector<VertexId> falling_;                // damp_where_barrier_falls: the vertices to damp again
    // damp_where_barrier_falls: per element, log(trial q - t) - log(q - t), valid where
    // change_stamp_ holds change_round_ (its trial quality unchanged since).
    std::vector<double> barrier_change_;
    std::vector<std::uint32_t> change_stamp_;
    std::uint32_t change_round_ = 0;
    std::vector<ElementId> around_;               // damp_where_barrier_falls: the elements of its vertices
    std::vector<ElementId> changing_, new_gaps_;  // note_barrier_changes: scratch
    std::vector<double> logs_;
    // Per element: log(q - t) at the iterate, valid where gap_stamp_ holds gap_round_ (one line
    // search: the iterate, t and the focus stand still while its trials come and go).
    std::vector<double> log_gap_;
    std::vector<std::uint32_t> gap_stamp_;
    std::uint32_t gap_round_ = 0;
    double best_worst_ = -std::numeric_limits<double>::infinity();
    long best_bad_ = 0;
    double best_mean_ = -std::numeric_limits<double>::infinity();  // the polish's best iterate
    std::optional<std::uint64_t> best_focus_;  // the focus generation best_x_ was last kept in
    double step_ = 0.05;  // largest vertex displacement of the next trial step, in reference lengths
    double gain_ = 0.0;   // objective increase of the last accepted step (at its mu and t)
    // What the iterations carry over (saved in checkpoints).
    double first_gradient_norm_ = -1.0;
    bool restart_ = true;  // next direction is steepest ascent
    int failures_ = 0;     // line searches in a row that found no step
    int steps_at_mu_ = 0;
    int let_go_steps_ = 0;  // steps in a row at this mu with the worst element's weight under kLeastWorstWeight
    int quick_solves_ = 0;  // Newton subproblems in a row solved by their first step
    // Where the phase began: the barrier's t and the worst quality's gap above it (0: no barrier).
    double first_t_ = 0.0, first_gap_ = 0.0;
    // Per iteration: the best worst quality, the objective's progress measure, the inverted
    // count, and how many times mu has shrunk.
    std::vector<double> best_history_, measure_history_, bad_history_, stage_history_;
    std::vector<double> gain_history_;  // the accepted steps' gains in units of mu, summed
    std::vector<double> passes_history_;  // gradient passes so far (a Newton step takes one per product)
    // The histories start over from their last entries (a wider focus).
    void restart_histories();
    // The objective's subproblem: its scale (the barrier's mu), its floor (t), the worst's share.
    double barrier_mu() const { return objective_.subproblem_scale(); }
    double barrier_t() const { return objective_.subproblem_floor(); }
    double barrier_worst_weight() const { return objective_.worst_share(); }
    // Newton directions (shape phase): the damping factor, adapted to how the last step went.
    detail::NewtonDirection newton_{work_};
    double newton_damping_ = 1e-2;
    // Focus (shape phase with focus_band < 1): which vertices move, the band it was made from
    // (the whole mesh's worst quality then and the top of the band) and the elements outside it.
    bool focusing_ = false;
    std::vector<std::uint8_t> moving_;
    double focus_base_ = 0.0, focus_top_ = 0.0;
    double band_ = 1.0;        // the focus band now: focus_band, widened where the focus stalled
    double widened_at_ = 0.0;  // the best worst quality when it was last widened
    double shrunk_at_ = 0.0;   // the best worst quality when a long stage was last cut short
    long focus_vertices_ = 0;  // free vertices of the focus, over all processes
    Frozen frozen_;
    std::vector<double> whole_q_;
    // The whole mesh's qualities when this phase made the focus of generation focus_start_.
    std::vector<double> focus_start_q_;
    std::optional<std::uint64_t> focus_start_;
};

void Phase::size_element_arrays() {
    const std::size_t m = static_cast<std::size_t>(work_.movable_elements());
    q_.resize(m);
    trial_q_.resize(m);
    weight_.resize(m);
    if (!curvature_.empty()) curvature_weight_.assign(m, 0.0);
    element_stamp_.assign(m, 0);
    barrier_change_.resize(m);
    change_stamp_.assign(m, 0);
    log_gap_.resize(m);
    gap_stamp_.assign(m, 0);
}

void Phase::refocus() {
    if (work_.focused() && focus_start_ == work_.focus_generation()) {
        // Since this phase made the focus only its free vertices moved: the elements outside it
        // keep the qualities they had then, and the focus's own are q_ (the bits a whole pass gives).
        whole_q_.swap(focus_start_q_);  // focus_on_moving sets focus_start_q_ again
        const auto elements = work_.focus_elements();
        for (std::size_t i = 0; i < elements.size(); ++i) whole_q_[static_cast<std::size_t>(elements[i])] = q_[i];
        work_.unfocus();
    } else if (work_.focused()) {
        work_.unfocus();
        whole_q_.resize(static_cast<std::size_t>(work_.movable_elements()));
        work_.evaluate(metric_, x_, whole_q_);
        ++summary_.quality_passes;
    } else {
        whole_q_ = q_;  // not yet focused (the phase's start): q_ rates the whole mesh at x_
    }
    frozen_ = {};
    const Mesh& mesh = work_.mesh();
    focus_base_ = worst_counted(work_, whole_q_, counted_);
    focus_top_ = focus_base_ + band_ * (metric_.ideal_value() - focus_base_);
    // A vertex moves when one of its elements lies in the band.
    moving_.assign(static_cast<std::size_t>(mesh.num_vertices()), 0);
    for (ElementId e = 0; e < work_.movable_elements(); ++e)
        if (whole_q_[e] < focus_top_)
            for (VertexId v : mesh.element(e)) moving_[v] = 1;
    moving_like_owners();
    // And their neighbours: a band vertex hemmed in by elements whose other corners stand still
    // stalls the focus (fandisk-100k: 0.2146 against 0.2248 for the whole mesh).
    // (Through the band vertices' own elements: a focus is a small part of a large mesh.)
    std::vector<VertexId> band;
    for (VertexId v = 0; v < mesh.num_vertices(); ++v)
        if (moving_[v]) band.push_back(v);
    for (VertexId v : band)
        for (ElementId e : mesh.elements_of(v))
            if (e < work_.movable_elements())
                for (VertexId w : mesh.element(e)) moving_[w] = 1;
    moving_like_owners();
    focus_on_moving(true);
}

void Phase::moving_like_owners() {
    if (!work_.distributed()) return;
    for (std::size_t v = 0; v < moving_.size(); ++v) mark_[v] = moving_[v];
    work_.halo().update(mark_, 1);
    for (std::size_t v = 0; v < moving_.size(); ++v) moving_[v] = mark_[v] != 0.0;
    std::fill(mark_.begin(), mark_.end(), 0.0);
}

void Phase::hold_near_worst() {
    const Stats s = stats(q_);
    focus_base_ = s.worst;
    focus_top_ = s.worst + kPolishBand * (metric_.ideal_value() - s.worst);
    objective_.set_floor(focus_top_, kPolishMu * std::max(s.mean - focus_top_, 1e-3 * std::abs(focus_top_) + 1e-12));
    // An element at the top itself is held too: the line search keeps the moving ones above it.
    const Mesh& mesh = work_.mesh();
    moving_.assign(static_cast<std::size_t>(mesh.num_vertices()), 1);
    for (ElementId e = 0; e < work_.movable_elements(); ++e)
        if (!(q_[e] > focus_top_))
            for (VertexId v : mesh.element(e)) moving_[v] = 0;
    moving_like_owners();
    whole_q_ = q_;
    focus_on_moving(true);
}

void Phase::restart_histories() {
    for (auto* history :
         {&best_history_, &measure_history_, &bad_history_, &stage_history_, &passes_history_, &gain_history_})
        *history = {history->back()};
}

void Phase::focus_on_moving(bool whole_rated) {
    work_.unfocus();
    const Mesh& whole = work_.mesh();
    // The elements that stay out, at the positions they keep while the focus lasts.
    if (!whole_rated) {
        whole_q_.resize(static_cast<std::size_t>(work_.movable_elements()));
        work_.evaluate(metric_, x_, whole_q_);
    }
    focus_start_q_ = whole_q_;  // what the next refocus starts from
    for (VertexId v = 0; v < whole.num_vertices(); ++v)
        if (moving_[v] && whole.can_move(v))
            for (ElementId e : whole.elements_of(v))
                if (e < work_.movable_elements()) whole_q_[e] = std::numeric_limits<double>::infinity();
    const auto still = work_.counted(whole_q_, counted_);
    frozen_ = frozen_stats(reducer_, still);
    // The barrier's t goes on weighing them: t where the whole mesh puts it, as if it all moved.
    // From the focus's terms alone t rose to within about one mu of the worst quality, where a
    // single element drives each step (fandisk-9M: 0.145 after 500 iterations, docs/global_solver.md).
    // Not the finish's fresh barrier: it weighs its focus alone.
    objective_.hold_still(focus_alone() ? std::span<const double>{} : still, reducer_);
    work_.focus(moving_);
    focus_start_ = work_.focus_generation();
    const Mesh& focus = work_.mesh();
    const auto owned = work_.owned();
    double count = 0.0;
    for (VertexId v = 0; v < focus.num_vertices(); ++v) count += owned[v] && focus.can_move(v);
    focus_vertices_ = static_cast<long>(reducer_.total(count));
    size_element_arrays();
    work_.evaluate(metric_, x_, q_);
    trial_x_ = x_;  // vertices that moved in the last focus may stand still in this one
    restart_ = true;
}

// A distributed run: the owner of a vertex holds all its elements, so its decision to damp the
// vertex is complete; ghosts take their owners' decisions.
void Phase::damp_like_owners(std::vector<VertexId>& damped) {
    if (!work_.distributed()) return;
    const auto owned = work_.owned();
    for (VertexId v : damped) mark_[v] = 1.0;
    work_.halo().update(mark_, 1);
    std::erase_if(damped, [&](VertexId v) { return !owned[v]; });
    for (VertexId v : work_.ghosts())
        if (mark_[v] != 0.0 && work_.mesh().can_move(v)) damped.push_back(v);
    std::fill(mark_.begin(), mark_.end(), 0.0);
}

void Phase::record(const Stats& s, double objective, double step, double gain) {
    IterationRecord r;
    r.iteration = summary_.iterations;
    r.phase = untangling_     ? "untangle"
              : stage_.polish ? "polish"
              : stage_.fresh  ? "finish_fresh"
              : stage_.finish ? "finish"
                              : "shape";
    r.worst_quality = s.worst;
    r.best_worst_quality = best_worst_;
    r.mean_quality = s.mean;
    r.inverted = s.bad / work_.copies();  // an inverted element's copies are all inverted
    r.mu = objective_.subproblem_scale();
    r.t = objective_.subproblem_floor();
    r.objective = objective;
    r.step = step;
    r.gain = gain;
    r.moved = focusing_ ? focus_vertices_ : 0;
    r.seconds = seconds_since(start_);
    summary_.history.push_back(std::move(r));
    if (observer_) observer_(summary_.history.back());
}

bool Phase::line_search(double objective, double max_direction) {
    const Mesh& mesh = work_.mesh();
    const ElementId movable = work_.movable_elements();
    const double length = work_.reference_length();
    // Rather than shrinking the whole step for an element that blocks it, the step of its
    // vertices is damped until it no longer blocks: one tangle does not freeze the mesh.
    const double floor = objective_.domain_floor();
    // In the shape phase, the barrier's own terms also judge the damped vertices (below).
    const bool barrier =
        options_.damped_vertex_ascent && !untangling_ && !stage_.finish && objective_.is_continuation();
    std::vector<VertexId> damped, once_damped;
    ++gap_round_;
    for (int attempt = 0; attempt < 40; ++attempt, step_ *= 0.5) {
        const double s = step_ * length / max_direction;
        // Only free vertices move: elsewhere trial_x_ holds x_ already (Phase::run, focus_on_moving).
        const auto free = work_.free_vertices();
        const auto count = static_cast<std::ptrdiff_t>(free.size());
#pragma omp parallel for schedule(static) if (static_cast<std::size_t>(movable) > detail::kParallelThreshold)
        for (std::ptrdiff_t i = 0; i < count; ++i) {
            const VertexId v = free[static_cast<std::size_t>(i)];
            damping_[v] = 1.0;
            for (int c = 0; c < 3; ++c) trial_x_[3 * v + c] = x_[3 * v + c] + s * direction_[3 * v + c];
        }
        // Sliding vertices are rated where they would go: on the boundary.
        if (sliding_) sliding_->project(mesh, trial_x_);
        work_.evaluate(metric_, trial_x_, trial_q_);
        ++summary_.quality_passes;
        once_damped.clear();
        bool blocked = true;
        for (int round = 0; round < 64 && blocked; ++round) {
            damped.clear();
            auto damp_if_blocking = [&](ElementId e) {
                if (blocks(e, floor))
                    for (VertexId v : mesh.element(e))
                        if (mesh.can_move(v) && stamp_[v] != round + 1) {
                            stamp_[v] = round + 1;
                            damped.push_back(v);
                        }
            };
            // After the first round only the elements just re-evaluated can block.
            if (round == 0)
                for (ElementId e = 0; e < movable; ++e) damp_if_blocking(e);
            else
                for (ElementId e : reevaluated_) damp_if_blocking(e);
            damp_like_owners(damped);
            blocked = reducer_.max(damped.empty() ? 0.0 : 1.0) > 0.0;
            if (!blocked) break;
            for (VertexId v : damped)
                if (damping_[v] == 1.0) once_damped.push_back(v);
            damp(damped, s);
        }
        for (VertexId v : free) stamp_[v] = 0;
        if (blocked) continue;
        if (barrier && !damp_where_barrier_falls(once_damped, s, objective_.subproblem_floor())) continue;
        // The Armijo test uses the slope of the damped step actually taken.
        const double slope = detail::free_owned_sums<1>(work_, [&](std::size_t v, auto& acc) {
            double d = 0.0;
            for (int c = 0; c < 3; ++c) d += gradient_[3 * v + c] * damping_[v] * direction_[3 * v + c];
            acc[0].add(d);
        })[0];
        if (!(slope > 0.0)) continue;
        const double trial_objective = objective_value(trial_q_);
        if (trial_objective > objective + 1e-4 * s * slope) {
            gain_ = trial_objective - objective;
            x_.swap(trial_x_);
            q_.swap(trial_q_);
            return true;
        }
    }
    return false;
}

void Phase::damp(const std::vector<VertexId>& vertices, double s) {
    const Mesh& mesh = work_.mesh();
    const ElementId movable = work_.movable_elements();
    ++element_stamp_round_;
    for (VertexId v : vertices) {
        damping_[v] *= 0.25;
        for (int c = 0; c < 3; ++c) trial_x_[3 * v + c] = x_[3 * v + c] + damping_[v] * s * direction_[3 * v + c];
        if (sliding_) sliding_->project(v, trial_x_);
    }
    reevaluated_.clear();
    for (VertexId v : vertices)
        for (ElementId e : mesh.elements_of(v)) {
            if (e >= movable || element_stamp_[e] == element_stamp_round_) continue;
            element_stamp_[e] = element_stamp_round_;
            reevaluated_.push_back(e);
        }
    metric_.evaluate_listed(mesh, trial_x_, reevaluated_, trial_q_.data());
}

// A vertex damped for one blocking element usually sits by the worst elements. Whole-mesh steps
// grow to thousands of reference lengths while they pay (the bulk of the barrier), and such a
// vertex, damped only until nothing blocks, may still take a step that lowers its own elements:
// the gain elsewhere carries the Armijo test, and the worst element gives up what the last steps
// won. Each such vertex is therefore damped again while the sum of log(q - t) over its elements is
// lower at the trial than at the iterate (at most 8 rounds). Only the owner of a vertex decides,
// as it holds all its elements; exact sums make the decision the same for any partition.
bool Phase::damp_where_barrier_falls(std::vector<VertexId>& once_damped, double s, double t) {
    const Mesh& mesh = work_.mesh();
    const ElementId movable = work_.movable_elements();
    const auto owned = work_.owned();
    ++change_round_;  // the changes of the last call are stale: another trial, maybe another t
    // Reads the changes noted (note_barrier_changes) for all the elements of the vertices it tests.
    auto barrier_falls = [&](VertexId v) {
        double sum = 0.0, magnitude = 0.0;
        int terms = 0;
        for (ElementId e : mesh.elements_of(v))
            if (e < movable) {
                sum += barrier_change_[e];
                magnitude += std::abs(barrier_change_[e]);
                ++terms;
            }
        // Rounding moves a plain sum of n terms by less than n 2^-52 times the sum of their
        // magnitudes; beyond that its sign is the exact sum's, whatever the order. Only sums
        // nearer zero (or not finite) are summed exactly.
        if (std::isfinite(magnitude) && std::abs(sum) > std::ldexp(static_cast<double>(terms), -52) * magnitude)
            return sum < 0.0;
        ExactSum change;
        for (ElementId e : mesh.elements_of(v))
            if (e < movable) change.add(barrier_change_[e]);
        return change.value() < 0.0;
    };
    std::erase_if(once_damped, [&](VertexId v) { return !owned[v]; });
    for (VertexId v : once_damped) once_damped_mark_[v] = 1;
    around_.clear();
    for (VertexId v : once_damped)
        for (ElementId e : mesh.elements_of(v))
            if (e < movable) around_.push_back(e);
    note_barrier_changes(around_, t);
    std::vector<VertexId>& falling = falling_;  // a member: no allocation per trial
    bool blocked = false;
    for (int round = 0; round < 8 && !blocked; ++round) {
        // After the first round only the vertices of the elements just re-rated can have changed.
        falling.clear();
        if (round == 0) {
            for (VertexId v : once_damped)
                if (barrier_falls(v)) falling.push_back(v);
        } else {
            for (ElementId e : reevaluated_)
                for (VertexId v : mesh.element(e))
                    if (once_damped_mark_[v] == 1) {
                        once_damped_mark_[v] = 2;  // tested in this round
                        if (barrier_falls(v)) falling.push_back(v);
                    }
            for (VertexId v : once_damped) once_damped_mark_[v] = 1;
        }
        damp_like_owners(falling);
        if (reducer_.max(falling.empty() ? 0.0 : 1.0) == 0.0) break;
        damp(falling, s);
        for (ElementId e : reevaluated_) {
            change_stamp_[e] = 0;
            blocked = blocked || blocks(e, t);
        }
        note_barrier_changes(reevaluated_, t);
        blocked = reducer_.max(blocked ? 1.0 : 0.0) > 0.0;
    }
    for (VertexId v : once_damped) once_damped_mark_[v] = 0;
    return !blocked;
}

// barrier_change_ (and log_gap_, once per line search) for those of `elements` not noted since
// the trial last moved them, their logarithms taken together: vectorized, with the same bits as
// one at a time (fast_log.hpp).
void Phase::note_barrier_changes(std::span<const ElementId> elements, double t) {
    changing_.clear();
    new_gaps_.clear();
    for (ElementId e : elements) {
        if (change_stamp_[e] == change_round_) continue;
        change_stamp_[e] = change_round_;
        changing_.push_back(e);
        if (gap_stamp_[e] != gap_round_) {
            gap_stamp_[e] = gap_round_;
            new_gaps_.push_back(e);
        }
    }
    logs_.resize(std::max(changing_.size(), new_gaps_.size()));
    for (std::size_t i = 0; i < new_gaps_.size(); ++i) logs_[i] = q_[new_gaps_[i]] - t;
    detail::log_all(logs_.data(), logs_.data(), new_gaps_.size());
    for (std::size_t i = 0; i < new_gaps_.size(); ++i) log_gap_[new_gaps_[i]] = logs_[i];
    for (std::size_t i = 0; i < changing_.size(); ++i) logs_[i] = trial_q_[changing_[i]] - t;
    detail::log_all(logs_.data(), logs_.data(), changing_.size());
    for (std::size_t i = 0; i < changing_.size(); ++i)
        barrier_change_[changing_[i]] = logs_[i] - log_gap_[changing_[i]];
}

// preconditioned = M^-1 gradient, M per vertex the 3x3 Gauss-Newton block of the objective
// (curvature), regularized: a Newton step for each vertex as if its neighbours stood still. It
// evens out the very different scales of elements and barrier weights.
void Phase::apply_preconditioner() {
    const std::size_t n = x_.size() / 3;
    const auto [trace_sum, counted] = detail::owned_sums<2>(work_, [&](std::size_t v, auto& acc) {
        const double* m = &curvature_[6 * v];
        const double trace = m[0] + m[3] + m[5];
        if (trace > 0.0) acc[0].add(trace), acc[1].add(1.0);
    });
    if (counted == 0.0) {
        preconditioned_ = gradient_;
        return;
    }
    const double floor = 1e-8 * trace_sum / counted;
#pragma omp parallel for schedule(static) if (n > detail::kParallelThreshold)
    for (std::size_t v = 0; v < n; ++v) {
        const double* m = &curvature_[6 * v];
        const double lambda = 1e-3 * (m[0] + m[3] + m[5]) / 3.0 + floor;
        detail::solve_block(m, lambda, &gradient_[3 * v], &preconditioned_[3 * v]);
    }
}

void Phase::keep_best() {
    if (best_focus_ != work_.focus_generation()) {
        best_x_ = x_;
        best_focus_ = work_.focus_generation();
        return;
    }
    detail::for_each_free_coordinate(work_, [&](std::size_t i) { best_x_[i] = x_[i]; });
}

PhaseResult Phase::end(TerminationReason reason, std::string message) {
    work_.unfocus();
    x_.swap(best_x_);  // the best iterate, which may be the current one
    return {reason, std::move(message), false, best_mean_};
}

bool Phase::sound(const Stats& s, double objective) const {
    // -inf is a value the log-barrier gives on purpose (for a log sum it cannot take, so that the
    // line search rejects such a trial); NaN, +inf or a NaN t mean the arithmetic broke down.
    return s.nan == 0 && !std::isnan(objective) && objective != std::numeric_limits<double>::infinity() &&
           !std::isnan(objective_.progress_measure());
}

void Phase::save_checkpoint(int iteration) {
    detail::SolverState state;
    state.numbers = {{"untangling", untangling_ ? 1.0 : 0.0},
                     {"finish", stage_.finish ? 1.0 : 0.0},
                     {"fresh", stage_.fresh ? 1.0 : 0.0},
                     {"polish", stage_.polish ? 1.0 : 0.0},
                     {"shape_reason", static_cast<double>(stage_.shape_reason)},
                     {"mean_goal", stage_.mean_goal},
                     {"best_mean", best_mean_},
                     {"round", stage_.round},
                     {"budget", stop_.max_iterations},
                     {"iteration", iteration},
                     {"best_worst", best_worst_},
                     {"best_bad", static_cast<double>(best_bad_)},
                     {"step", step_},
                     {"first_gradient_norm", first_gradient_norm_},
                     {"restart", restart_ ? 1.0 : 0.0},
                     {"failures", failures_},
                     {"steps_at_mu", steps_at_mu_},
                     {"let_go_steps", let_go_steps_},
                     {"quick_solves", quick_solves_},
                     {"first_t", first_t_},
                     {"first_gap", first_gap_},
                     {"newton_damping", newton_damping_},
                     {"focus_base", focus_base_},
                     {"focus_top", focus_top_},
                     {"focus_band", band_},
                     {"widened_at", widened_at_},
                     {"shrunk_at", shrunk_at_}};
    state.lists = {{"objective", objective_.state()},
                   {"best_history", best_history_},
                   {"measure_history", measure_history_},
                   {"bad_history", bad_history_},
                   {"stage_history", stage_history_},
                   {"passes_history", passes_history_},
                   {"gain_history", gain_history_}};
    state.vertex_fields = {{"x", x_},
                           {"best_x", best_x_},
                           {"direction", direction_},
                           {"previous_gradient", previous_gradient_},
                           {"previous_preconditioned", previous_preconditioned_}};
    if (focusing_) {
        std::vector<double> moving(3 * moving_.size(), 0.0);
        for (std::size_t v = 0; v < moving_.size(); ++v) moving[3 * v] = moving_[v];
        state.vertex_fields["moving"] = std::move(moving);
    }
    checkpointer_.save(summary_, state, seconds_since(start_));
}

// The state saved at the top of an iteration; returns that iteration. The qualities, the
// objective and its weights are recomputed from the coordinates (each element's quality is a
// function of its corners alone, so they come out bit for bit as they were).
int Phase::restore(const detail::SolverState& state, double& objective) {
    const std::size_t n = x_.size() / 3;
    x_ = state.vertex_field("x", n);
    trial_x_ = x_;
    best_x_ = state.vertex_field("best_x", n);
    direction_ = state.vertex_field("direction", n);
    previous_gradient_ = state.vertex_field("previous_gradient", n);
    previous_preconditioned_ = state.vertex_field("previous_preconditioned", n);
    best_worst_ = state.number("best_worst");
    best_bad_ = static_cast<long>(state.number("best_bad"));
    if (state.numbers.contains("best_mean")) best_mean_ = state.number("best_mean");
    step_ = state.number("step");
    first_gradient_norm_ = state.number("first_gradient_norm");
    restart_ = state.number("restart") != 0.0;
    failures_ = static_cast<int>(state.number("failures"));
    steps_at_mu_ = static_cast<int>(state.number("steps_at_mu"));
    let_go_steps_ = state.numbers.contains("let_go_steps") ? static_cast<int>(state.number("let_go_steps")) : 0;
    if (state.numbers.contains("newton_damping")) newton_damping_ = state.number("newton_damping");
    if (state.numbers.contains("quick_solves")) quick_solves_ = static_cast<int>(state.number("quick_solves"));
    if (state.numbers.contains("first_gap")) {
        first_t_ = state.number("first_t");
        first_gap_ = state.number("first_gap");
    }
    if (state.numbers.contains("shrunk_at")) shrunk_at_ = state.number("shrunk_at");
    objective_.restore_state(state.list("objective"));
    best_history_ = state.list("best_history");
    measure_history_ = state.list("measure_history");
    bad_history_ = state.list("bad_history");
    stage_history_ = state.list("stage_history");
    // (Checkpoints from before it have none: the gains are unknown, so no calm handover in this phase.)
    gain_history_ = state.lists.contains("gain_history")
                        ? state.list("gain_history")
                        : std::vector<double>(best_history_.size(), std::numeric_limits<double>::infinity());
    passes_history_ = state.list("passes_history");
    if (focusing_) {
        const auto& moving = state.vertex_field("moving", n);
        moving_.assign(n, 0);
        for (std::size_t v = 0; v < n; ++v) moving_[v] = moving[3 * v] != 0.0;
        focus_base_ = state.number("focus_base");
        focus_top_ = state.number("focus_top");
        band_ = state.number("focus_band");
        widened_at_ = state.number("widened_at");
        focus_on_moving();
        restart_ = state.number("restart") != 0.0;  // focusing restarts a new focus's directions, not this one's
    }
    work_.evaluate(metric_, x_, q_);
    objective = objective_value(q_);
    objective_.weights(q_, weight_);
    return static_cast<int>(state.number("iteration"));
}

PhaseResult Phase::run(const detail::SolverState* resume) {
    const std::size_t n3 = x_.size();
    trial_x_ = x_;  // the line search writes only the free vertices' trials
    gradient_.assign(n3, 0.0);
    direction_.assign(n3, 0.0);
    previous_gradient_.assign(n3, 0.0);
    best_x_ = x_;
    damping_.assign(n3 / 3, 1.0);
    // Only the preconditioner and Newton need the curvature (8 bytes per element, 48 per vertex).
    const bool newton =
        !untangling_ && !stage_.polish && (options_.direction == GlobalSolverOptions::Direction::Newton || stage_.finish);
    // The polish's sum has no curvature of its own: its barrier's gives the elements' scale.
    const bool precondition = (untangling_ && options_.precondition_untangling) || newton || stage_.polish;
    curvature_weight_.clear();
    curvature_.assign(precondition ? 2 * n3 : 0, 0.0);
    preconditioned_.assign(n3, 0.0);
    previous_preconditioned_.assign(n3, 0.0);
    stamp_.assign(n3 / 3, 0);
    mark_.assign(work_.distributed() ? n3 / 3 : 0, 0.0);
    once_damped_mark_.assign(n3 / 3, 0);
    // Newton's directions from the start come out worse on a focus (fandisk-100k: 0.0895 against
    // 0.2302 on the whole mesh after 500 iterations): they keep the whole mesh. The finish, from
    // where conjugate gradients stalled, focuses like them (on finish_band of their band).
    focusing_ = stage_.polish || (!untangling_ && (!newton || stage_.finish) && options_.focus_band < 1.0);
    band_ = stage_.polish ? 1.0 : stage_.finish ? options_.finish_band * options_.focus_band : options_.focus_band;
    widened_at_ = std::numeric_limits<double>::lowest();
    shrunk_at_ = std::numeric_limits<double>::lowest();
    // Focused, the element arrays take the focus's size at the first refocus; until then only q_
    // rates the whole mesh (sizing them all for it zeroed 90 MB on fandisk-2M, then unused).
    if (focusing_) q_.resize(static_cast<std::size_t>(work_.movable_elements()));
    else size_element_arrays();

    // The objective and its weights at the current iterate, for the history and the next step.
    double objective = 0.0;
    int first_iteration = stage_.iterations_before + 1;
    if (resume) {
        first_iteration = restore(*resume, objective);
    } else {
        work_.evaluate(metric_, x_, q_);
        ++summary_.quality_passes;
        // The barrier's first mu comes from the whole mesh, focused or not: the focus's fewer
        // terms would choose a looser barrier, under which conjugate gradients let its elements
        // sink toward t. Focused, it starts no looser than the band. (The finish's fresh barrier
        // weighs its focus alone, Newton steps following its central path: its mu comes from it.)
        if (focusing_) objective_.focus_on_band(band_, metric_.ideal_value());
        if (!focus_alone()) objective_.update(work_.counted(q_, counted_), reducer_);
        if (focusing_) {
            if (stage_.polish) hold_near_worst();
            else refocus();
            objective_.update(work_.counted(q_, counted_), reducer_);
        }
        const Stats s = stats(q_);
        best_worst_ = s.worst;
        best_bad_ = s.bad;
        best_mean_ = s.mean;
        if (barrier_mu() > 0.0) {
            first_t_ = barrier_t();
            first_gap_ = best_worst_ - first_t_;
        }
        best_history_ = {best_worst_};
        measure_history_ = {measure(s)};
        bad_history_ = {static_cast<double>(s.bad)};
        stage_history_ = {0.0};
        gain_history_ = {0.0};
        passes_history_ = {static_cast<double>(summary_.gradient_passes)};
        objective = objective_value(q_);
        objective_.weights(q_, weight_);
        record(s, objective, 0.0, 0.0);
        if (!sound(s, objective))
            return end(TerminationReason::NumericalFailure, "the qualities or the objective are not finite numbers at the "
                                                            "start of the phase");
        if (untangling_ && s.bad == 0 && untangled()) return end(TerminationReason::TargetReached, "untangled");
    }

    for (int iteration = first_iteration;; ++iteration) {
        // Checkpoints and stops at the top of an iteration, where the state is complete. Every
        // process stops at the same iteration: a stop requested on any of them counts.
        if (stop_requested_anywhere(reducer_)) {
            if (checkpointer_.writes()) save_checkpoint(iteration);
            return end(TerminationReason::Interrupted, detail::interrupted_after(summary_.iterations));
        }
        if (checkpointer_.due(summary_.iterations)) save_checkpoint(iteration);
        if (const auto spent = detail::budget_spent(stop_, iteration, reducer_, start_))
            return end(*spent, detail::budget_message(*spent, stop_, "iterations"));

        if (precondition) {
            objective_.curvature_weights(q_, curvature_weight_);
            work_.gradient(metric_, x_, weight_, gradient_, curvature_weight_, curvature_);
        } else {
            work_.gradient(metric_, x_, weight_, gradient_);
        }
        ++summary_.gradient_passes;
        // A sliding vertex ascends along its surface or curve.
        if (sliding_) sliding_->tangent(gradient_);
        const double g2 = detail::free_owned_sums<1>(work_, [&](std::size_t v, auto& acc) {
            acc[0].add(gradient_[3 * v] * gradient_[3 * v] + gradient_[3 * v + 1] * gradient_[3 * v + 1] +
                       gradient_[3 * v + 2] * gradient_[3 * v + 2]);
        })[0];
        if (!std::isfinite(g2))
            return end(TerminationReason::NumericalFailure, "the objective's gradient is not a finite number (iteration " +
                                                                std::to_string(summary_.iterations + 1) +
                                                                "); the best iterate is handed back");
        const double gradient_norm = std::sqrt(g2);
        if (first_gradient_norm_ < 0.0) first_gradient_norm_ = gradient_norm;
        if (!(gradient_norm > stop_.gradient_tolerance * first_gradient_norm_))
            return end(TerminationReason::GradientVanished, "the objective's gradient vanished");
        double decrement = 0.0;
        if (newton) {
            // CG to a tenth of the preconditioned residual (a usual forcing term; not tuned).
            const auto step = newton_.solve(metric_, objective_, x_, q_, curvature_weight_, curvature_, gradient_, newton_damping_,
                                            0.1, options_.newton_cg_iterations, direction_);
            summary_.quality_passes += step.products;
            summary_.gradient_passes += step.products;
            decrement = step.decrement;
            if (!(decrement > 0.0)) direction_ = gradient_;
        } else {
            if (precondition) apply_preconditioner();
            else  // read at the free vertices only
                detail::for_each_free_coordinate(work_, [&](std::size_t i) { preconditioned_[i] = gradient_[i]; });
            if (sliding_ && precondition) sliding_->tangent(preconditioned_);
            // Polak-Ribiere+ conjugate gradient (preconditioned), restarted whenever the objective
            // changes (mu) or the direction stops ascending.
            double beta = 0.0;
            if (options_.direction == GlobalSolverOptions::Direction::ConjugateGradient && !restart_) {
                const auto sums = detail::free_owned_sums<2>(work_, [&](std::size_t v, auto& acc) {
                    double a = 0.0, b = 0.0;
                    for (std::size_t i = 3 * v; i < 3 * v + 3; ++i) {
                        a += preconditioned_[i] * (gradient_[i] - previous_gradient_[i]);
                        b += previous_preconditioned_[i] * previous_gradient_[i];
                    }
                    acc[0].add(a);
                    acc[1].add(b);
                });
                beta = sums[1] > 0.0 ? std::max(0.0, sums[0] / sums[1]) : 0.0;
            }
            // Free vertices only: a new focus restarts (beta 0), and the line search reads no other.
            for (const VertexId v : work_.free_vertices())
                for (std::size_t i = 3 * static_cast<std::size_t>(v); i < 3 * static_cast<std::size_t>(v) + 3; ++i)
                    direction_[i] = preconditioned_[i] + beta * direction_[i];
            // Both terms are tangential already; this keeps their sum so despite rounding.
            if (sliding_) sliding_->tangent(direction_);
            const double slope = detail::free_owned_sums<1>(work_, [&](std::size_t v, auto& acc) {
                acc[0].add(gradient_[3 * v] * direction_[3 * v] + gradient_[3 * v + 1] * direction_[3 * v + 1] +
                           gradient_[3 * v + 2] * direction_[3 * v + 2]);
            })[0];
            if (!(slope > 0.0)) direction_ = preconditioned_;
        }
        // Ghosts move as their owners say: the exchange of the boundary vertices' directions.
        work_.halo().update(direction_, 3);
        // For the next conjugate direction, which reads the free vertices only.
        for (const VertexId v : work_.free_vertices())
            for (std::size_t i = 3 * static_cast<std::size_t>(v); i < 3 * static_cast<std::size_t>(v) + 3; ++i) {
                previous_gradient_[i] = gradient_[i];
                previous_preconditioned_[i] = preconditioned_[i];
            }
        double max_direction = 0.0;
        const auto owned = work_.owned();
        for (const VertexId v : work_.free_vertices())
            if (owned[v])
                max_direction = std::max(max_direction, std::hypot(direction_[3 * v], direction_[3 * v + 1], direction_[3 * v + 2]));
        max_direction = reducer_.max(max_direction);

        // Newton's first trial is its full step.
        if (newton) step_ = std::min(max_direction / work_.reference_length(), 1e6);
        const double first_trial = step_;
        const bool accepted = line_search(objective, max_direction);
        const double step = accepted ? step_ : 0.0;
        ++summary_.iterations;
        if (untangling_) ++summary_.untangle_iterations;
        // mu stays fixed for a few steps, so that conjugate directions make sense, and shrinks
        // once they are taken or when no step was found (weighting the worst elements more).
        failures_ = accepted ? 0 : failures_ + 1;
        restart_ = !accepted;
        // Steps may grow far beyond the mesh's size: an untangled vertex can have been thrown far
        // out (two_tets.vtk) and must be able to come back.
        if (accepted) step_ = std::min(2.0 * step_, 1e6);
        else step_ = 0.05;
        // The shape phase's conjugate gradients on the barrier shrink mu on their gains (below).
        const bool adaptive = !newton && !untangling_ && options_.gain_tolerance > 0.0 && barrier_mu() > 0.0;
        bool solved = false, out_of_reach = false;
        if (newton) {
            // Levenberg-Marquardt: less damping after a full step that gained at least half of
            // what the model promised (decrement / 2), more after a shortened or failed one.
            const bool full = accepted && step == first_trial && gain_ >= 0.25 * decrement;
            newton_damping_ = full ? std::max(newton_damping_ / 3.0, 1e-8) : std::min(newton_damping_ * 4.0, 1e8);
            // The subproblem at this mu is solved when the Newton decrement (in the barrier's own
            // units, F / mu) is small; a cap keeps a subproblem that cannot be solved from
            // holding mu forever.
            const bool converged = decrement <= options_.newton_tolerance * barrier_mu();
            const bool capped = ++steps_at_mu_ >= kNewtonStepsAtOneMu;
            // The finish's first part goes on with the shape phase's barrier. Where Newton steps
            // cannot solve its subproblem, the iterate is far from the barrier's central path at
            // this mu: a fresh barrier recenters it (solve(), below) instead of a smaller mu.
            out_of_reach = capped && !converged && stage_.finish && !stage_.fresh;
            solved = converged || (capped && !out_of_reach);
            if (solved || !accepted) quick_solves_ = accepted && converged && steps_at_mu_ == 1 ? quick_solves_ + 1 : 0;
        } else {
            // The shape phase's barrier subproblem is solved when a step gains little against
            // mu (F is in quality units; F / mu in the barrier's own): a fixed count of steps
            // solves a small mesh's subproblem many times over and a large one's too loosely,
            // and the result then moved with the count (issue 16). No cap on the steps at one mu:
            // a large focus keeps gaining for hundreds of steps, and a mu shrunk before its
            // subproblem is solved leaves t hugging the worst element (fandisk-9M with a 100-step
            // cap: 0.166 to 0.191 as focus_band or barrier_initial_active moved by 10%; without,
            // 0.187 to 0.191). A stage in which neither the worst quality nor t rises for three
            // progress windows is a stall (below): mu shrinks once more if the last such shrink
            // paid, else the phase ends.
            // At least steps_per_mu steps at each mu: a step blocked by some element also gains
            // little, and shrinking mu at each such step would run away.
            // Or where the barrier let its worst element go (kLeastWorstWeight).
            ++steps_at_mu_;
            const double weight = barrier_worst_weight();
            const bool first_mu = stage_history_.back() == 0.0;
            const bool let_go_now =
                weight < kLeastWorstWeight && (!first_mu || (first_gap_ > 0.0 && barrier_mu() > weight * first_gap_));
            let_go_steps_ = let_go_now ? let_go_steps_ + 1 : 0;
            const bool let_go = let_go_steps_ >= stop_.progress_window;
            // (The polish's objective has no mu: its conjugate directions restart on failures only.)
            solved = stage_.polish ? false
                     : adaptive    ? steps_at_mu_ >= options_.steps_per_mu && accepted &&
                                    (gain_ < options_.gain_tolerance * barrier_mu() || let_go)
                              : steps_at_mu_ >= options_.steps_per_mu;
        }
        if (!accepted || solved) {
            // Newton steps near the end solve each subproblem at once, and a fixed shrink then
            // approaches the optimum only linearly (flat-tet-sphere: 0.64 per step): after k such
            // subproblems in a row mu shrinks k times, so the path is followed ever faster.
            for (int k = 0; k < std::max(1, newton ? quick_solves_ : 0); ++k) objective_.advance();
            steps_at_mu_ = 0;
            let_go_steps_ = 0;
            restart_ = true;
        }
        objective_.update(work_.counted(q_, counted_), reducer_);
        const Stats s = stats(q_);
        objective = objective_value(q_);
        if (!sound(s, objective)) {
            record(s, objective, step, accepted ? gain_ : 0.0);
            return end(TerminationReason::NumericalFailure,
                       "the qualities, the objective or the barrier's t are not finite numbers (iteration " +
                           std::to_string(summary_.iterations) + "); the best iterate is handed back");
        }
        // Better: fewer non-positive elements, then a higher worst quality; in the polish (which
        // holds the worst element) no lower worst quality and a higher mean.
        const bool better = stage_.polish ? s.bad <= best_bad_ && s.worst >= best_worst_ && s.mean > best_mean_
                                          : detail::better_iterate(s.bad, s.worst, best_bad_, best_worst_);
        if (better) {
            best_bad_ = s.bad;
            best_worst_ = s.worst;
            best_mean_ = s.mean;
            keep_best();
        }
        objective_.weights(q_, weight_);
        record(s, objective, step, accepted ? gain_ : 0.0);
        best_history_.push_back(best_worst_);
        measure_history_.push_back(measure(s));
        bad_history_.push_back(static_cast<double>(s.bad));
        stage_history_.push_back(stage_history_.back() + ((!accepted || solved) ? 1.0 : 0.0));
        gain_history_.push_back(gain_history_.back() + (accepted && barrier_mu() > 0.0 ? gain_ / barrier_mu() : 0.0));
        passes_history_.push_back(static_cast<double>(summary_.gradient_passes));

        if (untangling_ && s.bad == 0 && untangled()) {
            best_x_ = x_;
            return end(TerminationReason::TargetReached, "untangled");
        }
        if (!untangling_ && !stage_.polish && detail::target_reached(stop_, best_worst_))
            return end(TerminationReason::TargetReached, "the worst quality reached the target");
        if (stage_.polish && best_mean_ > stage_.mean_goal)
            return end(TerminationReason::Converged, "above the input's mean");
        if (out_of_reach) {
            PhaseResult result = end(TerminationReason::Converged, "the barrier's subproblem is out of Newton's reach");
            result.recenter = true;
            return result;
        }
        // One Newton step can lift the worst elements far above t (fandisk-9M with barrier_shrink
        // 0.88: by five times the gap the finish began with). The bulk then holds t, and the steps
        // that follow trade the worst elements for it (500 iterations below the best iterate). A
        // fresh barrier from the best iterate weights the worst elements again. Measured from t or
        // from where t began, whichever is higher: each such restart needs the best worst quality
        // to have risen by more than three times the gap, so restarts cannot cycle.
        if (stage_.finish && first_gap_ > 0.0 && best_worst_ - std::max(barrier_t(), first_t_) > kLostGap * first_gap_) {
            PhaseResult result = end(TerminationReason::Converged,
                                     "the worst quality rose far above the barrier's t; a fresh barrier follows");
            result.recenter = true;
            return result;
        }
        // A stall is judged once a smaller mu has been tried in the window (a worst element held
        // at one mu is often freed by the next: house2 with long stages, fandisk-100k), or over
        // three windows without (a mu held by gains elsewhere while the worst stands still:
        // fandisk-1M, 289 iterations against 238 for the same result).
        // The finish's steps take a gradient pass per Hessian product: it needs as much progress
        // per pass as conjugate gradients (one pass per step) need per step.
        TerminationCriterion judged = stop_;
        const auto window = static_cast<std::size_t>(stop_.progress_window);
        if (stage_.finish && passes_history_.size() > window)
            judged.min_progress *= (passes_history_.back() - passes_history_[passes_history_.size() - 1 - window]) /
                                   static_cast<double>(window);
        const detail::StallWindow progress(judged, best_worst_);
        TerminationCriterion three = judged;
        three.progress_window = 3 * stop_.progress_window;
        const bool long_stall = detail::StallWindow(three, best_worst_).rose_too_little(best_history_);
        // Over a window: the worst quality and t rose too little, the inverted count did not fall.
        auto standing = [this](const detail::StallWindow& w) {
            return w.rose_too_little(best_history_) && w.rose_too_little(measure_history_) && w.did_not_fall(bad_history_);
        };
        const bool stalled = failures_ >= options_.max_failed_searches ||
                             (standing(progress) && (stage_.polish || progress.rose(stage_history_) || long_stall));
        // A focus that stalls may be held by the elements just outside it: a wider one, as long
        // as the last widening paid (each costs a stall window on more elements).
        // Not before the Newton finish, which starts on a fresh focus, nor in it: there the wider
        // focus cost more than it gained (fandisk-100k: with barrier_initial_active 10% higher
        // the widened conjugate gradients crept 160 iterations from 0.2270 to 0.2271 first).
        const bool widen = stalled && focusing_ && !stage_.finish && !stage_.newton_follows && band_ < 1.0 &&
                           best_worst_ > widened_at_ + progress.tolerance();
        // A stall inside one stage (mu held for three windows by gains that do not reach the
        // worst element) may be the subproblem's own plateau: a smaller mu weights the worst
        // elements more, as long as the last such cut paid.
        const bool shrink = !widen && stalled && adaptive && failures_ < options_.max_failed_searches &&
                            !progress.rose(stage_history_) && best_worst_ > shrunk_at_ + progress.tolerance();
        if (widen) {
            band_ = std::min(1.0, 2.0 * band_);
            widened_at_ = best_worst_;
            failures_ = 0;
            restart_ = true;
            restart_histories();
        } else if (shrink) {
            objective_.advance();
            steps_at_mu_ = 0;
            let_go_steps_ = 0;
            shrunk_at_ = best_worst_;
            restart_ = true;
            restart_histories();
            objective_.update(work_.counted(q_, counted_), reducer_);
            objective = objective_value(q_);
            objective_.weights(q_, weight_);
        } else if (failures_ >= options_.max_failed_searches) {
            return end(TerminationReason::NoImprovingStep, "no step along the search direction raises the objective");
        } else if (stalled) {
            return end(TerminationReason::Converged,
                       stage_.polish ? "the mean quality stopped rising" : "the worst quality stopped improving");
        }
        // Over three windows, as the worst quality rises in steps (a window without a rise is
        // common long before conjugate gradients stop paying: fandisk-100k); only while the
        // barrier's t creeps too (on fandisk-9M the worst stands still for 30 iterations at the
        // start while t climbs from 0.073 to 0.100), and mu has shrunk meanwhile (on fandisk-9M
        // with barrier_shrink 0.88 one mu holds for 95 iterations while the worst stands still
        // for 80, then jumps by 6%).
        // Where the steps gained less than kCalmGain mu each, ten times that pace hands over; where
        // they gained less than kQuickGain mu each, one window at kQuickHandoverProgress does.
        if (stage_.newton_follows) {
            auto creeping = [&](double factor, int windows) {
                TerminationCriterion slow = stop_;
                slow.min_progress *= factor;
                slow.progress_window = windows * stop_.progress_window;
                return detail::StallWindow(slow, best_worst_);
            };
            // The steps over the window gained less than `gain` mu each on average.
            auto gained_under = [&](const detail::StallWindow& window, double gain) {
                const std::size_t w = window.window();
                return window.spans(gain_history_) &&
                       gain_history_.back() - gain_history_[gain_history_.size() - 1 - w] < gain * static_cast<double>(w);
            };
            const detail::StallWindow creep = creeping(kHandoverProgress, 3),
                                      calm_creep = creeping(kCalmHandoverProgress, 3),
                                      quick_creep = creeping(kQuickHandoverProgress, 1);
            const bool slow = (standing(creep) || (gained_under(creep, kCalmGain) && standing(calm_creep))) &&
                              creep.rose(stage_history_);
            if (slow || (gained_under(quick_creep, kQuickGain) && standing(quick_creep)))
                return end(TerminationReason::Converged,
                           "the worst quality rose too slowly for conjugate gradients; Newton steps take over");
        }
        // An ascent can inch up for hundreds of iterations on one element that it cannot free
        // (fandisk-100k-boundary: 440 iterations from -0.102 to -0.100). When the inverted count
        // did not fall over the window and, at the window's pace, the worst element would still
        // be inverted when the budget runs out, hand over to local untangling now.
        if (untangling_ && progress.spans(best_history_)) {
            const double pace = progress.pace(best_history_);
            const double left = static_cast<double>(stop_.max_iterations - iteration);
            if (progress.did_not_fall(bad_history_) && best_worst_ + pace * left <= 0.0)
                return end(TerminationReason::Converged,
                           "the worst element rose too slowly to become valid within the iteration budget (" +
                               std::to_string(pace) + " per iteration over the last " +
                               std::to_string(progress.window()) + ")");
        }
        // Half way up the band, the elements above it start to matter: a new focus.
        if (focusing_ && !stage_.polish && (widen || s.worst >= focus_base_ + 0.5 * (focus_top_ - focus_base_))) {
            refocus();
            // A barrier over its focus alone keeps its t, and the weight on the worst, as its focus changes.
            if (focus_alone()) objective_.keep_weighting(work_.counted(q_, counted_), reducer_);
            objective_.update(work_.counted(q_, counted_), reducer_);
            objective = objective_value(q_);
            objective_.weights(q_, weight_);
        }
    }
}

// Where the barrier ascent stalls with elements inverted: sweeps of local untangling (Freitag &
// Plassmann) that move each free vertex of an element non-positive at the sweep's start, its
// neighbours held still, to where its elements' smallest volume is largest; until a sweep moves
// none, at most ten. Serially the vertices go one after the other in id order; a distributed run
// goes color by color (`coloring`, from the global ids: the same moves on any number of ranks),
// ghosts taking their owners' positions after each color. Records one history entry;
// returns the vertices moved everywhere.
int local_untangle_sweeps(const detail::Workspace& work, const VertexColoring* coloring, std::vector<double>& xyz,
                          const QualityMetric& hybrid, Summary& summary, const IterationObserver& observer,
                          Clock::time_point start) {
    const Mesh& mesh = work.mesh();
    const auto owned = work.owned();
    const auto classes = coloring ? coloring->classes() : std::vector<std::vector<VertexId>>{};
    std::vector<double> q(static_cast<std::size_t>(work.movable_elements()));
    std::vector<std::uint8_t> candidate(static_cast<std::size_t>(mesh.num_vertices()));
    int moved = 0;
    for (int sweep = 0; sweep < 10; ++sweep) {
        work.evaluate(hybrid, xyz, q);
        std::fill(candidate.begin(), candidate.end(), 0);
        for (std::size_t e = 0; e < q.size(); ++e)
            if (q[e] <= 0.0)
                for (VertexId v : mesh.element(static_cast<ElementId>(e))) candidate[v] = 1;
        double moved_now = 0.0;
        auto visit = [&](VertexId v) {
            if (candidate[v] && owned[v] && mesh.can_move(v))
                moved_now += detail::untangle_vertex(mesh, xyz, v, work.scale()).moved ? 1.0 : 0.0;
        };
        if (coloring) {
            for (const auto& members : classes) {
                for (VertexId v : members) visit(v);
                work.halo().update(xyz, 3);
            }
        } else {
            for (VertexId v = 0; v < mesh.num_vertices(); ++v) visit(v);
        }
        moved_now = work.reducer().total(moved_now);
        moved += static_cast<int>(moved_now);
        if (moved_now == 0.0) break;
    }
    std::vector<double> buffer;
    work.evaluate(hybrid, xyz, q);
    ++summary.quality_passes;
    const Stats s = quality_stats(work, q, buffer);
    IterationRecord r;
    r.iteration = summary.iterations;
    r.phase = "untangle_local";
    r.worst_quality = s.worst;
    r.best_worst_quality = s.worst;
    r.inverted = s.bad / work.copies();  // an inverted element's copies are all inverted
    r.mean_quality = s.mean;
    r.moved = moved;
    r.seconds = seconds_since(start);
    summary.history.push_back(std::move(r));
    if (observer) observer(summary.history.back());
    return moved;
}

}  // namespace

GlobalSolver::GlobalSolver(GlobalSolverOptions options) : options_(std::move(options)) { options_.validate(); }

namespace {

// Untangling (when needed) and shape improvement on the workspace; the caller frames the run.
// With `sliding`, its vertices slide in the shape phase.
Summary solve(const GlobalSolverOptions& options, const IterationObserver& observer, detail::SolverRun& run,
              detail::Workspace& work, detail::Checkpointer& checkpointer, const detail::SlidingBoundary* sliding) {
    Summary& summary = run.summary;
    // A resumed run enters the phase (and untangling round) it was checkpointed in.
    std::optional<detail::SolverState> resume;
    if (checkpointer.resumes()) resume = checkpointer.resume(summary, run);
    const bool resume_untangling = resume && resume->number("untangling") != 0.0;
    const auto start = run.start();
    auto finish = [&](TerminationReason reason, std::string message) { return run.finish(reason, std::move(message)); };
    std::vector<double> xyz(work.mesh().coordinates().begin(), work.mesh().coordinates().end());

    PhaseResult result{TerminationReason::TargetReached, ""};
    const bool tangled = summary.before.inverted - summary.before.inverted_frozen > 0 ||
                         summary.before.degenerate > 0;
    if (tangled && options.untangle && (!resume || resume_untangling)) {
        auto hybrid = make_metric("untangle_hybrid", options.metric_options);
        // Volumes measured against the size of each element's neighbourhood, so that a graded
        // mesh's small inverted elements weigh as much as its large ones.
        const std::vector<double> local_volumes = work.local_reference_volumes();
        MetricScale hybrid_scale = work.scale();
        hybrid_scale.element_reference_volume = local_volumes;
        hybrid->set_scale(hybrid_scale);
        // The global barrier ascent untangles most of a mesh; where it stalls on a few elements
        // (a local maximum of the worst quality), local steps move single vertices to where
        // their elements' smallest volume is largest, and the barrier ascent resumes.
        std::optional<VertexColoring> colors;  // distributed runs; collective: made when first needed
        const int first_round = resume ? static_cast<int>(resume->number("round")) : 0;
        // First the regularized energy, which needs no valid start; where it does not free every
        // element, the barrier ascent on the hybrid metric and local rounds go on from its best
        // iterate. (A run resumed from a checkpoint of the ascent goes straight back to it.)
        result = {TerminationReason::Converged, "not untangled yet"};
        const bool resume_energy = resume && resume->numbers.contains("energy");
        if (options.untangling == GlobalSolverOptions::Untangling::Energy && (!resume || resume_energy)) {
            const TerminationCriterion& limits = options.untangle_termination;
            const auto energy = detail::energy_untangle(work, xyz, limits.max_iterations, limits.max_seconds, summary,
                                                        observer, start, checkpointer, resume_energy ? &*resume : nullptr);
            if (resume_energy) resume.reset();
            result = {energy.reason, energy.message};
            const bool out_of_budget =
                result.reason == TerminationReason::IterationLimit || result.reason == TerminationReason::TimeLimit;
            if (out_of_budget || result.reason == TerminationReason::Interrupted ||
                result.reason == TerminationReason::NumericalFailure) {
                work.copy_back(xyz);
                return finish(out_of_budget ? TerminationReason::CannotUntangle : result.reason,
                              out_of_budget ? "untangling stopped (" + result.message + ") with elements still inverted"
                                            : "while untangling: " + result.message);
            }
        }
        for (int round = first_round; result.reason != TerminationReason::TargetReached; ++round) {
            const detail::SolverState* here = resume && round == first_round ? &*resume : nullptr;
            TerminationCriterion stop = options.untangle_termination;
            stop.max_iterations = here ? static_cast<int>(here->number("budget"))
                                       : std::max(0, stop.max_iterations - summary.untangle_iterations);
            // Hybrid qualities start negative: only the barrier (any t below them) is defined there.
            auto objective = make_objective("log_barrier", options.objective_options);
            result = Phase(work, xyz, *hybrid, *objective, stop, options, Stage{.untangling = true, .round = round}, summary, observer, start,
                           checkpointer)
                         .run(here);
            if (result.reason == TerminationReason::TargetReached) break;
            if (result.reason == TerminationReason::Interrupted || result.reason == TerminationReason::NumericalFailure) {
                work.copy_back(xyz);
                return finish(result.reason, "while untangling: " + result.message);
            }
            const bool out_of_budget =
                result.reason == TerminationReason::IterationLimit || result.reason == TerminationReason::TimeLimit;
            if (work.distributed() && !out_of_budget && round < options.local_untangle_rounds && !colors)
                colors = color_vertices(*work.distributed());
            if (out_of_budget || round == options.local_untangle_rounds ||
                local_untangle_sweeps(work, colors ? &*colors : nullptr, xyz, *hybrid, summary, observer, start) == 0) {
                work.copy_back(xyz);
                return finish(TerminationReason::CannotUntangle,
                              "untangling stopped (" + result.message + ") with elements still inverted");
            }
        }
        resume.reset();
    }
    if (resume && resume_untangling)
        throw FileError(resume->source, 0, "this checkpoint is of an untangling phase, but the mesh needs none");
    const bool still_tangled = !options.untangle && tangled;
    if (options.improve_shape && !still_tangled) {
        auto metric = work.copies() > 1 ? make_dihedral_sine_term() : make_metric(options.shape_metric, options.metric_options);
        metric->set_scale(work.scale());
        auto objective = make_objective(options.objective, options.objective_options);
        std::optional<SlidingVertices> sliding_vertices;
        if (sliding) sliding_vertices.emplace(work, *sliding);
        // Where conjugate gradients stall, the barrier's subproblems have become too ill-conditioned
        // for first-order steps; Newton steps go on from the best iterate (docs/global_solver.md).
        const bool finish = options.finish == GlobalSolverOptions::Finish::Newton && objective->is_continuation() &&
                            options.direction != GlobalSolverOptions::Direction::Newton && !sliding;
        // A run resumed from a checkpoint of the finish goes straight back to it, and to its part.
        const bool resume_finish = resume && resume->numbers.contains("finish") && resume->number("finish") != 0.0;
        // (Checkpoints from before the finish had two parts have no "fresh": theirs was fresh.)
        const bool resume_fresh = resume_finish && (!resume->numbers.contains("fresh") || resume->number("fresh") != 0.0);
        // A run resumed from a checkpoint of the mean's polish goes straight back to it.
        const bool resume_polish = resume && resume->numbers.contains("polish") && resume->number("polish") != 0.0;
        if (resume_polish) {
            const auto shape_reason = static_cast<TerminationReason>(resume->number("shape_reason"));
            result = {shape_reason, "the shape phases stopped (" + std::string(to_string(shape_reason)) + ") before the checkpoint"};
        }
        if (!resume_finish && !resume_polish)
            result = Phase(work, xyz, *metric, *objective, options.termination, options, Stage{.newton_follows = finish},
                           summary, observer, start, checkpointer, sliding_vertices ? &*sliding_vertices : nullptr)
                         .run(resume ? &*resume : nullptr);
        const bool stalled = result.reason == TerminationReason::Converged || result.reason == TerminationReason::NoImprovingStep;
        auto shape_iterations = [&] { return summary.iterations - summary.untangle_iterations; };
        const int left = options.termination.max_iterations - shape_iterations();
        const bool finishing = !resume_finish && !resume_polish && finish && stalled && left > 0;
        // First with the shape phase's own barrier (its mu): where the conjugate gradients stalled
        // near a max-min point, Newton steps converge from there (fandisk-9M). That part may take
        // its 50 steps before it hands over, so it goes first only where the budget leaves the fresh
        // barrier as many after them; nearer the budget's end the fresh barrier goes alone (the
        // larger gain on five of seven meshes where the first part hands over; fandisk-9M with
        // barrier_initial_active 10% lower stalls at iteration 488: 0.19026 against 0.18025).
        const bool first_part = resume_finish ? !resume_fresh : finishing && left >= 2 * kNewtonStepsAtOneMu;
        if (first_part)
            result = Phase(work, xyz, *metric, *objective, options.termination, options,
                           Stage{.finish = true, .iterations_before = shape_iterations()}, summary, observer, start, checkpointer)
                         .run(resume_finish ? &*resume : nullptr);
        // Far from that barrier's central path, a fresh barrier from the best iterate (mu from
        // the qualities, as at the start), under which the worst elements can rearrange; and
        // another one whenever a part's worst elements rose far above its t (Phase::run).
        bool fresh_next = resume_fresh || result.recenter || (finishing && !first_part);
        for (bool resuming = resume_fresh; fresh_next; resuming = false) {
            if (!resuming && shape_iterations() >= options.termination.max_iterations) {
                result = {TerminationReason::IterationLimit,
                          detail::budget_message(TerminationReason::IterationLimit, options.termination, "iterations")};
                break;
            }
            auto fresh = make_objective(options.objective, options.objective_options);
            result = Phase(work, xyz, *metric, *fresh, options.termination, options,
                           Stage{.finish = true, .iterations_before = shape_iterations(), .fresh = true}, summary, observer,
                           start, checkpointer)
                         .run(resuming ? &*resume : nullptr);
            fresh_next = result.recenter;
        }
        // The mean's polish, from the best iterate of them all, within what is left of the budget.
        auto mean_at = [&](std::span<const double> coordinates) {
            std::vector<double> q(static_cast<std::size_t>(work.movable_elements())), buffer;
            work.evaluate(*metric, coordinates, q);
            ++summary.quality_passes;
            return quality_stats(work, q, buffer).mean;
        };
        const bool budget_left = result.reason != TerminationReason::IterationLimit &&
                                 result.reason != TerminationReason::TimeLimit &&
                                 shape_iterations() < options.termination.max_iterations;
        const bool sound_end =
            result.reason != TerminationReason::Interrupted && result.reason != TerminationReason::NumericalFailure;
        std::optional<double> mean_before;
        double mean_goal = std::numeric_limits<double>::infinity();  // always: until the mean stops rising
        if (resume_polish) {
            mean_goal = resume->number("mean_goal");
        } else if (options.polish != GlobalSolverOptions::Polish::Off && budget_left && sound_end) {
            mean_before = mean_at(xyz);
            if (options.polish == GlobalSolverOptions::Polish::Auto) {
                mean_goal = mean_at(work.mesh().coordinates());
                if (!(*mean_before < mean_goal)) mean_before.reset();  // the mean did not fall
            }
        }
        if (resume_polish || mean_before) {
            MeanAboveFloor polish;
            const PhaseResult polished =
                Phase(work, xyz, *metric, polish, options.termination, options,
                      Stage{.iterations_before = shape_iterations(),
                            .polish = true,
                            .mean_goal = mean_goal,
                            .shape_reason = result.reason},
                      summary, observer, start, checkpointer, sliding_vertices ? &*sliding_vertices : nullptr)
                    .run(resume_polish ? &*resume : nullptr);
            if (polished.reason == TerminationReason::Interrupted || polished.reason == TerminationReason::NumericalFailure) {
                result = polished;
            } else {
                const double mean_after = polished.mean;
                std::ostringstream then;
                then << std::setprecision(7) << "; then, with the elements near the worst held still, the mean quality ";
                if (!mean_before) then << "came to " << mean_after;
                else if (mean_after > *mean_before) then << "rose from " << *mean_before << " to " << mean_after;
                else then << "stayed at " << *mean_before;
                then << " (" << polished.message << ")";
                result.message += then.str();
            }
        }
    } else if (resume) {
        throw FileError(resume->source, 0, "this checkpoint is of a shape phase, which this run does not have");
    }
    work.copy_back(xyz);
    if (result.reason == TerminationReason::Interrupted || result.reason == TerminationReason::NumericalFailure)
        return finish(result.reason, result.message);
    if (summary.before.inverted_frozen > 0)
        return finish(TerminationReason::CannotUntangle,
                      std::to_string(summary.before.inverted_frozen) +
                          " inverted elements have all their vertices fixed; no smoother can move them");
    if (still_tangled)
        return finish(TerminationReason::CannotUntangle, "the mesh is tangled and untangling was turned off");
    return finish(result.reason, result.message);
}

// One run on the part, with the boundary sliding (`sliding`) or not (nullptr).
Summary improve_part(const GlobalSolverOptions& options, const IterationObserver& observer, MeshPart part,
                     detail::SlidingBoundary* sliding) {
    const std::string name = "global";
    detail::SolverRun run(part, name, options.shape_metric);
    if (sliding) sliding->set_scale_exponent(run.scale_exponent());
    if (auto nothing = run.nothing_to_move()) return *nothing;
    detail::Checkpointer checkpointer(options.checkpoint, name, options_text(options), part);
    // The dihedral quality's six angles are terms of their own (docs/metrics.md): at a tie of two
    // angles the smaller one alone is a kink where the ascent stalls.
    const Mesh& mesh = part.mesh();
    const bool angle_terms = options.improve_shape && options.shape_metric == "dihedral_sine" &&
                             mesh.kind() == ElementKind::Tetrahedron && !mesh.has_cells();
    detail::Workspace work(part, options.renumber, angle_terms);
    return solve(options, observer, run, work, checkpointer, sliding);
}

}  // namespace

Summary GlobalSolver::improve(MeshPart part) {
    detail::ThreadScope threads(options_.threads);
    if (options_.boundary != GlobalSolverOptions::Boundary::Slide) return improve_part(options_, observer(), part, nullptr);
    // The sliding run is a shape phase from the valid mesh the first run left: untangling would
    // not keep the boundary on the surface.
    return detail::fixed_then_sliding(part, options_.surface, options_.termination, options_.improve_shape,
                                      [&](const TerminationCriterion& budget, detail::SlidingBoundary* sliding) {
                                          GlobalSolverOptions run = options_;
                                          run.termination = budget;
                                          if (sliding) run.untangle = false;
                                          return improve_part(run, observer(), part, sliding);
                                      });
}

}  // namespace paloverde
