#include "boundary_motion.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include "paloverde/assess/quality_assessor.hpp"
#include "paloverde/core/error.hpp"

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

void refuse_checkpoints_of_motion(const CheckpointOptions& checkpoint) {
    if (!checkpoint.file.empty() || !checkpoint.resume.empty())
        throw OptionError("checkpoints are not kept for a mesh whose boundary moved from its reference (morphing): "
                          "its run may take several steps, and a checkpoint holds one run; run it without checkpoint.file "
                          "and checkpoint.resume");
}

Summary follow_boundary_motion(MeshPart part, double smallest_fraction, const std::function<Summary()>& solve) {
    Mesh& mesh = part.mesh();
    const auto xyz = mesh.coordinates();
    const std::vector<double> given(xyz.begin(), xyz.end());
    const std::vector<double> reference(mesh.reference_coordinates().begin(), mesh.reference_coordinates().end());
    Summary total = solve();
    if (total.reason == TerminationReason::Interrupted) return total;
    // A run is good enough when it keeps at least half the worst quality of where it started
    // from (the reference, then the last step): a run that loses more has left elements pressed
    // against the moved boundary, which smaller steps avoid.
    auto worst_at = [&](std::span<const double> at) {
        const std::vector<double> now(xyz.begin(), xyz.end());
        std::copy(at.begin(), at.end(), xyz.begin());
        const QualityReport r = QualityAssessor({total.quality_metric}).assess(part);
        std::copy(now.begin(), now.end(), xyz.begin());
        const MetricReport& m = r.metrics.front();
        return m.movable.count > 0 ? m.movable.min : m.all.min;
    };
    double floor = 0.5 * worst_at(reference);
    if (total.valid() && total.worst_after >= floor) return total;

    // The first run's result: kept if the steps do no better.
    const std::vector<double> first(xyz.begin(), xyz.end());
    const Summary first_run = total;
    const std::vector<std::uint8_t> driven = driven_vertices(mesh);
    std::vector<double> valid = reference;  // the furthest accepted step's mesh; the reference at fraction 0
    double done = 0.0, step = 0.5;
    int steps = 0;
    Summary last;
    while (done < 1.0 && step >= smallest_fraction) {
        const double next = std::min(1.0, done + step);
        place(xyz, valid, reference, given, driven, next);
        last = solve();
        add_work(total, last);
        if (last.reason == TerminationReason::Interrupted) break;
        // At the smallest step, any valid result goes on.
        if (last.valid() && (last.worst_after >= floor || step < 2.0 * smallest_fraction)) {
            valid.assign(xyz.begin(), xyz.end());
            done = next;
            ++steps;
            step *= 2.0;
            floor = 0.5 * last.worst_after;
        } else {
            step /= 2.0;
        }
    }
    std::ostringstream why;
    const bool first_better = first_run.valid() && (done < 1.0 || first_run.worst_after >= last.worst_after);
    if (last.reason == TerminationReason::Interrupted) {
        // A step's mesh has its boundary short of where it was given: the first run's has not.
        std::copy(first.begin(), first.end(), xyz.begin());
        last = first_run;
        why << "interrupted while following the boundary's motion in steps, at " << percent(done)
            << " of it; the mesh handed back is the first run's";
    } else if (first_better) {
        std::copy(first.begin(), first.end(), xyz.begin());
        last = first_run;
        why << "one run untangled the whole motion; following it in steps (" << percent(done)
            << " of it followed) did no better; that run: " << first_run.message;
    } else if (done == 1.0) {
        why << "the boundary's motion followed in " << steps << " step" << (steps == 1 ? "" : "s")
            << " (in one, the worst element fell below half of the reference's, or stayed inverted); last step: "
            << last.message;
    } else {
        // The boundary where it was given, from the furthest valid step.
        if (done > 0.0) {
            place(xyz, valid, reference, given, driven, 1.0);
            last = solve();
            add_work(total, last);
        }
        if (done == 0.0 || last.after.inverted >= first_run.after.inverted) {
            std::copy(first.begin(), first.end(), xyz.begin());
            last = first_run;
        }
        why << "the boundary's motion cannot be followed without remeshing: the furthest valid mesh is at "
            << percent(done) << " of it, and steps down to " << percent(smallest_fraction)
            << " of the motion beyond it left inverted elements; " << last.after.inverted << " remain";
    }
    const bool followed = first_better || done == 1.0;
    total.reason = last.reason == TerminationReason::Interrupted ? TerminationReason::Interrupted
                   : followed                                     ? last.reason
                                                                  : TerminationReason::CannotUntangle;
    total.message = why.str();
    total.after = last.after;
    total.worst_after = last.worst_after;
    total.boundary = last.boundary;
    return total;
}

}  // namespace paloverde::detail
