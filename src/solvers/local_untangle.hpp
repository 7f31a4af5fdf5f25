#pragma once
// Local untangling of one vertex (Freitag & Plassmann): move the vertex, its neighbours held
// still, to where the smallest signed volume of its elements is largest. Signed volume is linear
// in the vertex's position, so this is a small linear program (3 unknowns and the minimum; 2
// for planar triangles), solved here by a primal barrier method with Newton steps.
#include <span>

#include "paloverde/mesh/simplex_mesh.hpp"
#include "paloverde/metrics/quality_metric.hpp"

namespace paloverde::detail {

struct VertexUntangle {
    double before = 0.0;  // smallest scaled volume of the vertex's elements, before
    double after = 0.0;   // and at the new position (== before if not moved)
    bool moved = false;
};

// Moves vertex v in xyz only if afterwards every one of its elements has positive volume, so a
// valid element is never inverted. `scale` gives the plane of triangle meshes and the volume
// unit (scaled_volume).
VertexUntangle untangle_vertex(const SimplexMesh& mesh, std::span<double> xyz, VertexId v, const MetricScale& scale);

}  // namespace paloverde::detail
