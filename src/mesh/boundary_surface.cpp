#include "paloverde/mesh/boundary_surface.hpp"

#include <CGAL/AABB_segment_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string>

#include "paloverde/core/error.hpp"

namespace paloverde {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Triangles = std::vector<Kernel::Triangle_3>;
using Segments = std::vector<Kernel::Segment_3>;
using TriangleTree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, CGAL::AABB_triangle_primitive<Kernel, Triangles::const_iterator>>>;
using SegmentTree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, CGAL::AABB_segment_primitive<Kernel, Segments::const_iterator>>>;

Vec3 minus(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3 cross(const Vec3& a, const Vec3& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }

// The angle between two vectors, in degrees; 0 when either has no length.
double angle_between(const Vec3& a, const Vec3& b) {
    const double la = norm(a), lb = norm(b);
    if (!(la > 0.0) || !(lb > 0.0)) return 0.0;
    return std::atan2(norm(cross(a, b)), dot(a, b)) * (180.0 / std::numbers::pi);
}

// A boundary facet: a triangle of a tet mesh's boundary, or an edge of a triangle mesh's (the
// third vertex then -1), its corners in the order that makes it face outward.
struct Facet {
    std::array<VertexId, 3> corner;
    std::array<VertexId, 3> key;  // the corners sorted
};

// The outward faces of a positively oriented tetrahedron (0, 1, 2, 3), and the outward edges of a
// positively oriented triangle: the mesh's own corner order decides, not its tangled geometry.
constexpr int kTetFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
constexpr int kTriEdges[3][2] = {{0, 1}, {1, 2}, {2, 0}};

std::vector<Facet> boundary_facets(const SimplexMesh& mesh) {
    std::vector<Facet> all;
    const bool tets = mesh.kind() == ElementKind::Tetrahedron;
    all.reserve(static_cast<std::size_t>(mesh.num_elements()) * (tets ? 4 : 3));
    for (ElementId e = 0; e < mesh.num_elements(); ++e) {
        const auto c = mesh.element(e);
        for (int f = 0; f < (tets ? 4 : 3); ++f) {
            Facet facet;
            facet.corner = tets ? std::array<VertexId, 3>{c[kTetFaces[f][0]], c[kTetFaces[f][1]], c[kTetFaces[f][2]]}
                                : std::array<VertexId, 3>{c[kTriEdges[f][0]], c[kTriEdges[f][1]], -1};
            facet.key = facet.corner;
            std::sort(facet.key.begin(), facet.key.end());
            all.push_back(facet);
        }
    }
    std::sort(all.begin(), all.end(), [](const Facet& a, const Facet& b) { return a.key < b.key; });
    std::vector<Facet> boundary;
    for (std::size_t i = 0; i < all.size();) {
        std::size_t j = i + 1;
        while (j < all.size() && all[j].key == all[i].key) ++j;
        if (j - i == 1) boundary.push_back(all[i]);
        i = j;
    }
    return boundary;
}

}  // namespace

struct BoundarySurface::Trees {
    Triangles triangles;
    Segments segments;
    TriangleTree triangle_tree;
    SegmentTree segment_tree;
};

void SurfaceOptions::validate() const {
    if (!(feature_angle > 0.0 && feature_angle < 180.0))
        throw OptionError("feature_angle must lie in (0, 180) degrees (got " + std::to_string(feature_angle) + ")");
}

BoundarySurface::~BoundarySurface() = default;
BoundarySurface::BoundarySurface(BoundarySurface&&) noexcept = default;
BoundarySurface& BoundarySurface::operator=(BoundarySurface&&) noexcept = default;

BoundarySurface::BoundarySurface(const SimplexMesh& mesh, const SurfaceOptions& options)
    : kind_(mesh.kind()), trees_(std::make_unique<Trees>()) {
    options.validate();
    const bool tets = kind_ == ElementKind::Tetrahedron;
    if (!tets && !mesh.is_planar())
        throw MeshError("the triangles do not lie in one plane: a surface mesh has no boundary to slide on");
    const auto n = static_cast<std::size_t>(mesh.num_vertices());
    const auto xyz = mesh.coordinates();
    original_.resize(n);
    for (std::size_t v = 0; v < n; ++v) original_[v] = {xyz[3 * v], xyz[3 * v + 1], xyz[3 * v + 2]};
    if (n > 0) {
        Vec3 low = original_[0], high = original_[0];
        for (const auto& p : original_)
            for (int d = 0; d < 3; ++d) low[d] = std::min(low[d], p[d]), high[d] = std::max(high[d], p[d]);
        diagonal_ = norm(minus(high, low));
    }
    roles_.assign(n, BoundaryRole::Interior);

    const std::vector<Facet> facets = boundary_facets(mesh);
    face_count_ = facets.size();
    // Boundary edges with the facets on them: for a tet mesh, the edges of its boundary faces;
    // for a triangle mesh, the boundary edges themselves (each on a curve).
    struct EdgeUse {
        std::array<VertexId, 2> key;
        std::size_t facet;
    };
    std::vector<EdgeUse> uses;
    for (std::size_t f = 0; f < facets.size(); ++f) {
        const auto& c = facets[f].corner;
        for (VertexId v : c)
            if (v >= 0) roles_[static_cast<std::size_t>(v)] = BoundaryRole::Surface;
        if (tets) {
            for (int i = 0; i < 3; ++i) uses.push_back({{std::min(c[i], c[(i + 1) % 3]), std::max(c[i], c[(i + 1) % 3])}, f});
        } else {
            uses.push_back({{std::min(c[0], c[1]), std::max(c[0], c[1])}, f});
        }
    }
    std::sort(uses.begin(), uses.end(), [](const EdgeUse& a, const EdgeUse& b) { return a.key < b.key; });
    auto normal = [&](std::size_t f) {
        const auto& c = facets[f].corner;
        return cross(minus(original_[c[1]], original_[c[0]]), minus(original_[c[2]], original_[c[0]]));
    };
    // Each vertex's feature edges, by the vertex at their other end.
    std::vector<std::vector<VertexId>> along(n);
    for (std::size_t i = 0; i < uses.size();) {
        std::size_t j = i + 1;
        while (j < uses.size() && uses[j].key == uses[i].key) ++j;
        const bool feature = !tets || j - i != 2 || angle_between(normal(uses[i].facet), normal(uses[i + 1].facet)) > options.feature_angle;
        if (feature) {
            const auto [a, b] = uses[i].key;
            along[static_cast<std::size_t>(a)].push_back(b);
            along[static_cast<std::size_t>(b)].push_back(a);
            trees_->segments.emplace_back(Kernel::Point_3(original_[a][0], original_[a][1], original_[a][2]),
                                          Kernel::Point_3(original_[b][0], original_[b][1], original_[b][2]));
            ++feature_count_;
        }
        i = j;
    }
    for (std::size_t v = 0; v < n; ++v) {
        if (roles_[v] == BoundaryRole::Interior || along[v].empty()) continue;
        bool corner = along[v].size() != 2;
        if (!corner) {
            // A curve through v turns by 180 degrees less the angle between its two edges there.
            const double turn = 180.0 - angle_between(minus(original_[along[v][0]], original_[v]),
                                                      minus(original_[along[v][1]], original_[v]));
            corner = turn > options.feature_angle;
        }
        roles_[v] = corner ? BoundaryRole::Corner : BoundaryRole::Curve;
    }
    if (tets)
        for (const auto& f : facets) {
            const auto p = [&](VertexId v) { return Kernel::Point_3(original_[v][0], original_[v][1], original_[v][2]); };
            const Kernel::Triangle_3 t(p(f.corner[0]), p(f.corner[1]), p(f.corner[2]));
            if (!t.is_degenerate()) trees_->triangles.push_back(t);
        }
    if (!trees_->triangles.empty()) {
        trees_->triangle_tree.insert(trees_->triangles.cbegin(), trees_->triangles.cend());
        trees_->triangle_tree.accelerate_distance_queries();
    }
    trees_->segments.erase(std::remove_if(trees_->segments.begin(), trees_->segments.end(),
                                          [](const Kernel::Segment_3& s) { return s.is_degenerate(); }),
                           trees_->segments.end());
    if (!trees_->segments.empty()) {
        trees_->segment_tree.insert(trees_->segments.cbegin(), trees_->segments.cend());
        trees_->segment_tree.accelerate_distance_queries();
    }
}

int BoundarySurface::freedom(VertexId v) const {
    switch (role(v)) {
        case BoundaryRole::Interior: return kind_ == ElementKind::Tetrahedron ? 3 : 2;
        case BoundaryRole::Surface: return 2;
        case BoundaryRole::Curve: return 1;
        case BoundaryRole::Corner: return 0;
    }
    return 0;
}

Vec3 BoundarySurface::project(VertexId v, const Vec3& p) const {
    const Kernel::Point_3 q(p[0], p[1], p[2]);
    auto out = [](const Kernel::Point_3& r) { return Vec3{r.x(), r.y(), r.z()}; };
    switch (role(v)) {
        case BoundaryRole::Interior: return p;
        case BoundaryRole::Surface:
            return trees_->triangles.empty() ? original_[static_cast<std::size_t>(v)] : out(trees_->triangle_tree.closest_point(q));
        case BoundaryRole::Curve:
            return trees_->segments.empty() ? original_[static_cast<std::size_t>(v)] : out(trees_->segment_tree.closest_point(q));
        case BoundaryRole::Corner: return original_[static_cast<std::size_t>(v)];
    }
    return p;
}

std::size_t BoundarySurface::count(BoundaryRole r) const {
    return static_cast<std::size_t>(std::count(roles_.begin(), roles_.end(), r));
}

}  // namespace paloverde
