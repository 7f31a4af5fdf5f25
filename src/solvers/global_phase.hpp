#pragma once
// One phase of the global solver's barrier ascent (docs/global_solver.md): the stages it can be,
// the figures of an iterate's qualities, and the Phase that runs one stage from its start (or a
// checkpoint) to its end. Its parts live in:
//   global_phase.cpp     the iteration: gradient, direction, step, bookkeeping
//   phase_rules.cpp      when a subproblem is solved, and when the phase ends or hands over
//   line_search.cpp      the line search and its per-vertex damping
//   focus.cpp            which vertices move (focus_band, the polish's held elements)
//   phase_checkpoint.cpp the phase's state in checkpoints
//   quality_stats.cpp    whole-mesh figures of the qualities
//   global_untangle.cpp  the untangling stage (energy, barrier rounds, local sweeps)
//   shape_stages.cpp     the shape stages and their order (next_stage)
// global_solver.cpp holds the solver's entry and runs the two.
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "paloverde/metrics/quality_metric.hpp"
#include "paloverde/objectives/objective_function.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "checkpointer.hpp"
#include "newton_direction.hpp"
#include "run_support.hpp"
#include "sliding_vertices.hpp"
#include "stopping.hpp"
#include "workspace.hpp"

namespace paloverde::detail {

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
Frozen frozen_stats(const Reducer& reducer, std::span<const double> counted);
// With `frozen`, the figures of the whole: the qualities given and the frozen elements.
Stats quality_stats(const Workspace& work, std::span<const double> all, std::vector<double>& buffer,
                    const Frozen& frozen = {});
// The worst of the qualities `all` that this process counts (NaN skipped), over all processes:
// quality_stats' worst alone.
double worst_counted(const Workspace& work, std::span<const double> all, std::vector<double>& buffer);

// Newton steps at one mu before its subproblem counts as out of reach.
inline constexpr int kNewtonStepsAtOneMu = 50;

// The stages of the global solver, in the order it may run them; next_stage (shape_stages.cpp)
// says which follows which. Shape: the conjugate gradients' (or steepest ascent's, or Newton's)
// shape phase; ShapeThenFinish: the same where the Newton finish follows it and it may hand over;
// Finish: Newton steps on the shape phase's barrier, counting on from its iterations;
// FreshFinish: Newton steps on a fresh barrier; Polish: the mean's polish after them all.
enum class StageKind { Untangle, Shape, ShapeThenFinish, Finish, FreshFinish, Polish };

// Where solve() stands, for the phase and its checkpoints.
struct Stage {
    StageKind kind = StageKind::Shape;
    int round = 0;              // Untangle: the untangling round
    int iterations_before = 0;  // the finish and the polish: the shape iterations before them
    // The polish ends once the mean quality exceeds this (polish auto: the input's mean).
    double mean_goal = std::numeric_limits<double>::infinity();
    // The polish: why the shape phases before it stopped (GlobalSolverOptions::polish).
    TerminationReason shape_reason = TerminationReason::Converged;
    // Shape: run again, on a barrier started just under the worst quality, after a shape phase
    // that stalled below its start (ShapeStages::next_stage).
    bool close_start = false;

    bool untangling() const { return kind == StageKind::Untangle; }
    bool finish() const { return kind == StageKind::Finish || kind == StageKind::FreshFinish; }
    bool fresh() const { return kind == StageKind::FreshFinish; }
    bool polish() const { return kind == StageKind::Polish; }
    bool newton_follows() const { return kind == StageKind::ShapeThenFinish; }
    // The phase's name in the history.
    const char* label() const;
};

struct PhaseResult {
    TerminationReason reason;
    std::string message;
    // The Newton finish found its barrier's subproblem out of reach: a fresh barrier should follow.
    bool recenter = false;
    // The mean quality of the iterate handed back (the polish, which keeps the best mean).
    double mean = std::numeric_limits<double>::quiet_NaN();
    // The iterate handed back is better than the phase's start (fewer inverted elements, or a
    // higher worst quality).
    bool gained = true;
};

// What the solver's phases share: the run, its budget and where it reports.
struct PhaseContext {
    Workspace& work;
    const GlobalSolverOptions& options;
    Summary& summary;
    const IterationObserver& observer;
    Clock::time_point start;
    Checkpointer& checkpointer;
};

// One phase (a stage) of the barrier ascent over the workspace's movable elements. Steps are
// accepted when they raise the objective (Armijo), stay in its domain and do not add non-positive
// elements; the worst quality of an iterate may dip while the barrier rebalances, so the phase
// keeps the best iterate (highest worst quality) and ends on it.
class Phase {
public:
    Phase(const PhaseContext& context, std::vector<double>& xyz, const QualityMetric& metric,
          ObjectiveFunction& objective, const TerminationCriterion& stop, Stage stage,
          const SlidingVertices* sliding = nullptr)
        : work_(context.work), x_(xyz), metric_(metric), objective_(objective), stop_(stop),
          options_(context.options), stage_(stage), summary_(context.summary), observer_(context.observer),
          start_(context.start), checkpointer_(context.checkpointer), sliding_(sliding) {}

    // From the phase's start, or from a checkpoint's state at an iteration boundary.
    PhaseResult run(const SolverState* resume = nullptr);

private:
    // What one iteration decided about the objective's subproblem.
    struct Subproblem {
        bool solved = false;        // go on to the next one
        bool out_of_reach = false;  // the Newton finish: a fresh barrier should follow
        bool adaptive = false;      // mu shrinks on the steps' gains (conjugate gradients on a barrier)
    };

    // global_phase.cpp: the iteration.
    void prepare();
    std::optional<PhaseResult> start(double& objective);
    std::optional<PhaseResult> iterate(int iteration, double& objective);
    std::optional<PhaseResult> at_top(int iteration);
    std::optional<PhaseResult> ascent_gradient();
    double newton_direction();
    void conjugate_direction();
    double share_direction();
    void next_subproblem();
    void note_iterate(const Stats& s, double objective, double step, bool accepted, bool solved);
    void apply_preconditioner();
    void record(const Stats& s, double objective, double step, double gain);
    PhaseResult end(TerminationReason reason, std::string message);
    // Every number the next iteration needs is finite (a NaN ends the phase on its best iterate).
    bool sound(const Stats& s, double objective) const;
    // best_x_ = x_. Within one focus only its free vertices move, so only they can differ: a
    // small focus of a large mesh does not copy the mesh at every better iterate.
    void keep_best();
    // The histories start over from their last entries (a wider focus).
    void restart_histories();
    Stats stats(std::span<const double> q) { return quality_stats(work_, q, counted_, frozen_); }
    double objective_value(std::span<const double> q) { return objective_.value(work_.counted(q, counted_), reducer_); }
    // The objective's state and weights at x_ (after the subproblem or the focus changed).
    void update_objective(double& objective);
    bool untangled() const;
    // The progress the stall windows watch: the barrier's t, or in the polish the mean quality.
    double measure(const Stats& s) const { return stage_.polish() ? s.mean : objective_.progress_measure(); }

    // phase_rules.cpp: when the subproblem is solved and when the phase ends.
    Subproblem judge_subproblem(bool accepted, bool full_step, double decrement);
    std::optional<PhaseResult> judge_end(int iteration, const Stats& s, double& objective, const Subproblem& sub);
    std::optional<PhaseResult> reached_end(const Stats& s, bool out_of_reach);
    bool standing(const StallWindow& w) const;
    std::optional<PhaseResult> judge_stall(const TerminationCriterion& judged, const StallWindow& progress,
                                           bool adaptive, double& objective, bool& widened);
    std::optional<PhaseResult> hands_over();
    std::optional<PhaseResult> too_slow_to_untangle(int iteration, const StallWindow& progress);

    // line_search.cpp
    bool line_search(double objective, double max_direction);
    // A sliding vertex's damping factor at step s: its move held to one reference length.
    double slide_damping(VertexId v, double s, double length) const;
    // Rates the trial step s; false where some element blocks it however much its vertices are damped.
    bool damp_blocking(double s, std::vector<VertexId>& damped, std::vector<VertexId>& once_damped);
    // A trial element blocks the step when it leaves the objective's domain (above floor) or
    // becomes non-positive although it was positive.
    bool blocks(ElementId e, double floor) const {
        return !(trial_q_[e] > floor) || (trial_q_[e] <= 0.0 && q_[e] > 0.0);
    }
    void damp_like_owners(std::vector<VertexId>& damped);
    // Damps each vertex's share of the trial step (s times the direction) fourfold and rates
    // its elements again (into reevaluated_).
    void damp(const std::vector<VertexId>& vertices, double s);
    // The trial's damped vertices are damped again while their own elements' barrier terms are
    // lower than at the iterate. False when that makes an element block (the trial fails).
    bool damp_where_barrier_falls(std::vector<VertexId>& once_damped, double s, double t);
    bool barrier_falls(VertexId v) const;
    void note_barrier_changes(std::span<const ElementId> elements, double t);

    // focus.cpp
    void size_element_arrays();
    // Focus on the elements below the band above the whole mesh's worst quality (focus_band).
    void refocus();
    // Since this phase made the focus: the whole mesh's qualities at x_ into whole_q_.
    void rate_whole_mesh();
    // The finish's fresh barrier weighs its focus alone: there t and mu come from the few worst
    // elements. With the still elements' terms (many more) t stayed far below the worst elements,
    // which the steps then traded for the rest (docs/global_solver.md, "The fresh barrier weighs
    // its focus alone").
    bool focus_alone() const { return focusing_ && stage_.fresh(); }
    // The mean's polish: holds still the vertices of the elements below kPolishBand and sets
    // the objective's floor at its top (q_ rates the whole mesh at x_).
    void hold_near_worst();
    // A distributed run: ghosts take their owners' flags in moving_ (each owner holds every
    // element of its vertices, so its decision is complete).
    void moving_like_owners();
    // Focus on the elements around the vertices flagged in moving_ (frozen_: the others).
    // whole_rated: whole_q_ holds the whole mesh's qualities at x_ already (refocus).
    void focus_on_moving(bool whole_rated = false);

    // phase_checkpoint.cpp
    void save_checkpoint(int iteration);
    int restore(const SolverState& state, double& objective);

    Workspace& work_;
    std::vector<double>& x_;
    const QualityMetric& metric_;
    ObjectiveFunction& objective_;
    const TerminationCriterion& stop_;
    const GlobalSolverOptions& options_;
    Stage stage_;
    Summary& summary_;
    const IterationObserver& observer_;
    Clock::time_point start_;
    Checkpointer& checkpointer_;
    const SlidingVertices* sliding_;  // the boundary vertices that slide, if any
    const Reducer& reducer_ = work_.reducer();
    bool newton_ = false;        // Newton directions (the finish, or direction: newton)
    bool precondition_ = false;  // the preconditioner and Newton need the objective's curvature

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
    // Where the phase started (PhaseResult::gained); a start unknown counts as beaten.
    double start_worst_ = -std::numeric_limits<double>::infinity();
    long start_bad_ = std::numeric_limits<long>::max();
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
    std::vector<double> gain_history_;    // the accepted steps' gains in units of mu, summed
    std::vector<double> passes_history_;  // gradient passes so far (a Newton step takes one per product)
    // Newton directions (shape phase): the damping factor, adapted to how the last step went.
    NewtonDirection newton_solver_{work_};
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

// The global solver's stages after one another (solve() in global_solver.cpp runs them).
// Untangling (global_untangle.cpp): TargetReached once untangled, else how the run ends (reason
// and message). Resets `resume` once it has resumed from it. With `sliding` (a surface mesh),
// its vertices slide on the surface while untangling too.
PhaseResult untangle(const PhaseContext& context, std::vector<double>& xyz, const SlidingBoundary* sliding,
                     std::optional<SolverState>& resume);
// The shape stages (shape_stages.cpp) from `before`, how the untangling ended: how the run ends.
PhaseResult improve_shape(const PhaseContext& context, std::vector<double>& xyz, const SlidingBoundary* sliding,
                          const std::optional<SolverState>& resume, PhaseResult before);

}  // namespace paloverde::detail
