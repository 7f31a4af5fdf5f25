#pragma once
// Whether an element is inverted is decided exactly (CGAL's filtered predicates), never by a
// floating-point volume compared with a threshold: a sign decides, so the sign must be right.
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "paloverde/core/exact_sum.hpp"
#include "paloverde/mesh/mesh.hpp"

namespace paloverde {

// +1 positively oriented, 0 degenerate (flat), -1 inverted. Triangles are oriented by the mesh's
// plane normal; in a non-planar surface mesh they are +1 unless degenerate.
int element_orientation(const Mesh& mesh, std::span<const double> coordinates, ElementId element);
// element_orientation() of the elements first..last-1, into out[0..last-first): the same answers,
// a mesh of tetrahedra's filtered a block at a time.
void element_orientations(const Mesh& mesh, std::span<const double> coordinates, ElementId first, ElementId last,
                          std::int8_t* out);

// Cells, for a mesh with cells: inverted when any corner is, degenerate when none is and one is flat.
struct OrientationCounts {
    ElementId inverted = 0;
    ElementId degenerate = 0;
};
OrientationCounts count_orientations(const Mesh& mesh, std::span<const double> coordinates);
inline OrientationCounts count_orientations(const Mesh& mesh) {
    return count_orientations(mesh, mesh.coordinates());
}

// The orientation convention of a file. Some tools write a tetrahedron with two corners in the
// other order than Paloverde's (positive volume: corner 3 on the positive side of corners 0, 1,
// 2), so that every valid element reads as inverted. Which convention a file uses is told by the
// total signed volume of its elements rather than by counting: moving interior vertices leaves the
// total equal to the volume the boundary encloses, however tangled the interior, while a count
// follows the tangle (docs/cli.md, "Orientation of the input").
enum class OrientationMode {
    Auto,     // flip the elements when their total signed volume is negative
    AsIs,     // take the file's order
    Flipped   // flip every element, whatever the total
};
std::string_view to_string(OrientationMode mode);  // "auto", "as_is", "flipped"

// Sums over elements of their signed measure (volume of a tet, area of a planar triangle about the
// plane normal), at unit scale 2^scale_exponent, as exact sums that add across processes.
// `total` adds the measures rounded to doubles, `magnitude` their absolute values, and `rounding`
// a bound on the rounding error of each (orient3d/orient2d's static filter): the exact total
// has the sign of `total` whenever |total| > rounding.
struct SignedMeasure {
    ExactSum total, magnitude, rounding;
};
// Over the elements with counted[e] != 0, or all when `counted` is empty. Triangles are measured
// as element_orientation() orients them: projected on the coordinate plane most aligned with
// `plane_normal`, flipped if the normal points down that axis.
SignedMeasure signed_measure(const Mesh& mesh, std::span<const double> xyz, int scale_exponent,
                             const Vec3& plane_normal, std::span<const std::uint8_t> counted = {});

struct OrientationDecision {
    OrientationMode mode = OrientationMode::Auto;
    bool oriented = true;  // false for triangles not in one plane: they have no orientation
    int sign = 0;          // of the file's total signed measure: +1, -1, 0 (zero within rounding, or not oriented)
    double share = 0.0;    // that total over the sum of absolute measures, in [-1, 1]
    bool flipped = false;  // the elements are held flipped (flip_elements())
    // One line for reports: what was done and why.
    std::string describe(ElementKind kind) const;
};
// The decision from the whole mesh's sums (summed over every process).
OrientationDecision decide_orientation(OrientationMode mode, bool oriented, const SignedMeasure& measure);

// Decides for a whole mesh as read from a file and, when the decision is to flip, flips its
// elements and marks them flipped (Mesh::elements_flipped()), so writers restore the
// file's order. A planar triangle mesh is measured about its own plane normal, which is already
// the area-weighted one: its total is never negative, so `auto` keeps it.
OrientationDecision orient(Mesh& mesh, OrientationMode mode);

}  // namespace paloverde
