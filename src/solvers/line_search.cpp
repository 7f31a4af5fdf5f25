// The phase's line search: trial steps along the direction, halved until one raises the
// objective (Armijo), with the step of the vertices whose elements would block it damped rather
// than the whole step shrunk.
#include <algorithm>
#include <cmath>

#include "core/blocked_sum.hpp"
#include "core/exact_sums.hpp"
#include "core/fast_log.hpp"
#include "global_phase.hpp"

namespace paloverde::detail {

bool Phase::line_search(double objective, double max_direction) {
    const double length = work_.reference_length();
    // In the shape phase, the barrier's own terms also judge the damped vertices (below).
    const bool judge_by_barrier = options_.damped_vertex_ascent && !stage_.untangling() && !stage_.finish() &&
                                  objective_.is_continuation();
    std::vector<VertexId> damped, once_damped;
    ++gap_round_;
    for (int attempt = 0; attempt < 40; ++attempt, step_ *= 0.5) {
        const double s = step_ * length / max_direction;
        // Only free vertices move: elsewhere trial_x_ holds x_ already (Phase::prepare, focus_on_moving).
        const auto free = work_.free_vertices();
        const auto count = static_cast<std::ptrdiff_t>(free.size());
#pragma omp parallel for schedule(static) if (static_cast<std::size_t>(work_.movable_elements()) > kParallelThreshold)
        for (std::ptrdiff_t i = 0; i < count; ++i) {
            const VertexId v = free[static_cast<std::size_t>(i)];
            damping_[v] = sliding_ ? slide_damping(v, s, length) : 1.0;
            for (int c = 0; c < 3; ++c) trial_x_[3 * v + c] = x_[3 * v + c] + damping_[v] * s * direction_[3 * v + c];
        }
        // Sliding vertices are rated where they would go: on the boundary.
        if (sliding_) sliding_->project(work_.mesh(), trial_x_);
        work_.evaluate(metric_, trial_x_, trial_q_);
        ++summary_.quality_passes;
        if (!damp_blocking(s, damped, once_damped)) continue;
        if (judge_by_barrier && !damp_where_barrier_falls(once_damped, s, objective_.subproblem_floor())) continue;
        // The Armijo test uses the slope of the damped step actually taken.
        const double slope = free_owned_sums<1>(work_, [&](std::size_t v, auto& acc) {
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

// On a surface mesh, where every vertex slides, a vertex moves at most one reference length per
// step: its tangent plane says little about the surface farther away, and the projection of a
// far point is slow and lands anywhere. As a damping factor, the Armijo slope and damp() take it
// into account like any other. (A volume mesh's sliding boundary vertices are left uncapped: there
// the cap raises the worst element a little at up to twice the time.)
double Phase::slide_damping(VertexId v, double s, double length) const {
    if (!work_.mesh().has_surface_normals() || !work_.mesh().slides(v)) return 1.0;
    const double* d = &direction_[3 * static_cast<std::size_t>(v)];
    const double move = s * std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    return move > length ? length / move : 1.0;
}

// Rather than shrinking the whole step for an element that blocks it, the step of its vertices is
// damped until it no longer blocks: one tangle does not freeze the mesh. `once_damped`: the
// vertices damped at all.
bool Phase::damp_blocking(double s, std::vector<VertexId>& damped, std::vector<VertexId>& once_damped) {
    const Mesh& mesh = work_.mesh();
    const double floor = objective_.domain_floor();
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
            for (ElementId e = 0; e < work_.movable_elements(); ++e) damp_if_blocking(e);
        else
            for (ElementId e : reevaluated_) damp_if_blocking(e);
        damp_like_owners(damped);
        blocked = reducer_.max(damped.empty() ? 0.0 : 1.0) > 0.0;
        if (!blocked) break;
        for (VertexId v : damped)
            if (damping_[v] == 1.0) once_damped.push_back(v);
        damp(damped, s);
    }
    for (VertexId v : work_.free_vertices()) stamp_[v] = 0;
    return !blocked;
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

// Whether the sum of the barrier changes noted (note_barrier_changes) over v's elements is negative.
bool Phase::barrier_falls(VertexId v) const {
    const Mesh& mesh = work_.mesh();
    const ElementId movable = work_.movable_elements();
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
    log_all(logs_.data(), logs_.data(), new_gaps_.size());
    for (std::size_t i = 0; i < new_gaps_.size(); ++i) log_gap_[new_gaps_[i]] = logs_[i];
    for (std::size_t i = 0; i < changing_.size(); ++i) logs_[i] = trial_q_[changing_[i]] - t;
    log_all(logs_.data(), logs_.data(), changing_.size());
    for (std::size_t i = 0; i < changing_.size(); ++i)
        barrier_change_[changing_[i]] = logs_[i] - log_gap_[changing_[i]];
}

// A distributed run: the owner of a vertex holds all its elements, so its decision to damp the
// vertex is complete; ghosts take their owners' decisions.
void Phase::damp_like_owners(std::vector<VertexId>& damped) {
    if (work_.part().whole()) return;
    const auto owned = work_.owned();
    for (VertexId v : damped) mark_[v] = 1.0;
    work_.halo().update(mark_, 1);
    std::erase_if(damped, [&](VertexId v) { return !owned[v]; });
    for (VertexId v : work_.ghosts())
        if (mark_[v] != 0.0 && work_.mesh().can_move(v)) damped.push_back(v);
    std::fill(mark_.begin(), mark_.end(), 0.0);
}

}  // namespace paloverde::detail
