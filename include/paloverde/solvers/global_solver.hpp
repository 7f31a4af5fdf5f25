#pragma once
// The global solver: all free vertices move together along one search direction of an
// objective over the whole mesh (by default the log-barrier of Sastry & Shontz). A tangled mesh
// is first untangled (the regularized energy of Garanzha et al., then where needed the barrier
// ascent on the hybrid volume/shape metric); once every element is valid the shape metric takes
// over and no element is ever allowed to invert again. A stop request
// (stop.hpp) or a NaN ends the run on its best iterate.
#include <string>

#include "paloverde/mesh/boundary_surface.hpp"
#include "paloverde/metrics/quality_metric.hpp"
#include "paloverde/objectives/objective_function.hpp"
#include "paloverde/solvers/checkpoint.hpp"
#include "paloverde/solvers/solver.hpp"
#include "paloverde/solvers/termination.hpp"

namespace paloverde {

struct GlobalSolverOptions {
    // Newton: truncated Newton steps in the shape phase (docs/global_solver.md), mu shrinking once
    // the barrier's subproblem is solved rather than after steps_per_mu steps; log_barrier only.
    // Untangling keeps conjugate gradients.
    enum class Direction { SteepestAscent, ConjugateGradient, Newton };
    Direction direction = Direction::ConjugateGradient;
    std::string objective = "log_barrier";
    ObjectiveOptions objective_options;
    std::string shape_metric = "aspect_ratio";
    MetricOptions metric_options;
    bool untangle = true;             // untangle first when movable elements are inverted
    // Energy: minimize the regularized untangling energy first (docs/global_solver.md), and go on
    // with the barrier ascent where it leaves elements inverted. Barrier: the ascent alone.
    enum class Untangling { Energy, Barrier };
    Untangling untangling = Untangling::Energy;
    bool improve_shape = true;        // run the shape phase
    TerminationCriterion termination; // shape phase
    TerminationCriterion untangle_termination = TerminationCriterion::for_untangling();
    // While untangling, scale each vertex's move by the inverse of its 3x3 block of the
    // objective's curvature (block-Jacobi preconditioning): inverted elements of very different
    // sizes and barrier weights then all make progress. (In the shape phase it measured worse.)
    bool precondition_untangling = true;
    // When the barrier ascent stalls with elements still inverted: rounds of local vertex
    // untangling (then the ascent resumes). 0 keeps untangling purely global.
    int local_untangle_rounds = 5;
    // Shape phase: mu shrinks once an accepted step gains less than gain_tolerance * mu (the
    // barrier's subproblem nearly solved), after at least steps_per_mu steps at one mu; also
    // when one mu held through three progress windows while the worst quality stood still (as
    // long as the last such shrink paid), and after a progress window of steps in which the worst
    // element held under 1% of the barrier's weight (on the phase's first mu only while the worst
    // also stood farther above t than where the phase began). Untangling, and the shape phase with
    // gain_tolerance 0: after steps_per_mu steps.
    // Newton has its own rule (newton_tolerance).
    double gain_tolerance = 0.1;
    int steps_per_mu = 5;
    // Shape phase: iterate on the vertices of the elements whose quality lies in this lowest
    // fraction of worst..ideal and on their neighbours (with every element around them); the rest
    // stand still until the worst has climbed half way up the band, when the focus is chosen
    // anew, or the focus stalls, when the Newton finish takes over (finish: none: it is widened,
    // twice the band, while widening pays). Terms of elements far above the worst weigh almost
    // nothing in the barrier, and skipping them makes an iteration cost what the focus costs, not
    // the whole mesh. 1: the whole mesh (and always with direction newton, whose directions from
    // the start measured worse on a focus; the finish focuses).
    double focus_band = 0.03;
    // The Newton finish's band, as a fraction of focus_band (< 1: with 1 nothing focuses), in
    // (0, 1]. Where the conjugate gradients stall the qualities have piled up above the worst, and
    // the whole band holds far more vertices than the few worst elements the Newton steps work on:
    // a third of it makes the finish's steps far cheaper on a large mesh, to the same result
    // (docs/global_solver.md, "The Newton finish").
    double finish_band = 1.0 / 3.0;
    // Newton: mu shrinks once gradient . direction (the Newton decrement squared) falls below
    // newton_tolerance * mu; each direction takes at most newton_cg_iterations Hessian products.
    double newton_tolerance = 0.1;
    int newton_cg_iterations = 100;
    // When the shape phase's conjugate gradients stall, or creep (their worst quality and t rose
    // by less than 100 times min_progress over three progress windows, or 1000 times where their
    // steps gained less than a mu each): Newton finishes from
    // their best iterate, on a focus, with a fresh barrier (newton_tolerance and
    // newton_cg_iterations as above), until it stalls too or the budget runs out. Only with
    // log_barrier (its curvature), not while the boundary slides (the surface's constraint is not
    // in its Hessian).
    enum class Finish { None, Newton };
    Finish finish = Finish::Newton;
    // The mean's polish, after the shape phases (and the finish): the barrier raises the worst
    // element partly at the expense of the rest, and may leave the mean quality below the
    // input's. The polish holds still every vertex of an element within 3% of worst..ideal of
    // the worst quality and raises the sum of the other elements' qualities, each kept above
    // that line (MeanAboveFloor): the worst element and every element near it keep their
    // qualities bit for bit. auto: where the mean fell below the input's, until it is above it
    // again (the first step or two: the polish costs little), and as always where elements are
    // rated in a target's metric (there the max-min leaves thin elements tilted) or on a surface
    // mesh (its worst triangle, between creases, often cannot rise at all); always: until
    // the mean stops rising; off. It counts against the same budget.
    enum class Polish { Off, Auto, Always };
    Polish polish = Polish::Auto;
    // Shape phase (log_barrier, not the finish): a vertex the line search damped so that no element
    // blocks is damped further while its own elements' barrier terms are lower at the trial than
    // at the iterate. The bulk keeps its long steps; the vertices by the worst elements stop
    // giving their neighbourhood away (docs/global_solver.md, "Damped vertices ascend").
    bool damped_vertex_ascent = true;
    int max_failed_searches = 8;      // line searches in a row without a step before giving up
    bool renumber = true;             // reverse Cuthill-McKee order while solving
    // Boundary vertices: fixed (the fixed flags decide), or slide: after the run with the boundary
    // fixed, a shape phase in which they move too, on the input's boundary, along feature curves,
    // corners fixed (mesh/boundary_surface.hpp; docs/global_solver.md). Serial and distributed
    // runs alike (a part slides on the whole mesh's boundary), checkpoints too; no newton
    // directions, no Newton finish.
    enum class Boundary { Fixed, Slide };
    Boundary boundary = Boundary::Fixed;
    SurfaceOptions surface;           // with slide: the feature angle
    int threads = 0;                  // 0: OpenMP's default; results do not depend on it
    // Morphing (Mesh::reference_coordinates): when the mesh as it is does not untangle, the
    // boundary's motion is followed from the reference in steps, halved down to this fraction of
    // the whole motion before giving up; in (0, 1].
    double smallest_motion_step = 1.0 / 64.0;
    CheckpointOptions checkpoint;     // periodic checkpoints, resuming (checkpoint.hpp)

    void validate() const;  // throws OptionError
};

class GlobalSolver final : public Solver {
public:
    explicit GlobalSolver(GlobalSolverOptions options = {});
    std::string_view name() const override { return "global"; }
    // On a distributed part every rank moves the vertices it owns. The result equals the serial
    // run's on the whole mesh (with the default renumbering), except when the local untangling
    // fallback runs: it sweeps by hashed colors when distributed, in id order serially.
    Summary improve(MeshPart part) override;

private:
    Summary run_once(MeshPart part);  // without following a boundary motion in steps
    GlobalSolverOptions options_;
};

}  // namespace paloverde
