// The global solver's untangling stage: the regularized energy, then rounds of the barrier
// ascent on the hybrid metric with sweeps of local untangling between them.
#include <algorithm>
#include <memory>
#include <optional>

#include "paloverde/solvers/vertex_coloring.hpp"
#include "energy_untangle.hpp"
#include "global_phase.hpp"
#include "local_untangle.hpp"

namespace paloverde::detail {

namespace {

// Where the barrier ascent stalls with elements inverted: sweeps of local untangling (Freitag &
// Plassmann) that move each free vertex of an element non-positive at the sweep's start, its
// neighbours held still, to where its elements' smallest volume is largest; until a sweep moves
// none, at most ten. Serially the vertices go one after the other in id order; a distributed run
// goes color by color (`coloring`, from the global ids: the same moves on any number of ranks),
// ghosts taking their owners' positions after each color. A sliding vertex (`slide`) moves on
// its patch or curve. Records one history entry; returns the vertices moved everywhere.
int local_untangle_sweeps(const Workspace& work, const VertexColoring* coloring, std::vector<double>& xyz,
                          const QualityMetric& hybrid, Summary& summary, const IterationObserver& observer,
                          Clock::time_point start, const VertexSlide* slide) {
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
                moved_now += untangle_vertex(mesh, xyz, v, work.scale(), slide).moved ? 1.0 : 0.0;
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

// First the regularized energy, which needs no valid start; where it does not free every element,
// the barrier ascent on the hybrid metric and local rounds go on from its best iterate. On a
// surface mesh (`sliding`) every one of them moves its vertices along the surface.
class Untangling {
public:
    Untangling(const PhaseContext& context, std::vector<double>& xyz, const SlidingBoundary* sliding,
               std::optional<SolverState>& resume)
        : context_(context), work_(context.work), options_(context.options), xyz_(xyz), resume_(resume),
          hybrid_(make_metric("untangle_hybrid", options_.metric_options)),
          local_volumes_(work_.local_reference_volumes()) {
        if (sliding) sliding_.emplace(work_, *sliding);
        MetricScale hybrid_scale = work_.scale();
        hybrid_scale.element_reference_volume = local_volumes_;
        hybrid_->set_scale(hybrid_scale);
    }

    PhaseResult run() {
        const int first_round = resume_ ? static_cast<int>(resume_->number("round")) : 0;
        PhaseResult result{TerminationReason::Converged, "not untangled yet"};
        // (A run resumed from a checkpoint of the ascent goes straight back to it.)
        const bool resume_energy = resume_ && resume_->numbers.contains("energy");
        if (options_.untangling == GlobalSolverOptions::Untangling::Energy && (!resume_ || resume_energy)) {
            if (auto ended = energy(resume_energy, result)) return *ended;
        }
        result = rounds(first_round, result);
        resume_.reset();
        return result;
    }

private:
    static bool out_of_budget(const PhaseResult& r) {
        return r.reason == TerminationReason::IterationLimit || r.reason == TerminationReason::TimeLimit;
    }
    static bool ends_run(const PhaseResult& r) {
        return out_of_budget(r) || r.reason == TerminationReason::Interrupted ||
               r.reason == TerminationReason::NumericalFailure;
    }

    // The energy's result into `result`; how the run ends where the energy ends it.
    std::optional<PhaseResult> energy(bool resume_energy, PhaseResult& result) {
        const TerminationCriterion& limits = options_.untangle_termination;
        const auto energy = energy_untangle(work_, xyz_, limits.max_iterations, limits.max_seconds, context_.summary,
                                            context_.observer, context_.start, context_.checkpointer,
                                            resume_energy ? &*resume_ : nullptr, slides());
        if (resume_energy) resume_.reset();
        result = {energy.reason, energy.message};
        if (!ends_run(result)) return std::nullopt;
        if (out_of_budget(result))
            return PhaseResult{TerminationReason::CannotUntangle,
                               "untangling stopped (" + result.message + ") with elements still inverted"};
        return PhaseResult{result.reason, "while untangling: " + result.message};
    }

    // The global barrier ascent untangles most of a mesh; where it stalls on a few elements (a
    // local maximum of the worst quality), local steps move single vertices to where their
    // elements' smallest volume is largest, and the barrier ascent resumes.
    PhaseResult rounds(int first_round, PhaseResult result) {
        for (int round = first_round; result.reason != TerminationReason::TargetReached; ++round) {
            const SolverState* here = resume_ && round == first_round ? &*resume_ : nullptr;
            TerminationCriterion stop = options_.untangle_termination;
            stop.max_iterations = here ? static_cast<int>(here->number("budget"))
                                       : std::max(0, stop.max_iterations - context_.summary.untangle_iterations);
            // Hybrid qualities start negative: only the barrier (any t below them) is defined there.
            auto objective = make_objective("log_barrier", options_.objective_options);
            result = Phase(context_, xyz_, *hybrid_, *objective, stop, Stage{.kind = StageKind::Untangle, .round = round},
                           slides())
                         .run(here);
            if (result.reason == TerminationReason::TargetReached) break;
            if (result.reason == TerminationReason::Interrupted || result.reason == TerminationReason::NumericalFailure)
                return {result.reason, "while untangling: " + result.message};
            if (!work_.part().whole() && !out_of_budget(result) && round < options_.local_untangle_rounds && !colors_)
                colors_ = color_vertices(work_.part());
            if (out_of_budget(result) || round == options_.local_untangle_rounds ||
                local_untangle_sweeps(work_, colors_ ? &*colors_ : nullptr, xyz_, *hybrid_, context_.summary,
                                      context_.observer, context_.start, slides()) == 0)
                return {TerminationReason::CannotUntangle,
                        "untangling stopped (" + result.message + ") with elements still inverted"};
        }
        return result;
    }

    const SlidingVertices* slides() const { return sliding_ ? &*sliding_ : nullptr; }

    const PhaseContext& context_;
    Workspace& work_;
    const GlobalSolverOptions& options_;
    std::vector<double>& xyz_;
    std::optional<SolverState>& resume_;
    std::unique_ptr<QualityMetric> hybrid_;
    // Volumes measured against the size of each element's neighbourhood, so that a graded mesh's
    // small inverted elements weigh as much as its large ones.
    std::vector<double> local_volumes_;
    std::optional<VertexColoring> colors_;  // distributed runs; collective: made when first needed
    std::optional<SlidingVertices> sliding_;
};

}  // namespace

PhaseResult untangle(const PhaseContext& context, std::vector<double>& xyz, const SlidingBoundary* sliding,
                     std::optional<SolverState>& resume) {
    return Untangling(context, xyz, sliding, resume).run();
}

}  // namespace paloverde::detail
