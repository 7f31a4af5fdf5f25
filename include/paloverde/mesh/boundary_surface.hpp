#pragma once
// The boundary of a mesh as a surface its boundary vertices may slide on (issue 17): the input's
// boundary triangulation (a tet mesh's boundary faces; a planar triangle mesh's boundary edges),
// kept as it was for the whole run, with its feature curves and corners.
//
// - A feature edge is a boundary edge where the two boundary faces meet at more than the feature
//   angle (the angle between their normals), or one that does not lie on exactly two boundary
//   faces (an open or non-manifold boundary). For a triangle mesh every boundary edge is on a
//   curve.
// - A boundary vertex on no feature edge lies on the surface (2 degrees of freedom); on exactly
//   two whose directions turn by at most the feature angle, on a curve (1); otherwise (one, three
//   or more feature edges, or a sharp turn) it is a corner and stays where it is (0).
// - project() brings a moved boundary vertex back: a surface vertex to the nearest point of the
//   boundary triangulation, a curve vertex to the nearest point of the feature edges, a corner to
//   its own place.
#include <cstdint>
#include <memory>
#include <vector>

#include "paloverde/core/types.hpp"
#include "paloverde/mesh/simplex_mesh.hpp"

namespace paloverde {

struct SurfaceOptions {
    double feature_angle = 40.0;  // degrees, in (0, 180): sharper creases are kept as curves
    void validate() const;        // throws OptionError
};

enum class BoundaryRole : std::uint8_t { Interior, Surface, Curve, Corner };

class BoundarySurface {
public:
    // From the mesh's current coordinates (the input's boundary, before any vertex moves).
    // Tetrahedra, or planar triangles; throws MeshError for a surface (non-planar triangle) mesh.
    explicit BoundarySurface(const SimplexMesh& mesh, const SurfaceOptions& options = {});
    ~BoundarySurface();
    BoundarySurface(BoundarySurface&&) noexcept;
    BoundarySurface& operator=(BoundarySurface&&) noexcept;

    BoundaryRole role(VertexId v) const { return roles_[static_cast<std::size_t>(v)]; }
    // Degrees of freedom of vertex v: 3 (2 in a planar triangle mesh) inside, 2 on the surface
    // (tetrahedra only), 1 on a curve, 0 at a corner.
    int freedom(VertexId v) const;
    // Where vertex v may be, nearest to p (see above); an interior vertex's p itself.
    Vec3 project(VertexId v, const Vec3& p) const;

    std::size_t boundary_faces() const { return face_count_; }  // triangles (edges for triangle meshes)
    std::size_t feature_edges() const { return feature_count_; }
    std::size_t count(BoundaryRole role) const;
    double bounding_box_diagonal() const { return diagonal_; }

private:
    struct Trees;  // CGAL's AABB trees, kept out of this header
    ElementKind kind_;
    std::vector<BoundaryRole> roles_;
    std::vector<Vec3> original_;  // each vertex's place in the input (corners stay there)
    std::size_t face_count_ = 0, feature_count_ = 0;
    double diagonal_ = 0.0;
    std::unique_ptr<Trees> trees_;
};

}  // namespace paloverde
