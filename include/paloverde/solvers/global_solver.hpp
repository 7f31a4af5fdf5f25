#pragma once
// The global solver: all free vertices move together along one search direction of an
// objective over the whole mesh (by default the log-barrier of Sastry & Shontz). A tangled mesh
// is first untangled with the hybrid volume/shape metric; once every element is valid the
// shape metric takes over and no element is ever allowed to invert again.
#include <string>

#include "paloverde/metrics/quality_metric.hpp"
#include "paloverde/objectives/objective_function.hpp"
#include "paloverde/solvers/solver.hpp"
#include "paloverde/solvers/termination.hpp"

namespace paloverde {

struct GlobalSolverOptions {
    enum class Direction { SteepestAscent, ConjugateGradient };
    Direction direction = Direction::ConjugateGradient;
    std::string objective = "log_barrier";
    ObjectiveOptions objective_options;
    std::string shape_metric = "aspect_ratio";
    MetricOptions metric_options;
    bool untangle = true;             // untangle first when movable elements are inverted
    bool improve_shape = true;        // run the shape phase
    TerminationCriterion termination; // shape phase
    TerminationCriterion untangle_termination = TerminationCriterion::for_untangling();
    int steps_per_mu = 3;             // steps at one mu before it shrinks
    int max_failed_searches = 8;      // line searches in a row without a step before giving up
    bool renumber = true;             // reverse Cuthill-McKee order while solving
    int threads = 0;                  // 0: OpenMP's default; results do not depend on it

    void validate() const;  // throws OptionError
};

class GlobalSolver final : public Solver {
public:
    explicit GlobalSolver(GlobalSolverOptions options = {});
    std::string_view name() const override { return "global"; }
    Summary improve(SimplexMesh& mesh) override;

private:
    GlobalSolverOptions options_;
};

}  // namespace paloverde
