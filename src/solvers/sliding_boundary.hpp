#pragma once
// Boundary vertices that slide on the input's boundary (boundary: slide, issue 17). A solver
// that slides its boundary runs twice: the ordinary run with the boundary fixed (untangling and
// shape), then a shape run from its result in which the sliding vertices move too
// (`release()` gives them 2 degrees of freedom on a surface patch, 1 on a feature curve
// (Mesh::degrees_of_freedom), so that colorings, movable elements and reports count them like any
// free vertex and a solver knows them by Mesh::slides(); it keeps each such vertex's moves on its
// patch or curve with tangent() and project()). No run lowers the worst element, so the result is
// never below the boundary-fixed run's; join() makes one Summary of the two.
//
// Which vertices slide: every boundary vertex on a patch or a curve (mesh/boundary_surface.hpp;
// corners stay). When the fixed flags are exactly the boundary (the default, and Mesquite files'
// `fixed` fields) that is all of them; a `fixed` field that marks anything else is the user's
// choice, and the boundary vertices it fixes stay where they are.
//
// A part of a distributed run slides on the whole mesh's boundary (gathered on every rank; the
// faces where the part was cut are not boundary), so a vertex slides, and projects, exactly as
// it would serially. An owner and its ghosts project the same point the same way.
#include <functional>
#include <optional>
#include <span>
#include <vector>

#include "paloverde/mesh/boundary_surface.hpp"
#include "paloverde/parallel/mesh_part.hpp"
#include "paloverde/solvers/checkpoint.hpp"
#include "paloverde/solvers/summary.hpp"
#include "paloverde/solvers/termination.hpp"
#include "checkpointer.hpp"
#include "vertex_slide.hpp"

namespace paloverde::detail {

// What surface meshes do not go with yet (OptionError): a reference mesh or a displacement.
void refuse_on_surfaces(const MeshPart& part);

// Refuses an analytic domain (SurfaceOptions::domain) that does not go with the mesh (OptionError),
// and a planar mesh off its plane domain (MeshError naming the vertex farthest off). A surface
// mesh, and a tetrahedral mesh whose boundary slides, are checked as their surface is built.
// Collective.
void check_domain(const MeshPart& part, const SurfaceDomain& domain, bool boundary_slides);

// The boundary-fixed run's share of the shape budget `termination`: half its iterations and
// seconds, so that a run which would use them all (a focused global run creeping up) still
// leaves the sliding run its turn.
TerminationCriterion fixed_run_budget(const TerminationCriterion& termination);
// What the boundary-fixed run `fixed` left of the shape phase's budget `termination` for the
// sliding run: none when it spent it, or ended where sliding does not go on from (an element
// inverted or degenerate, interrupted, at its target); a spent budget is then noted in
// fixed.message. The seconds spent are the slowest process's (`reducer`), so that every process
// decides alike.
std::optional<TerminationCriterion> sliding_budget(const TerminationCriterion& termination, Summary& fixed,
                                                   const Reducer& reducer);

class SlidingBoundary final : public VertexSlide {
public:
    // From the input mesh or a rank's part of it, at its own scale (before any run moves or
    // rescales it). Collective. A surface mesh slides on itself: see
    // slide_on_surface(); `open_edges_slide` says whether its open edges' vertices slide too.
    SlidingBoundary(MeshPart part, const SurfaceOptions& options, bool open_edges_slide = false);
    ~SlidingBoundary();  // gives the mesh its fixed flags back (and clears a surface's normals)
    // Gives the vertices that slide their degrees of freedom (2 or 1), until destruction.
    void release();
    SlidingBoundary(const SlidingBoundary&) = delete;
    SlidingBoundary& operator=(const SlidingBoundary&) = delete;

    // The run works at unit scale: the input's coordinates times 2^exponent (exact).
    void set_scale_exponent(int exponent) { exponent_ = exponent; }
    // At unit scale: the part of a move that stays on v's patch or curve to first order, and the
    // point of v's patch or curve nearest to p.
    Vec3 tangent(VertexId v, const Vec3& d) const override { return surface_.tangent(v, d); }
    Vec3 project(VertexId v, const Vec3& p) const override;
    // What the runs did to the boundary, from the mesh handed back (at the input's scale), over
    // the whole mesh. Collective.
    BoundaryMotion motion() const;
    // One Summary of the boundary-fixed run and the sliding one (`slid`; none when the fixed run
    // left nothing to slide or no budget). Worst qualities are over every element: the two runs
    // free different vertices, and neither lowers the smallest quality of all.
    Summary join(Summary fixed, std::optional<Summary> slid) const;

private:
    void slide_on_surface(bool open_edges_slide);
    void turn_targets_to(std::span<const Vec3> normals);  // a surface's targets, to its elements' normals

    MeshPart part_;
    Mesh& mesh_;
    BoundarySurface surface_;
    std::vector<std::uint8_t> fixed_;   // the flags the mesh had, given back at the end
    std::vector<std::uint8_t> released_;  // the degrees of freedom while the boundary slides
    std::vector<std::uint8_t> slides_;  // per vertex: it slides once released
    std::vector<double> input_;         // the input's coordinates
    double volume_before_ = 0.0;
    int exponent_ = 0;
    bool normals_set_ = false;  // the mesh's surface normals are this run's (Mesh::surface_normals)
};

// One run of a solver, its shape budget `budget`, with its vertices sliding (`sliding`) or the
// boundary fixed (nullptr), and `checkpoint` for its own checkpoints.
using SlidingRun = std::function<Summary(const TerminationCriterion& budget, SlidingBoundary* sliding,
                                         const CheckpointOptions& checkpoint)>;

// A solver's boundary: slide run on `part`: `run(termination, nullptr, ...)` with the boundary
// fixed on half the budget, then, where it leaves budget and a valid mesh (and `slide` is true: a
// run that improves shapes at all), `run(termination left, &sliding, ...)` with the boundary
// vertices released; one Summary of the two. With a checkpoint file FILE (`checkpoints`), which
// run is under way is written there before each (before the sliding one, with the fixed run's
// outcome and mesh), and the run writes its own to FILE.run (RunCheckpoints); resumed, it goes on
// in the run it was written before and ends as the uninterrupted run, bit for bit. Collective.
Summary fixed_then_sliding(MeshPart part, const SurfaceOptions& surface, const TerminationCriterion& termination,
                           bool slide, const CheckpointSettings& checkpoints, const SlidingRun& run);

// Whether `part` is a surface mesh: triangles in 3D that do not lie in one plane. Collective.
bool is_surface_mesh(const MeshPart& part);
// A surface mesh's normals as its solvers rate it about (Mesh::surface_normals; the default
// feature angle), from the mesh as it is: a report's, so that the triangles the input turned
// over count as inverted. Collective: a part's come from the whole surface.
std::vector<Vec3> input_surface_normals(const MeshPart& part);

// A solver's run on a surface mesh: one shape run, `run(&sliding)`, in which every vertex that is
// not fixed slides on the input surface (on its patch, along its crease or, where
// `open_edges_slide`, along its open edge; corners stay), each triangle rated about the surface's
// normal. Without a moved boundary (OptionError, naming what to drop); the run's checkpoints are
// its own, as a single run's. The Summary reports the motion. Collective: a part slides on the
// whole surface.
template <class Run>
Summary on_surface(MeshPart part, const SurfaceOptions& surface, bool open_edges_slide, Run run) {
    refuse_on_surfaces(part);
    SlidingBoundary sliding(part, surface, open_edges_slide);
    sliding.release();
    Summary summary = run(&sliding);
    summary.boundary = sliding.motion();
    return summary;
}

}  // namespace paloverde::detail
