#include "paloverde/mesh/orientation.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <cmath>

namespace paloverde {

namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;

Kernel::Point_3 point3(std::span<const double> xyz, VertexId v) {
    const std::size_t i = 3 * static_cast<std::size_t>(v);
    return {xyz[i], xyz[i + 1], xyz[i + 2]};
}

// A planar mesh's triangles keep their orientation when projected onto the coordinate plane most
// aligned with the mesh plane, flipped if the normal points down that axis.
int planar_triangle_orientation(const SimplexMesh& mesh, std::span<const double> xyz, std::span<const VertexId> c) {
    const Vec3& n = mesh.plane_normal();
    int axis = 0;
    for (int i = 1; i < 3; ++i)
        if (std::abs(n[i]) > std::abs(n[axis])) axis = i;
    const int u = (axis + 1) % 3, w = (axis + 2) % 3;
    auto p = [&](VertexId v) {
        return Kernel::Point_2(xyz[3 * static_cast<std::size_t>(v) + u], xyz[3 * static_cast<std::size_t>(v) + w]);
    };
    const int sign = static_cast<int>(CGAL::orientation(p(c[0]), p(c[1]), p(c[2])));
    return n[axis] >= 0.0 ? sign : -sign;
}
}  // namespace

int element_orientation(const SimplexMesh& mesh, std::span<const double> xyz, ElementId element) {
    const auto c = mesh.element(element);
    if (mesh.kind() == ElementKind::Tetrahedron)
        return static_cast<int>(CGAL::orientation(point3(xyz, c[0]), point3(xyz, c[1]), point3(xyz, c[2]), point3(xyz, c[3])));
    if (mesh.is_planar()) return planar_triangle_orientation(mesh, xyz, c);
    return CGAL::collinear(point3(xyz, c[0]), point3(xyz, c[1]), point3(xyz, c[2])) ? 0 : 1;
}

OrientationCounts count_orientations(const SimplexMesh& mesh, std::span<const double> xyz) {
    OrientationCounts counts;
    for (ElementId e = 0; e < mesh.num_elements(); ++e) {
        const int o = element_orientation(mesh, xyz, e);
        counts.inverted += o < 0;
        counts.degenerate += o == 0;
    }
    return counts;
}

}  // namespace paloverde
