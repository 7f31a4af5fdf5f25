#pragma once
// Laplacian smoothing: each free vertex moves to the mean of its neighbours. Smart Laplace (the
// default) takes such a move only if the vertex's worst element does not get worse and no valid
// element inverts, so it keeps the Solver guarantee. Plain Laplace moves every free vertex at
// once (Jacobi) and may invert elements: it is the one solver that does not hand back the input
// when the result is worse; its Summary::message says how many elements it inverted.
#include <string>

#include "paloverde/metrics/quality_metric.hpp"
#include "paloverde/solvers/solver.hpp"
#include "paloverde/solvers/termination.hpp"
#include "paloverde/solvers/vertex_coloring.hpp"

namespace paloverde {

struct LaplaceSolverOptions {
    bool smart = true;
    std::string metric = "aspect_ratio";  // what smart Laplace protects and the Summary reports
    MetricOptions metric_options;
    // An iteration is a sweep. Here min_progress is a distance, not the other solvers' relative
    // rise of the worst quality: the sweeps stop once no vertex moved more than min_progress
    // times the mean edge length in one (progress_window is not read). Plain Laplace may lower the
    // worst quality while it settles, so how far the vertices still move is what says it has.
    TerminationCriterion termination = [] {
        TerminationCriterion c;
        c.max_iterations = 100;
        return c;
    }();
    ColoringOrder coloring = ColoringOrder::SmallestLast;  // smart Laplace moves one color at a time
    int threads = 0;  // 0: OpenMP's default; results do not depend on it

    void validate() const;  // throws OptionError naming the field
};

class LaplaceSolver final : public Solver {
public:
    explicit LaplaceSolver(LaplaceSolverOptions options = {});
    std::string_view name() const override { return options_.smart ? "smart_laplace" : "laplace"; }
    // Serial only: a part of a DistributedMesh is an OptionError (on every rank).
    Summary improve(MeshPart part) override;

private:
    LaplaceSolverOptions options_;
};

}  // namespace paloverde
