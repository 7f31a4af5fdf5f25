#include "sliding_boundary.hpp"

#include <algorithm>
#include <cmath>

#include "paloverde/mesh/orientation.hpp"

namespace paloverde::detail {

namespace {

// The mesh's volume (area for planar triangles), at the input's scale.
double volume_of(const SimplexMesh& mesh) {
    const auto xyz = mesh.coordinates();
    const int exponent = unit_scale_exponent(xyz);
    const SignedMeasure m = signed_measure(mesh, xyz, exponent, mesh.plane_normal());
    return std::ldexp(m.total.value(), -exponent * (mesh.kind() == ElementKind::Tetrahedron ? 3 : 2));
}

}  // namespace

SlidingBoundary::SlidingBoundary(SimplexMesh& mesh, const SurfaceOptions& options)
    : mesh_(mesh), surface_(mesh, options), fixed_(mesh.fixed().begin(), mesh.fixed().end()),
      input_(mesh.coordinates().begin(), mesh.coordinates().end()), volume_before_(volume_of(mesh)) {
    const auto n = static_cast<std::size_t>(mesh.num_vertices());
    std::vector<std::uint8_t> on_boundary(n);
    for (std::size_t v = 0; v < n; ++v) on_boundary[v] = surface_.role(static_cast<VertexId>(v)) != BoundaryRole::Interior;
    const bool boundary_fixed = on_boundary == fixed_;
    slides_.assign(n, 0);
    std::vector<std::uint8_t> fixed = fixed_;
    for (std::size_t v = 0; v < n; ++v) {
        const BoundaryRole role = surface_.role(static_cast<VertexId>(v));
        if (role != BoundaryRole::Surface && role != BoundaryRole::Curve) continue;
        if (fixed_[v] && !boundary_fixed) continue;  // fixed by the user's own choice
        slides_[v] = 1;
        fixed[v] = 0;
    }
    mesh_.set_fixed(std::move(fixed));
}

SlidingBoundary::~SlidingBoundary() { mesh_.set_fixed(fixed_); }

Vec3 SlidingBoundary::project(VertexId v, const Vec3& p) const {
    Vec3 q = surface_.project(v, {std::ldexp(p[0], -exponent_), std::ldexp(p[1], -exponent_), std::ldexp(p[2], -exponent_)});
    for (double& c : q) c = std::ldexp(c, exponent_);
    return q;
}

BoundaryMotion SlidingBoundary::motion() const {
    BoundaryMotion m;
    const auto xyz = mesh_.coordinates();
    double largest = 0.0;
    for (std::size_t v = 0; v < slides_.size(); ++v) {
        if (!slides_[v]) continue;
        ++m.sliding;
        const Vec3 p = {xyz[3 * v], xyz[3 * v + 1], xyz[3 * v + 2]};
        if (!std::equal(p.begin(), p.end(), input_.begin() + static_cast<std::ptrdiff_t>(3 * v))) ++m.moved;
        largest = std::max(largest, surface_.distance(p));
    }
    const double diagonal = surface_.bounding_box_diagonal();
    m.largest_distance = diagonal > 0.0 ? largest / diagonal : 0.0;
    m.volume_before = volume_before_;
    m.volume_after = volume_of(mesh_);
    return m;
}

}  // namespace paloverde::detail
