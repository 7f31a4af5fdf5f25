#pragma once
// What a solver run did and why it stopped, in the spirit of Ceres' Solver::Summary.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "paloverde/assess/quality_assessor.hpp"

namespace paloverde {

enum class TerminationReason {
    TargetReached,       // the worst quality reached the requested target
    Converged,           // the worst quality stopped rising (relative progress below tolerance)
    GradientVanished,    // the objective's gradient is (relatively) zero
    NoImprovingStep,     // no step along the search direction improves without harming the worst element
    IterationLimit,
    TimeLimit,
    CannotUntangle,      // inverted elements remain that moving the free vertices did not fix
    NothingToMove,       // no free vertex, or no element with one
    Interrupted,         // a stop was requested (stop.hpp: Ctrl-C, SIGTERM); ended on the best iterate
    NumericalFailure,    // the objective, its gradient or a quality became NaN or infinite; ended on the best iterate
};

std::string_view to_string(TerminationReason reason);

struct IterationRecord {
    int iteration = 0;
    std::string phase;  // "untangle", "shape", or "slide" (the shape sweeps of a sliding boundary)
    double worst_quality = 0.0;       // of this iterate
    double best_worst_quality = 0.0;  // of the best iterate so far: what the phase hands back
    double mean_quality = 0.0;
    long inverted = 0;   // elements with a non-positive quality in this phase's metric
    double mu = 0.0, t = 0.0;
    double objective = 0.0;
    double step = 0.0;   // largest vertex displacement of the accepted step, over the reference length
    double gain = 0.0;   // how much the accepted step raised the objective (0: no step)
    long moved = 0;      // vertices moved one at a time (local solvers); the focus's free vertices (global, focus_band < 1)
    double seconds = 0.0;
};

// With sliding boundary vertices (boundary: slide): how far the boundary moved, measured on
// the mesh handed back, against the input's boundary.
struct BoundaryMotion {
    long sliding = 0;  // boundary vertices that may slide (on a surface patch or a feature curve)
    long moved = 0;    // of them, those that moved
    // Largest distance of a boundary vertex from the input's boundary triangulation, over the
    // input's bounding-box diagonal: 0 up to rounding when every move stayed on the surface.
    double largest_distance = 0.0;
    double volume_before = 0.0, volume_after = 0.0;  // the mesh's volume (area for triangles)
};

struct Summary {
    std::string solver;
    TerminationReason reason = TerminationReason::NothingToMove;
    std::string message;   // why, in a sentence a user can act on
    int iterations = 0;    // all phases
    int untangle_iterations = 0;
    long quality_passes = 0;   // evaluations of every element's quality
    long gradient_passes = 0;  // evaluations of the whole gradient
    double seconds = 0.0;
    std::string quality_metric;       // the metric worst_* refer to
    // Over elements with a free vertex; with a sliding boundary (its two runs free different
    // vertices) over every element.
    double worst_before = 0.0, worst_after = 0.0;
    // The counts, and the statistics of the solver's metric and the aspect ratio (QualityAssessor has
    // every metric, for a full report of the mesh).
    QualityReport before, after;
    std::vector<IterationRecord> history;
    std::optional<BoundaryMotion> boundary;  // runs with sliding boundary vertices only

    // The mesh handed back has no inverted element (decided exactly).
    bool valid() const { return after.inverted == 0; }
    // Valid, and stopped for a reason that is not a failure (nor an interruption).
    bool success() const;

    std::string brief_report() const;
    std::string full_report() const;
    std::string history_csv() const;
    std::string to_json() const;
};

}  // namespace paloverde
