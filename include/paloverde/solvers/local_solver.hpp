#pragma once
// The local smoother (Freitag & Plassmann), the baseline the global solver is compared with. One
// sweep visits every free vertex once, one color at a time; a vertex moves to raise the smallest
// quality of its own elements with its neighbours held still. Vertices of one color share no
// element, so they move in parallel and the result does not depend on the thread count.
// A tangled mesh is first untangled by the same sweeps near inverted elements, each vertex
// lowering the regularized energy of its elements (or raising their smallest signed volume).
#include <string>

#include "paloverde/mesh/boundary_surface.hpp"
#include "paloverde/metrics/quality_metric.hpp"
#include "paloverde/solvers/checkpoint.hpp"
#include "paloverde/solvers/solver.hpp"
#include "paloverde/solvers/termination.hpp"
#include "paloverde/solvers/vertex_coloring.hpp"

namespace paloverde {

namespace detail {
class SolverRun;
class Checkpointer;
class SlidingBoundary;
}

struct LocalSolverOptions {
    std::string metric = "aspect_ratio";
    MetricOptions metric_options;
    bool untangle = true;
    bool improve_shape = true;         // false: stop once no element is inverted (no shape sweeps)
    // How a vertex of an inverted element moves while untangling. Energy: to the minimum of the
    // regularized energy of its elements (the per-vertex form of the global solver's; epsilon
    // shrinks between sweeps; docs/local_solver.md). Volume: to where the smallest signed volume
    // of its elements is largest (a small linear program), else up the smallest volume.
    enum class Untangling { Energy, Volume };
    Untangling untangling = Untangling::Energy;
    TerminationCriterion termination;  // shape sweeps (an iteration is a sweep)
    TerminationCriterion untangle_termination = TerminationCriterion::for_untangling();
    ColoringOrder coloring = ColoringOrder::SmallestLast;
    int ascent_steps = 4;            // ascent steps per vertex visit
    // Elements whose quality is within this fraction of the patch minimum are active: the
    // direction must raise all of them.
    double active_tolerance = 1e-3;
    // In the shape sweeps only vertices whose worst element lies in the lowest band of qualities
    // move: below worst + improve_below * (ideal - worst), worst over the whole mesh. Max-min
    // moves trade a patch's good elements for its worst one, so moving every vertex lowers the
    // mean quality (by about a tenth) for no gain in the worst; 1 or more moves them all.
    double improve_below = 0.1;
    // Boundary vertices: fixed (the fixed flags decide), or slide: after the run with the
    // boundary fixed, shape sweeps in which they move on the input's boundary, along feature
    // curves, corners fixed (mesh/boundary_surface.hpp; docs/local_solver.md). Checkpoints too
    // (checkpoint.hpp).
    enum class Boundary { Fixed, Slide };
    Boundary boundary = Boundary::Fixed;
    SurfaceOptions surface;          // with slide: the feature angle
    int threads = 0;                 // 0: OpenMP's default; results do not depend on it
    // Morphing (Mesh::reference_coordinates): when the mesh as it is does not untangle, the
    // boundary's motion is followed from the reference in steps, halved down to this fraction of
    // the whole motion before giving up; in (0, 1].
    double smallest_motion_step = 1.0 / 64.0;
    CheckpointOptions checkpoint;    // periodic checkpoints (at sweep boundaries), resuming

    void validate() const;  // throws OptionError naming the field
};

class LocalSolver final : public Solver {
public:
    explicit LocalSolver(LocalSolverOptions options = {});
    std::string_view name() const override { return "local"; }
    // Summary::message ends with the number of colors, e.g. "(12 colors)".
    // On a distributed part each rank moves the vertices it owns; the coloring is global, and
    // after each color the ghosts take their owners' new positions. (Not bitwise the serial
    // result: the coloring differs from the serial smallest-last one.)
    Summary improve(MeshPart part) override;

private:
    Summary run_once(MeshPart whole_or_part);  // without following a boundary motion in steps
    // What a sweep needs of the mesh: the elements whose statistics this process counts, the
    // reductions and ghost updates (no-ops serially), the colors of the vertices it moves.
    struct Domain {
        const Mesh& mesh;
        std::vector<ElementId> counted_movable;
        const Reducer& reducer;
        const Halo& halo;
        VertexColoring coloring;
        MetricScale scale;
    };
    // The run on the part, with the boundary sliding (`sliding`) or not (nullptr).
    // `shared`: the run's reports, for the solver's one run (Solver::shared_reports).
    Summary improve_part(MeshPart whole_or_part, detail::SlidingBoundary* sliding, SharedReports shared = {});
    Summary sweep_colors(detail::SolverRun& run, const Domain& domain, detail::Checkpointer& checkpointer,
                         const detail::SlidingBoundary* sliding = nullptr);

    LocalSolverOptions options_;
};

}  // namespace paloverde
