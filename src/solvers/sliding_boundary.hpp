#pragma once
// Boundary vertices that slide on the input's boundary (boundary: slide, issue 17) for one solver
// run. While it lives, the mesh's fixed flags free the vertices that slide, so that colorings,
// movable elements and reports count them like any free vertex; a solver then keeps each such
// vertex's moves on its surface patch or feature curve with tangent() and project().
//
// Which vertices slide: every boundary vertex on a patch or a curve (mesh/boundary_surface.hpp;
// corners stay). When the fixed flags are exactly the boundary (the default, and Mesquite files'
// `fixed` fields) that is all of them; a `fixed` field that marks anything else is the user's
// choice, and the boundary vertices it fixes stay where they are.
#include <span>
#include <vector>

#include "paloverde/mesh/boundary_surface.hpp"
#include "paloverde/solvers/summary.hpp"

namespace paloverde::detail {

class SlidingBoundary {
public:
    // From the mesh at the input's scale, before the run rescales it.
    SlidingBoundary(SimplexMesh& mesh, const SurfaceOptions& options);
    ~SlidingBoundary();  // gives the mesh its fixed flags back
    SlidingBoundary(const SlidingBoundary&) = delete;
    SlidingBoundary& operator=(const SlidingBoundary&) = delete;

    // The run works at unit scale: the input's coordinates times 2^exponent (exact).
    void set_scale_exponent(int exponent) { exponent_ = exponent; }
    bool slides(VertexId v) const { return slides_[static_cast<std::size_t>(v)] != 0; }
    // At unit scale: the part of a move that stays on v's patch or curve to first order, and the
    // point of v's patch or curve nearest to p.
    Vec3 tangent(VertexId v, const Vec3& d) const { return surface_.tangent(v, d); }
    Vec3 project(VertexId v, const Vec3& p) const;
    // What the run did to the boundary, from the mesh handed back (at the input's scale).
    BoundaryMotion motion() const;

private:
    SimplexMesh& mesh_;
    BoundarySurface surface_;
    std::vector<std::uint8_t> fixed_;   // the flags the mesh had, given back at the end
    std::vector<std::uint8_t> slides_;  // per vertex
    std::vector<double> input_;         // the input's coordinates
    double volume_before_ = 0.0;
    int exponent_ = 0;
};

}  // namespace paloverde::detail
