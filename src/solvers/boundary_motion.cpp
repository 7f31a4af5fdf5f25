#include "boundary_motion.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <sstream>
#include <vector>

#include "paloverde/assess/quality_assessor.hpp"
#include "core/exact_sums.hpp"
#include "paloverde/core/error.hpp"
#include "checkpointer.hpp"
#include "run_support.hpp"

namespace paloverde::detail {

namespace {

// Vertices whose positions the motion gives (those that do not move freely).
std::vector<std::uint8_t> driven_vertices(const Mesh& mesh) {
    std::vector<std::uint8_t> driven(static_cast<std::size_t>(mesh.num_vertices()));
    for (VertexId v = 0; v < mesh.num_vertices(); ++v) driven[static_cast<std::size_t>(v)] = mesh.degrees_of_freedom(v) < 3;
    return driven;
}

// The mesh at `fraction` of the motion: driven vertices between the reference and where they were
// given, the others where `free_from` has them.
void place(std::span<double> xyz, std::span<const double> free_from, std::span<const double> reference,
           std::span<const double> given, const std::vector<std::uint8_t>& driven, double fraction) {
    for (std::size_t v = 0; v < driven.size(); ++v)
        for (std::size_t c = 3 * v; c < 3 * v + 3; ++c)
            xyz[c] = !driven[v] ? free_from[c] : fraction == 1.0 ? given[c] : reference[c] + fraction * (given[c] - reference[c]);
}

// The free vertices carried along with the driven ones from `from` to `to` (whose driven vertices
// are where they go): the harmonic extension of the driven vertices' displacement, each edge
// weighted by its inverse squared length at `from`, so that small elements (by a moving wall, where
// meshes are fine) move nearly rigidly and large ones take up the deformation. A predictor: the
// solver untangles and improves from there. Conjugate gradients, Jacobi preconditioned, on the
// vertices the part owns (their rows are whole: a part holds every element around them), ghosts
// refreshed from their owners. Each row adds its neighbours in the order of their positions at
// `from` and the dot products are exact sums, so the result is the same bits however the mesh is
// split. Collective.
void carry_free_vertices(MeshPart part, const std::vector<std::uint8_t>& driven, std::span<const double> from,
                         std::span<double> to) {
    const Mesh& mesh = part.mesh();
    const auto n = static_cast<std::size_t>(mesh.num_vertices());
    auto position = [&](VertexId v) {
        const auto i = 3 * static_cast<std::size_t>(v);
        return std::array<double, 3>{from[i], from[i + 1], from[i + 2]};
    };
    // The unknowns: free vertices this part owns.
    std::vector<std::size_t> unknowns;
    for (VertexId v = 0; v < mesh.num_vertices(); ++v)
        if (!driven[static_cast<std::size_t>(v)] && part.owns(v)) unknowns.push_back(static_cast<std::size_t>(v));
    std::vector<std::size_t> offsets{0};
    std::vector<VertexId> neighbours, row;
    std::vector<double> weights;
    for (std::size_t v : unknowns) {
        row.clear();
        for (ElementId e : mesh.elements_of(static_cast<VertexId>(v)))
            for (VertexId u : mesh.element(e))
                if (static_cast<std::size_t>(u) != v) row.push_back(u);
        std::sort(row.begin(), row.end());
        row.erase(std::unique(row.begin(), row.end()), row.end());
        // (Vertices at one position have weight 0: their order changes no sum.)
        std::stable_sort(row.begin(), row.end(), [&](VertexId a, VertexId b) { return position(a) < position(b); });
        for (VertexId u : row) {
            double length2 = 0.0;
            for (std::size_t c = 0; c < 3; ++c) {
                const double d = from[3 * static_cast<std::size_t>(u) + c] - from[3 * v + c];
                length2 += d * d;
            }
            neighbours.push_back(u);
            weights.push_back(length2 > 0.0 ? 1.0 / length2 : 0.0);
        }
        offsets.push_back(neighbours.size());
    }
    const std::size_t m = unknowns.size();
    std::vector<double> diagonal(m, 0.0);
    for (std::size_t i = 0; i < m; ++i)
        for (std::size_t k = offsets[i]; k < offsets[i + 1]; ++k) diagonal[i] += weights[k];
    // Per local vertex (ghosts refreshed before each product); per unknown.
    // The three coordinates are three systems with one matrix, solved side by side (one ghost
    // update and one reduction per step for all three). Per local vertex (p, ghosts refreshed before
    // each product) or per unknown (the rest), three values each.
    std::vector<double> p(3 * n, 0.0), x(3 * m, 0.0), r(3 * m, 0.0), z(3 * m, 0.0), q(3 * m, 0.0);
    // q = A p over the unknowns: the weighted Laplacian with the driven vertices held at zero.
    auto apply = [&] {
        part.halo().update(p, 3);
        for (std::size_t i = 0; i < m; ++i) {
            double sum[3];
            for (std::size_t c = 0; c < 3; ++c) sum[c] = diagonal[i] * p[3 * unknowns[i] + c];
            for (std::size_t k = offsets[i]; k < offsets[i + 1]; ++k) {
                const auto u = static_cast<std::size_t>(neighbours[k]);
                if (!driven[u])
                    for (std::size_t c = 0; c < 3; ++c) sum[c] -= weights[k] * p[3 * u + c];
            }
            for (std::size_t c = 0; c < 3; ++c) q[3 * i + c] = sum[c];
        }
    };
    // Per coordinate c, the totals over the whole mesh of term(i, c) (K values each).
    auto totals = [&]<int K>(auto term) {
        auto sums = exact_sums<3 * K>(m, [&](std::size_t i, auto& acc) {
            if (diagonal[i] == 0.0) return;  // an unknown without edges stays (its terms are 0)
            for (std::size_t c = 0; c < 3; ++c) {
                const auto values = term(3 * i + c);
                for (int k = 0; k < K; ++k) acc[static_cast<std::size_t>(K) * c + static_cast<std::size_t>(k)].add(values[k]);
            }
        });
        part.reducer().sum(sums);
        std::array<std::array<double, K>, 3> out;
        for (std::size_t c = 0; c < 3; ++c)
            for (int k = 0; k < K; ++k) out[c][static_cast<std::size_t>(k)] = sums[static_cast<std::size_t>(K) * c + static_cast<std::size_t>(k)].value();
        return out;
    };
    for (std::size_t i = 0; i < m; ++i) {
        if (diagonal[i] == 0.0) continue;
        for (std::size_t k = offsets[i]; k < offsets[i + 1]; ++k) {
            const auto u = static_cast<std::size_t>(neighbours[k]);
            if (driven[u])
                for (std::size_t c = 0; c < 3; ++c) r[3 * i + c] += weights[k] * (to[3 * u + c] - from[3 * u + c]);
        }
        for (std::size_t c = 0; c < 3; ++c) z[3 * i + c] = p[3 * unknowns[i] + c] = r[3 * i + c] / diagonal[i];
    }
    const auto start = totals.template operator()<2>([&](std::size_t j) { return std::array<double, 2>{r[j] * z[j], r[j] * r[j]}; });
    double rz[3], bb[3];
    bool active[3];
    for (std::size_t c = 0; c < 3; ++c) rz[c] = start[c][0], bb[c] = start[c][1], active[c] = rz[c] > 0.0;
    const double limit = 4.0 * part.reducer().total(static_cast<double>(m));
    for (double iteration = 0; iteration < limit && (active[0] || active[1] || active[2]); ++iteration) {
        apply();
        const auto pq = totals.template operator()<1>([&](std::size_t j) { return std::array<double, 1>{p[3 * unknowns[j / 3] + j % 3] * q[j]}; });
        double alpha[3];
        for (std::size_t c = 0; c < 3; ++c) {
            if (active[c] && !(pq[c][0] > 0.0)) active[c] = false;
            alpha[c] = active[c] ? rz[c] / pq[c][0] : 0.0;
        }
        for (std::size_t i = 0; i < m; ++i) {
            if (diagonal[i] == 0.0) continue;
            for (std::size_t c = 0; c < 3; ++c) {
                if (!active[c]) continue;
                const std::size_t j = 3 * i + c;
                x[j] += alpha[c] * p[3 * unknowns[i] + c];
                r[j] -= alpha[c] * q[j];
                z[j] = r[j] / diagonal[i];
            }
        }
        const auto next = totals.template operator()<2>([&](std::size_t j) { return std::array<double, 2>{r[j] * z[j], r[j] * r[j]}; });
        double beta[3];
        for (std::size_t c = 0; c < 3; ++c) {
            if (active[c] && next[c][1] <= 1e-24 * bb[c]) active[c] = false;
            beta[c] = active[c] ? next[c][0] / rz[c] : 0.0;
            if (active[c]) rz[c] = next[c][0];
        }
        for (std::size_t i = 0; i < m; ++i)
            for (std::size_t c = 0; c < 3; ++c)
                if (active[c]) p[3 * unknowns[i] + c] = z[3 * i + c] + beta[c] * p[3 * unknowns[i] + c];
    }
    for (std::size_t i = 0; i < m; ++i)
        for (std::size_t c = 0; c < 3; ++c) to[3 * unknowns[i] + c] = from[3 * unknowns[i] + c] + x[3 * i + c];
    part.halo().update(to, 3);
}

// `run`'s work added to `total`'s, its history after total's.
void add_work(Summary& total, const Summary& run) {
    const int first = total.history.empty() ? 0 : total.history.back().iteration + 1;
    const double seconds = total.seconds;
    for (IterationRecord r : run.history) {
        r.iteration += first;
        r.seconds += seconds;
        total.history.push_back(std::move(r));
    }
    total.iterations += run.iterations;
    total.untangle_iterations += run.untangle_iterations;
    total.quality_passes += run.quality_passes;
    total.gradient_passes += run.gradient_passes;
    total.seconds += run.seconds;
}

// A restored outcome, with the counters and history a checkpoint restored into `work` and the
// seconds it recorded.
Summary with_work(Summary outcome, Summary work, double seconds) {
    take_work(outcome, std::move(work));
    outcome.seconds = seconds;
    return outcome;
}

// A followed motion's Summary with the every-vertex run after it, whose mesh it ends with (that
// run holds the boundary still: how far it slid stays the motion's).
Summary with_every_vertex_run(Summary followed, const Summary& run) {
    add_work(followed, run);
    followed.reason = run.reason;
    followed.message += "; then, every vertex moving: " + run.message;
    followed.after = run.after;
    followed.worst_after = run.worst_after;
    return followed;
}

// The first run: from the interior carried along with the boundary from the reference when that
// inverts fewer elements than the interior where it was given.
Summary run_first(MeshPart part, const std::vector<double>& given, const std::vector<double>& reference,
                  const std::vector<std::uint8_t>& driven, const std::function<Summary()>& solve) {
    std::vector<double> carried = given;
    carry_free_vertices(part, driven, reference, carried);
    const QualityAssessor count({"aspect_ratio"});
    const long inverted_given = count.assess(part).inverted;
    std::copy(carried.begin(), carried.end(), part.mesh().coordinates().begin());
    if (count.assess(part).inverted >= inverted_given) std::copy(given.begin(), given.end(), part.mesh().coordinates().begin());
    return solve();
}

// The worst quality in `metric` of the mesh at `at`, the part's coordinates left as they are. A
// run is good enough when it keeps at least half the worst quality of where it started from (the
// reference, then the last step): a run that loses more has left elements pressed against the
// moved boundary, which smaller steps avoid.
double worst_at(MeshPart part, const std::string& metric, std::span<const double> at) {
    const auto xyz = part.mesh().coordinates();
    const std::vector<double> now(xyz.begin(), xyz.end());
    std::copy(at.begin(), at.end(), xyz.begin());
    const QualityReport r = QualityAssessor({metric}).assess(part);
    std::copy(now.begin(), now.end(), xyz.begin());
    const MetricReport& m = r.metrics.front();
    return m.movable.count > 0 ? m.movable.min : m.all.min;
}

std::string percent(double fraction) {
    std::ostringstream out;
    out << std::round(1000.0 * fraction) / 10.0 << "%";
    return out.str();
}

}  // namespace

bool has_boundary_motion(MeshPart part) {
    const Mesh& mesh = part.mesh();
    const auto reference = mesh.reference_coordinates();
    double moved = 0.0;
    if (!reference.empty()) {
        const auto xyz = mesh.coordinates();
        for (VertexId v = 0; v < mesh.num_vertices() && moved == 0.0; ++v) {
            if (mesh.degrees_of_freedom(v) == 3) continue;
            const auto i = 3 * static_cast<std::size_t>(v);
            if (xyz[i] != reference[i] || xyz[i + 1] != reference[i + 1] || xyz[i + 2] != reference[i + 2]) moved = 1.0;
        }
    }
    return part.reducer().max(moved) > 0.0;
}

Summary follow_boundary_motion(MeshPart part, double smallest_fraction, double max_seconds,
                               const CheckpointSettings& checkpoints, const MotionRun& solve, bool every_vertex_run) {
    auto start = Clock::now();
    // What is left of max_seconds (> 0), or 0 when spent or when there is no limit.
    auto seconds_left = [&] { return max_seconds > 0.0 ? std::max(0.0, max_seconds - part.reducer().max(seconds_since(start))) : 0.0; };
    Mesh& mesh = part.mesh();
    // The mesh's coordinates now: a solver run on a distributed part may hand them back in a new array.
    const auto xyz = [&mesh] { return mesh.coordinates(); };
    const std::vector<double> given(xyz().begin(), xyz().end());
    const std::vector<double> reference(mesh.reference_coordinates().begin(), mesh.reference_coordinates().end());
    const std::vector<std::uint8_t> driven = driven_vertices(mesh);
    OptionsText step_option;
    step_option("smallest_motion_step", smallest_fraction);
    Checkpointer checkpointer(checkpoints.options, checkpoints.solver, checkpoints.options_text + step_option.text(), part,
                              CheckpointKind::Motion);
    // Each run's own checkpoints go beside the motion's, which says what run that is.
    RunCheckpoints runs(part, checkpoints.options);
    auto run = [&](double seconds, MotionRunKind kind) { return solve(seconds, runs.next_run(), kind); };
    Summary total, first_run;           // every run's work; the first run's
    std::vector<double> first, valid;   // the first run's mesh (kept if the steps do no better); the furthest accepted step's
    double done = 0.0, step = 0.5, floor = 0.0;
    int steps = 0;
    bool refused_last = false;  // the last step run was refused
    std::optional<SolverState> resumed;
    if (checkpointer.resumes()) {
        resumed = checkpointer.resume(total);
        start -= std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(resumed->elapsed));
    }
    // The every-vertex run from the mesh as it is, after the followed motion `followed`, within
    // what is left of the time (none left: the followed motion as it ended).
    auto moving_every_vertex = [&](Summary followed) {
        const double seconds = seconds_left();
        if (max_seconds > 0.0 && seconds == 0.0) return followed;
        return with_every_vertex_run(std::move(followed), run(seconds, MotionRunKind::EveryVertex));
    };
    // A followed motion's end: with every_vertex_run, its checkpoint, then the every-vertex run.
    auto ended = [&](Summary followed) {
        if (!every_vertex_run) return followed;
        if (runs.writes_now()) {
            runs.forget();
            SolverState state;
            state.numbers = {{"every_vertex", 1.0}, {"seconds", followed.seconds}};
            state.vertex_fields = {{"followed", std::vector<double>(xyz().begin(), xyz().end())}};
            store_outcome(state, "followed", followed);
            checkpointer.save(followed, state, seconds_since(start));
        }
        return moving_every_vertex(std::move(followed));
    };
    if (resumed && resumed->numbers.contains("every_vertex")) {
        const SolverState& state = *resumed;
        const std::vector<double>& followed = state.vertex_field("followed", given.size() / 3);
        std::copy(followed.begin(), followed.end(), xyz().begin());
        return moving_every_vertex(with_work(restored_outcome(state, "followed"), std::move(total), state.number("seconds")));
    }
    if (resumed && resumed->number("first_run_done") != 0.0) {
        const SolverState& state = *resumed;
        first_run = restored_outcome(state, "first_run");
        // Every run's work on top of the first run's outcome (the Summary's before is the first run's).
        total = with_work(first_run, std::move(total), state.number("seconds"));
        first = state.vertex_field("first", given.size() / 3);
        valid = state.vertex_field("valid", given.size() / 3);
        done = state.number("done");
        step = state.number("step");
        floor = state.number("floor");
        steps = static_cast<int>(state.number("steps"));
        refused_last = state.number("refused_last") != 0.0;
    } else {
        if (runs.writes_now()) {
            runs.forget();
            SolverState state;
            state.numbers = {{"first_run_done", 0.0}};
            checkpointer.save(total, state, seconds_since(start));
        }
        total = run_first(part, given, reference, driven, [&] { return run(max_seconds, MotionRunKind::First); });
        if (total.reason == TerminationReason::Interrupted) return total;
        floor = 0.5 * worst_at(part, total.quality_metric, reference);
        if (total.valid() && total.worst_after >= floor) return ended(std::move(total));
        first.assign(xyz().begin(), xyz().end());
        first_run = total;
        valid = reference;  // fraction 0
    }
    Summary last;
    bool out_of_time = false;
    while (done < 1.0 && step >= smallest_fraction) {
        // Where the steps stand before the next one, which starts from `valid`.
        if (runs.writes_now()) {
            runs.forget();
            SolverState state;
            state.numbers = {{"first_run_done", 1.0}, {"done", done}, {"step", step}, {"floor", floor}, {"steps", steps},
                             {"refused_last", refused_last ? 1.0 : 0.0}, {"seconds", total.seconds}};
            state.vertex_fields = {{"first", first}, {"valid", valid}};
            store_outcome(state, "first_run", first_run);
            checkpointer.save(total, state, seconds_since(start));
        }
        const double seconds = seconds_left();
        if (max_seconds > 0.0 && seconds == 0.0) {
            out_of_time = true;
            break;
        }
        const double next = std::min(1.0, done + step);
        place(xyz(), valid, reference, given, driven, next);
        carry_free_vertices(part, driven, valid, xyz());
        last = run(seconds, next < 1.0 ? MotionRunKind::Step : MotionRunKind::Last);
        add_work(total, last);
        if (last.reason == TerminationReason::Interrupted) break;
        // At the smallest step, any valid result goes on.
        if (last.valid() && (last.worst_after >= floor || step < 2.0 * smallest_fraction)) {
            valid.assign(xyz().begin(), xyz().end());
            done = next;
            ++steps;
            // Never past the end: a step halved after this one must try a nearer fraction. A step
            // that follows a refused one keeps its size: the motion just proved hard there, and a
            // doubled step would likely be refused again (a run as costly as a kept one).
            step = std::min((refused_last ? 1.0 : 2.0) * step, 1.0 - done);
            refused_last = false;
            floor = 0.5 * last.worst_after;
        } else {
            step /= 2.0;
            refused_last = true;
        }
    }
    std::ostringstream why;
    const bool interrupted = last.reason == TerminationReason::Interrupted;
    const bool first_better = first_run.valid() && (done < 1.0 || first_run.worst_after >= last.worst_after);
    if (interrupted || out_of_time) {
        // A step's mesh has its boundary short of where it was given: the first run's has not.
        std::copy(first.begin(), first.end(), xyz().begin());
        last = first_run;
        why << (out_of_time ? "the time limit ran out" : "interrupted") << " while following the boundary's motion in steps, at "
            << percent(done) << " of it; the mesh handed back is the first run's (" << first_run.after.inverted
            << " inverted)";
    } else if (first_better) {
        std::copy(first.begin(), first.end(), xyz().begin());
        last = first_run;
        why << "one run untangled the whole motion; following it in steps (" << percent(done)
            << " of it followed) did no better; that run: " << first_run.message;
    } else if (done == 1.0) {
        why << "the boundary's motion followed in " << steps << " step" << (steps == 1 ? "" : "s")
            << " (in one, the worst element fell below half of the reference's, or stayed inverted); last step: "
            << last.message;
    } else {
        // The boundary where it was given, from the furthest valid step; with none, the first
        // run's untangling goes on with the whole budget.
        const double seconds = seconds_left();
        const bool runs_again = max_seconds == 0.0 || seconds > 0.0;
        if (runs_again) {
            if (done > 0.0) {
                place(xyz(), valid, reference, given, driven, 1.0);
                carry_free_vertices(part, driven, valid, xyz());
            } else {
                std::copy(first.begin(), first.end(), xyz().begin());
            }
            last = run(seconds, MotionRunKind::Last);
            add_work(total, last);
        }
        if (!runs_again || last.after.inverted >= first_run.after.inverted) {
            std::copy(first.begin(), first.end(), xyz().begin());
            last = first_run;
        }
        why << "the boundary's motion cannot be followed without remeshing: the furthest valid mesh is at "
            << percent(done) << " of it, and steps down to " << percent(smallest_fraction)
            << " of the motion beyond it left inverted elements; " << last.after.inverted << " remain";
    }
    const bool followed = first_better || done == 1.0;
    total.reason = interrupted ? TerminationReason::Interrupted
                   : out_of_time                                  ? TerminationReason::TimeLimit
                   : followed                                     ? last.reason
                                                                  : TerminationReason::CannotUntangle;
    total.message = why.str();
    total.after = last.after;
    total.worst_after = last.worst_after;
    total.boundary = last.boundary;
    return followed && !interrupted && !out_of_time ? ended(std::move(total)) : total;
}

}  // namespace paloverde::detail
