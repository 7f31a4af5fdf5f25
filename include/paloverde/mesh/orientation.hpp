#pragma once
// Whether an element is inverted is decided exactly (CGAL's filtered predicates), never by a
// floating-point volume compared with a threshold: a sign decides, so the sign must be right.
#include <cstdint>
#include <span>
#include <vector>

#include "paloverde/mesh/simplex_mesh.hpp"

namespace paloverde {

// +1 positively oriented, 0 degenerate (flat), -1 inverted. Triangles are oriented by the mesh's
// plane normal; in a non-planar surface mesh they are +1 unless degenerate.
int element_orientation(const SimplexMesh& mesh, std::span<const double> coordinates, ElementId element);

struct OrientationCounts {
    ElementId inverted = 0;
    ElementId degenerate = 0;
};
OrientationCounts count_orientations(const SimplexMesh& mesh, std::span<const double> coordinates);
inline OrientationCounts count_orientations(const SimplexMesh& mesh) {
    return count_orientations(mesh, mesh.coordinates());
}

}  // namespace paloverde
