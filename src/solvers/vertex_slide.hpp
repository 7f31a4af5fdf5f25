#pragma once
// Where a vertex that slides may go (boundary: slide, surface meshes), in the numbering of the
// mesh a solver works on: what local moves (untangling a vertex, its energy's Newton steps) need
// of a SlidingBoundary, which speaks the caller's ids, or of the workspace's SlidingVertices.
#include "paloverde/core/types.hpp"

namespace paloverde::detail {

class VertexSlide {
public:
    // The part of a move d of vertex v that stays on its patch or curve to first order.
    virtual Vec3 tangent(VertexId v, const Vec3& d) const = 0;
    // The point of v's patch or curve nearest to p.
    virtual Vec3 project(VertexId v, const Vec3& p) const = 0;

protected:
    ~VertexSlide() = default;
};

}  // namespace paloverde::detail
