// Which vertices a phase moves: a focus on the elements near the worst (focus_band), or in the
// mean's polish every vertex but those of the elements near the worst. The elements outside stand
// still at the qualities they had when the focus was made (frozen_), and the objective is told so.
#include <algorithm>
#include <cmath>
#include <limits>

#include "global_phase.hpp"

namespace paloverde::detail {

namespace {

// The mean's polish holds still the vertices of the elements in this lowest fraction of
// worst..ideal quality; the others stay above its top (GlobalSolverOptions::polish).
constexpr double kPolishBand = 0.03;
// Its barrier's mu, as a fraction of the gap between the mean quality and that top: an element
// weighs twice once it comes within mu of the top, so the elements the sum would push down stop
// well before they crowd there.
constexpr double kPolishMu = 0.01;

}  // namespace

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

void Phase::rate_whole_mesh() {
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
}

void Phase::refocus() {
    rate_whole_mesh();
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
    // stalls the focus below what the whole mesh reaches. (Through the band vertices' own
    // elements: a focus is a small part of a large mesh.)
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
    if (work_.part().whole()) return;
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
    // From the focus's terms alone t rises to within about one mu of the worst quality, where a
    // single element drives each step (docs/global_solver.md). Not the finish's fresh barrier: it
    // weighs its focus alone.
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

}  // namespace paloverde::detail
