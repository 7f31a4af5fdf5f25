#pragma once
// The boundary of a mesh as a surface its boundary vertices may slide on: the input's boundary
// triangulation (a tet mesh's boundary faces; a planar triangle mesh's boundary edges; a surface
// mesh's triangles),
// kept as it was for the whole run, with its feature curves and corners.
//
// - A feature edge is a boundary edge where the two boundary faces meet at more than the feature
//   angle (the angle between their normals), or one that does not lie on exactly two boundary
//   faces (an open or non-manifold boundary). For a triangle mesh every boundary edge is on a
//   curve.
// - A boundary vertex on no feature edge lies on the surface (2 degrees of freedom); on exactly
//   two whose directions turn by at most the feature angle, on a curve (1); otherwise (one, three
//   or more feature edges, or a sharp turn) it is a corner and stays where it is (0).
// - The surface falls into patches (boundary faces joined across edges that are not feature
//   edges) and the feature edges into curves (joined at curve vertices, ending at corners).
//   project() brings a moved boundary vertex back onto its own patch or curve only: a vertex next
//   to a crease cannot cut across it onto the other side, nor jump to a nearby piece of the
//   boundary it is not part of. A corner goes back to its own place.
// - A tet mesh's boundary edge on more than two boundary faces (a non-manifold boundary) leaves
//   the surface undefined there, and is refused; so is a surface mesh's edge of more than two
//   triangles.
// - A surface mesh (triangles in 3D, not in one plane) is its own surface: every triangle is a
//   facet, every vertex lies on a patch, a curve (a crease, or an open edge of the surface) or is
//   a corner.
// - The surface is the same whatever the numbering of its vertices and the order of its facets'
//   corners: it orders them by their coordinates. So a part of a distributed mesh, built from the
//   whole mesh's boundary in global ids, projects and slides exactly as the serial mesh does.
#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "paloverde/core/types.hpp"
#include "paloverde/mesh/mesh.hpp"
#include "paloverde/mesh/surface_domain.hpp"

namespace paloverde {

struct SurfaceOptions {
    double feature_angle = 40.0;  // degrees, in (0, 180): sharper creases are kept as curves
    // Where a surface mesh's vertices on patches (and a volume mesh's sliding ones) project: the
    // input's triangles, or an analytic shape every such vertex of the input lies on (see
    // BoundarySurface::project).
    SurfaceDomain domain;
    void validate() const;  // throws OptionError
};

// A boundary triangulation, its vertices named by ids of any numbering: what a BoundarySurface is
// built from. A part of a distributed mesh has the whole mesh's, in global ids
// (DistributedMesh::gather_boundary).
struct BoundaryFacets {
    ElementKind kind = ElementKind::Tetrahedron;
    std::vector<GlobalId> ids;  // the boundary's vertices, ascending
    std::vector<double> xyz;    // their coordinates, 3 per id
    // Each facet's corners by id, in the order that makes it face outward: a tet mesh's boundary
    // triangles, a planar triangle mesh's boundary edges (the third corner -1); a surface mesh's
    // own triangles (turned as in the file, which need not agree).
    std::vector<std::array<GlobalId, 3>> facets;
    bool surface = false;   // the facets are a surface mesh's triangles: every vertex is on them
    // A surface mesh of quadrilaterals: the diagonals its cells were cut along, which are edges of
    // the facets but not of the mesh, and so never a crease.
    std::vector<std::array<GlobalId, 2>> cuts;
    double diagonal = 0.0;  // of the whole mesh's bounding box
    // A mesh's own boundary, its vertices named by their index: for a surface (non-planar
    // triangle) mesh, the surface itself. Throws MeshError for a mesh with cells.
    static BoundaryFacets of(const Mesh& mesh);
    // The same, `surface` saying whether the mesh is a surface mesh (a part of a distributed
    // surface can lie in one plane while the whole does not).
    static BoundaryFacets of(const Mesh& mesh, bool surface);
};

// Whether `mesh` is a surface mesh: triangles or 2D cells in 3D that do not lie in one plane (a
// part of a distributed surface may; MeshPart callers ask every part).
bool is_surface_mesh(const Mesh& mesh);

enum class BoundaryRole : std::uint8_t { Interior, Surface, Curve, Corner };

class BoundarySurface {
public:
    // From the mesh's current coordinates (the input's boundary, before any vertex moves):
    // tetrahedra, planar triangles, or a surface mesh of triangles (the surface itself, its open
    // edges curves like its creases). Throws MeshError for cells or a non-manifold edge.
    explicit BoundarySurface(const Mesh& mesh, const SurfaceOptions& options = {});
    // From a boundary triangulation; `vertex_ids` names each vertex of the caller's mesh in the
    // boundary's numbering (a vertex not among boundary.ids is interior). Throws MeshError.
    BoundarySurface(const BoundaryFacets& boundary, std::span<const GlobalId> vertex_ids,
                    const SurfaceOptions& options = {});
    ~BoundarySurface();
    BoundarySurface(BoundarySurface&&) noexcept;
    BoundarySurface& operator=(BoundarySurface&&) noexcept;

    BoundaryRole role(VertexId v) const {
        const std::int32_t i = index_[static_cast<std::size_t>(v)];
        return i < 0 ? BoundaryRole::Interior : roles_[static_cast<std::size_t>(i)];
    }
    // Degrees of freedom of vertex v: 3 (2 in a planar triangle mesh) inside, 2 on the surface
    // (tetrahedra only), 1 on a curve, 0 at a corner.
    int freedom(VertexId v) const;
    // Where vertex v may be, nearest to p (see above); an interior vertex's p itself.
    Vec3 project(VertexId v, const Vec3& p) const;
    // The part of a move d that keeps vertex v on its patch to first order: d less its component
    // along the surface's normal at v, d's component along the curve's tangent at v, nothing at a
    // corner, d itself inside. (From the input's boundary; project() corrects what is left.)
    Vec3 tangent(VertexId v, const Vec3& d) const;
    // Distance from p to the input's boundary triangulation (its boundary edges for triangles).
    double distance(const Vec3& p) const;

    bool is_surface_mesh() const { return surface_; }  // built from a surface mesh's own triangles
    // Vertex v is on an open edge of a surface mesh (an edge of one triangle: its outline).
    bool on_open_edge(VertexId v) const {
        const std::int32_t i = index_[static_cast<std::size_t>(v)];
        return surface_ && i >= 0 && on_open_[static_cast<std::size_t>(i)];
    }
    // A surface mesh's: per triangle (in the order of BoundaryFacets::facets, the mesh's element
    // order), the unit normal its quality and orientation are taken about (Mesh::surface_normals):
    // the mean of its corners' normals of the input surface, so that a sliver, whose own normal
    // can face anywhere on a curved surface, is rated in the surface's tangent plane as it is
    // mended. Its own normal where that mean is not on its side, unless the input turned it
    // over: a triangle that faces against the triangles around its corners (more than 120
    // degrees from them on average) keeps the mean, and so is rated inverted until a solver turns
    // it back. Empty for other meshes.
    std::span<const Vec3> element_normals() const { return element_normals_; }
    // A surface mesh's triangles that the input turned over (above).
    std::size_t turned_over() const { return turned_over_; }
    // The same for the elements of `mesh`, the surface mesh this surface was built from: a
    // triangle mesh's element_normals(); in a mesh of triangle and quadrilateral cells, each
    // corner element takes the mean normal of its cell's triangles (Mesh::surface_normals).
    std::vector<Vec3> normals_of(const Mesh& mesh) const;
    // The same for a part of a distributed surface mesh, its vertices named by `vertex_ids` (the
    // surface's ids: global ids).
    std::vector<Vec3> normals_of(const Mesh& mesh, std::span<const GlobalId> vertex_ids) const;
    std::size_t boundary_faces() const { return face_count_; }  // triangles (edges for triangle meshes)
    std::size_t feature_edges() const { return feature_count_; }
    std::size_t count(BoundaryRole role) const;  // of the caller's vertices
    double bounding_box_diagonal() const { return diagonal_; }

private:
    struct Trees;  // CGAL's AABB trees, kept out of this header
    ElementKind kind_;
    bool surface_ = false;  // built from a surface mesh's own triangles
    SurfaceDomain domain_;  // where patch vertices project, when analytic
    // Per vertex of the caller's mesh: its boundary vertex, or -1 inside. Boundary vertices are
    // numbered by their coordinates (lexicographically), and the arrays below are per boundary vertex.
    std::vector<std::int32_t> index_;
    std::vector<BoundaryRole> roles_;
    std::vector<Vec3> original_;  // each vertex's place in the input (corners stay there)
    // Surface vertices: the unit normal of their faces at the input; curve vertices: the unit
    // tangent of their curve; zero otherwise.
    std::vector<Vec3> direction_;
    std::vector<std::int32_t> piece_;  // surface vertices: their patch; curve vertices: their curve
    std::vector<std::uint8_t> on_open_;  // per boundary vertex: on an open edge (surface meshes)
    // Per boundary vertex (rows star_start_[i] .. star_start_[i + 1]): the primitives of its patch or
    // curve that touched it in the input, where project() looks first.
    std::vector<std::int32_t> star_start_, star_;
    std::vector<Vec3> element_normals_;  // surface meshes: see element_normals()
    // Surface meshes: each facet's corners by id, sorted, with its place in BoundaryFacets::facets;
    // sorted, so that a caller's element finds its facets (normals_of).
    std::vector<std::pair<std::array<GlobalId, 3>, std::size_t>> facet_keys_;
    std::size_t face_count_ = 0, feature_count_ = 0, turned_over_ = 0;
    double diagonal_ = 0.0;
    std::unique_ptr<Trees> trees_;
};

}  // namespace paloverde
