#pragma once
// When a solver phase stops. Every test is relative or dimensionless, so a mesh scaled by 1e-4
// or 1e4 stops at the same iteration.
#include <optional>

namespace paloverde {

struct TerminationCriterion {
    int max_iterations = 500;
    double max_seconds = 0.0;                     // 0: no time limit
    std::optional<double> target_worst_quality;   // stop once the worst quality reaches it
    // Stop when the worst quality rose by less than this (relative to its magnitude, at least
    // 1e-3 in absolute terms) over the last `progress_window` iterations. Laplace reads it as a
    // distance (laplace_solver.hpp).
    double min_progress = 1e-6;
    int progress_window = 10;
    // Stop when the gradient norm falls below this fraction of its first value (the global
    // solver's; the local and Laplace sweeps have no whole gradient and do not read it).
    double gradient_tolerance = 1e-12;

    void validate() const;  // throws OptionError naming the field

    // Untangling moves through many small steps while the worst element inches up: a longer
    // budget and a wider progress window.
    static TerminationCriterion for_untangling() {
        TerminationCriterion c;
        c.max_iterations = 500;
        c.progress_window = 25;
        return c;
    }
};

}  // namespace paloverde
