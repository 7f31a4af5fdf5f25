#pragma once
// The native mesh, stored as flat arrays so that solvers stream over coordinates and connectivity
// without indirection. Its elements are simplices of one kind (triangles or tetrahedra): the
// mesh's own, or, for a mesh with quadrilaterals, hexahedra, wedges or pyramids (cells), the
// corner simplices of its cells (cell_types.hpp), each with the map that rates it against the
// ideal cell's corner. Solvers, metrics and exact predicates see only simplices; readers,
// writers, the boundary and the reports see the cells.
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "paloverde/core/types.hpp"
#include "paloverde/mesh/cell_types.hpp"
#include "paloverde/mesh/mesh_interface.hpp"

namespace paloverde {

class Mesh final : public MeshInterface {
public:
    Mesh() = default;
    // Validates the arrays (sizes, finite coordinates, indices in range, no repeated corner in an
    // element) and throws MeshError naming the first offending vertex or element. Vertices start
    // free; global ids start as 0..n-1.
    Mesh(ElementKind kind, std::vector<double> coordinates, std::vector<VertexId> connectivity);

    // A mesh of cells of one dimension (any mix of the types of that dimension), validated like
    // the constructor's arrays, naming the offending cell. Triangles or tetrahedra alone give the
    // plain simplex mesh (no cells); otherwise each cell's corners become elements, cell by cell
    // in the order of its frames. `keep_cells`: keep them as cells even when all are triangles or
    // all tetrahedra (a part of a mixed mesh is rated and reported as the whole mesh is).
    static Mesh from_cells(std::vector<double> coordinates, std::span<const CellType> types,
                           std::vector<VertexId> cell_connectivity, bool keep_cells = false);

    // Copies any MeshInterface through its batch interface.
    static Mesh copy_of(const MeshInterface& mesh);

    ElementKind kind() const noexcept { return kind_; }
    int corners() const noexcept { return corner_count(kind_); }
    VertexId num_vertices() const noexcept { return static_cast<VertexId>(coordinates_.size() / 3); }
    ElementId num_elements() const noexcept {
        return static_cast<ElementId>(connectivity_.size() / corner_count(kind_));
    }

    // 3 doubles per vertex.
    std::span<const double> coordinates() const noexcept { return coordinates_; }
    std::span<double> coordinates() noexcept { return coordinates_; }
    Vec3 point(VertexId v) const noexcept {
        return {coordinates_[3 * v], coordinates_[3 * v + 1], coordinates_[3 * v + 2]};
    }
    // corners() ids per element.
    std::span<const VertexId> connectivity() const noexcept { return connectivity_; }
    std::span<const VertexId> element(ElementId e) const noexcept {
        return std::span<const VertexId>(connectivity_).subspan(static_cast<std::size_t>(e) * corners(),
                                                                 corners());
    }

    // Cells: empty (has_cells() false) for a mesh of simplices, where each element is its own cell.
    bool has_cells() const noexcept { return !cell_types_.empty(); }
    ElementId num_cells() const noexcept {
        return has_cells() ? static_cast<ElementId>(cell_types_.size()) : num_elements();
    }
    CellType cell_type(ElementId c) const noexcept { return has_cells() ? cell_types_[c] : simplex_cell(kind_); }
    std::span<const VertexId> cell(ElementId c) const noexcept {
        if (!has_cells()) return element(c);
        return std::span<const VertexId>(cell_connectivity_)
            .subspan(static_cast<std::size_t>(cell_offsets_[c]), static_cast<std::size_t>(cell_offsets_[c + 1] - cell_offsets_[c]));
    }
    std::span<const CellType> cell_types() const noexcept { return cell_types_; }
    std::span<const std::int64_t> cell_offsets() const noexcept { return cell_offsets_; }
    std::span<const VertexId> cell_connectivity() const noexcept { return cell_connectivity_; }
    // Per element: the cell it is a corner of, and its corner map (corner_map()); empty without cells.
    std::span<const ElementId> element_cells() const noexcept { return element_cell_; }
    std::span<const std::uint8_t> corner_maps() const noexcept { return corner_map_; }
    ElementId cell_of(ElementId e) const noexcept { return has_cells() ? element_cell_[e] : e; }
    // Reduces per-element values to per-cell ones by the minimum (a cell is as good as its worst
    // corner); without cells, a copy.
    std::vector<double> cell_minimum(std::span<const double> per_element) const;
    // Renumbers or reorders: the cells' vertices by new_id (new_id[old]), the elements' cell, map
    // and target by old_element (new element i was old_element[i]). For any mesh made of some of
    // another's elements.
    void carry_element_data_from(const Mesh& source, std::span<const VertexId> new_id,
                                 std::span<const ElementId> old_element);
    // Renumbers the mesh in place: vertex i becomes the one that was old_vertex[i] (empty: the
    // vertices keep their ids), element i the one that was old_element[i]. Every per-vertex and
    // per-element field goes with them, and the cells' corners are renamed; the cells keep their
    // order, and the plane and the marks (flipped, locality ordered) stay as they were: nothing
    // moved. All or nothing: should memory run out, the mesh is as it was. Throws MeshError for
    // orders that are not permutations of the vertices and elements.
    void permute(std::span<const VertexId> old_vertex, std::span<const ElementId> old_element);

    // Targets (metrics/targets.hpp): per element, the map that carries its corner simplex to the
    // simplex a metric rates in its place (instead of its cell's corner map), so that an element
    // equal to its target is rated as the regular simplex; and the signed volume (area, in 2D)
    // that mapped simplex has at the target's size, which size metrics measure against. Empty
    // without targets: every element is then rated against the ideal element.
    bool has_targets() const noexcept { return !target_maps_.empty(); }
    std::span<const CornerMap> target_maps() const noexcept { return target_maps_; }
    std::span<const double> target_volumes() const noexcept { return target_volumes_; }
    // Per element, or empty: the space its target is measured in, as the map N (N[row][column], a
    // map of space of determinant 1) that carries its corners there after its map: the square
    // root of a metric, in which a simplex whose stretch is meant (targets.hpp) is rated against
    // the regular simplex. Without them every element is rated in space as it is.
    std::span<const CornerMap> target_metric_roots() const noexcept { return target_metric_roots_; }
    // Throws MeshError for a wrong count, or naming the first element whose map (or metric root)
    // is not finite or reverses orientation, or whose volume is not a finite positive number.
    void set_targets(std::vector<CornerMap> maps, std::vector<double> volumes, std::vector<CornerMap> metric_roots = {});
    void clear_targets() noexcept;
    // Multiplies every coordinate by 2^exponent, and the target volumes, reference coordinates
    // and target edge lengths with them: exact, and harmless to orientation (unit_scale_exponent).
    void scale(int exponent);

    // Morphing: where the vertices were before the boundary moved (the undeformed mesh), three
    // coordinates per vertex; empty when the mesh carries no motion. Solvers that untangle apply
    // the motion of the vertices that do not move freely in steps from there when the mesh as it
    // is does not untangle (solvers/boundary_motion.hpp). Throws MeshError for a wrong size or a
    // coordinate that is not finite.
    std::span<const double> reference_coordinates() const noexcept { return reference_coordinates_; }
    void set_reference_coordinates(std::vector<double> xyz);
    void clear_reference_coordinates() noexcept { reference_coordinates_.clear(); }

    // Sizes from a field: the edge length wanted at each vertex (a size field's values), one per
    // vertex; empty when none is given. Targets whose size comes from a field (TargetSource::Field)
    // give an element the regular shape's size at the mean of its vertices' lengths. Throws
    // MeshError for a wrong count or a length that is not a finite positive number.
    std::span<const double> target_edge_lengths() const noexcept { return target_edge_lengths_; }
    void set_target_edge_lengths(std::vector<double> lengths);
    void clear_target_edge_lengths() noexcept { target_edge_lengths_.clear(); }

    // Anisotropic sizes from a field: the metric wanted at each vertex, the symmetric positive
    // definite M in which a wanted edge e has unit length (e^T M e = 1; edges of length h in every
    // direction: M = I / h^2), six values per vertex in VTK's order: xx, yy, zz, xy, yz, xz.
    // Targets from it (TargetSource::Metric) make each element the ideal one in the mean of its
    // vertices' metrics. Empty when none is given; scaled with the mesh. Throws MeshError for a
    // wrong count or a vertex whose matrix is not finite, or (volume meshes) not positive definite.
    static constexpr int kMetricValues = 6;
    std::span<const double> target_metrics() const noexcept { return target_metrics_; }
    void set_target_metrics(std::vector<double> metrics);
    void clear_target_metrics() noexcept { target_metrics_.clear(); }

    // Vertex -> incident elements, compressed rows.
    std::span<const ElementId> elements_of(VertexId v) const noexcept {
        return std::span<const ElementId>(vertex_elements_)
            .subspan(vertex_element_offsets_[v], vertex_element_offsets_[v + 1] - vertex_element_offsets_[v]);
    }
    std::span<const std::int64_t> vertex_element_offsets() const noexcept { return vertex_element_offsets_; }
    std::span<const ElementId> vertex_elements() const noexcept { return vertex_elements_; }

    // 1 for vertices that must not move.
    std::span<const std::uint8_t> fixed() const noexcept { return fixed_; }
    // Where a vertex may move, decided here for every solver and assessment: in 3 directions (a
    // free vertex), 2 (on a surface, a sliding boundary vertex), 1 (along a feature curve) or none
    // (a fixed one). Solvers ask can_move() and slides(), not the fixed flag.
    int degrees_of_freedom(VertexId v) const noexcept {
        return freedom_.empty() ? (fixed_[v] ? 0 : 3) : freedom_[v];
    }
    bool can_move(VertexId v) const noexcept { return degrees_of_freedom(v) > 0; }
    // It moves, but on a surface or a curve only.
    bool slides(VertexId v) const noexcept {
        const int d = degrees_of_freedom(v);
        return d == 1 || d == 2;
    }
    // Each vertex's degrees of freedom (0 to 3); the fixed flags follow (fixed: 0). Throws
    // MeshError for a wrong size or a value above 3.
    void set_degrees_of_freedom(std::vector<std::uint8_t> freedom);
    // Element e has a vertex that can move: the only elements a vertex mover changes (movable).
    bool element_can_move(ElementId e) const noexcept {
        for (VertexId v : element(e))
            if (can_move(v)) return true;
        return false;
    }
    // Fixed (0) or free (3) only: any surface or curve freedom is dropped.
    void set_fixed(std::vector<std::uint8_t> fixed);
    // Fixes exactly the vertices on the boundary (faces of one cell in 3D, edges of one in 2D).
    void fix_boundary();
    VertexId num_free_vertices() const noexcept;

    std::span<const GlobalId> global_ids() const noexcept { return global_ids_; }
    void set_global_ids(std::vector<GlobalId> ids);

    // Triangle meshes: whether all vertices lie in one plane, and that plane's unit normal, which
    // defines a triangle's orientation (its signed area). Tetrahedral meshes: always planar=false.
    bool is_planar() const noexcept { return planar_; }
    const Vec3& plane_normal() const noexcept { return plane_normal_; }

    // Surface meshes (triangles and 2D cells in 3D that do not lie in one plane): per element, the
    // unit normal of the surface there (a cell's corner elements share their cell's), about which
    // its signed area, its orientation and its metrics are taken (an element whose normal turns
    // past 90 degrees from it is inverted). Empty otherwise: a planar mesh is oriented by its
    // plane, and a surface triangle alone by its own normal (never inverted). A solver sets them
    // from its input surface for a run (BoundarySurface::normals_of) and clears them after; so
    // does `paloverde quality`. Throws MeshError for a wrong count, or naming the first normal
    // that is not a unit vector.
    bool has_surface_normals() const noexcept { return !surface_normals_.empty(); }
    std::span<const Vec3> surface_normals() const noexcept { return surface_normals_; }
    void set_surface_normals(std::vector<Vec3> normals);
    void clear_surface_normals() noexcept { surface_normals_.clear(); }

    // Swaps the last two corners of every element, which reverses each one's orientation (a mesh
    // with cells mirrors each cell, CellInfo::mirror, and takes its corners anew in place). A planar
    // triangle mesh's normal turns with its triangles (as if found anew), so their orientation
    // about it is unchanged. Adjacency, fixed flags and ids stay as they are.
    void flip_elements();
    // Whether the elements are held flipped relative to the file they came from (orient() flipped
    // them because the file uses the mirror convention): writers swap the corners back, so that an
    // output keeps the convention of its input. Copies keep the mark.
    bool elements_flipped() const noexcept { return elements_flipped_; }
    void set_elements_flipped(bool flipped) noexcept { elements_flipped_ = flipped; }
    // Whether the numbering keeps neighbours near each other (a mesh a solver has renumbered, set
    // by whoever renumbered it): a pass over the elements then reads their corners almost in order,
    // and the processor's own prefetching does better than asking for each corner ahead. Copies
    // keep the mark.
    bool locality_ordered() const noexcept { return locality_ordered_; }
    void set_locality_ordered(bool ordered) noexcept { locality_ordered_ = ordered; }

    // MeshInterface.
    ElementKind element_kind() const override { return kind_; }
    std::size_t vertex_count() const override { return static_cast<std::size_t>(num_vertices()); }
    std::size_t element_count() const override { return static_cast<std::size_t>(num_elements()); }
    void get_coordinates(std::span<const VertexId> vertices, std::span<double> xyz) const override;
    void set_coordinates(std::span<const VertexId> vertices, std::span<const double> xyz) override;
    void get_connectivity(std::span<const ElementId> elements, std::span<VertexId> corners) const override;
    void get_fixed(std::span<const VertexId> vertices, std::span<std::uint8_t> fixed) const override;

private:
    void build_adjacency();
    void find_plane();

    ElementKind kind_ = ElementKind::Tetrahedron;
    std::vector<double> coordinates_;
    std::vector<VertexId> connectivity_;
    std::vector<std::int64_t> vertex_element_offsets_{0};
    std::vector<ElementId> vertex_elements_;
    std::vector<std::uint8_t> fixed_;
    std::vector<std::uint8_t> freedom_;  // empty while every vertex is fixed or free
    std::vector<GlobalId> global_ids_;
    bool planar_ = false;
    Vec3 plane_normal_{0.0, 0.0, 1.0};
    bool elements_flipped_ = false;
    bool locality_ordered_ = false;
    std::vector<CellType> cell_types_;
    std::vector<std::int64_t> cell_offsets_;
    std::vector<VertexId> cell_connectivity_;
    std::vector<ElementId> element_cell_;
    std::vector<std::uint8_t> corner_map_;
    std::vector<CornerMap> target_maps_;
    std::vector<double> target_volumes_;
    std::vector<CornerMap> target_metric_roots_;
    std::vector<double> reference_coordinates_;
    std::vector<double> target_edge_lengths_;
    std::vector<double> target_metrics_;
    std::vector<Vec3> surface_normals_;
};

// Power-of-two rescaling, exact both ways and harmless to orientation: the exponent e for which
// 2^e times the largest coordinate magnitude lies in [1, 2) (0 for all-zero coordinates), and
// multiplying every coordinate by 2^e. Volumes of coordinates near 1e300 or 1e-300 overflow or
// underflow; solvers and the assessor work at unit scale instead.
int unit_scale_exponent(std::span<const double> xyz);
void scale_coordinates(std::span<double> xyz, int exponent);

// What the mesh is made of, for reports: "tetrahedron mesh", "hexahedron mesh" (one cell type),
// or "mixed mesh: 120 hexahedra, 40 wedges" (its types in the order of CellType).
std::string describe_cells(const Mesh& mesh);

// Throws MeshError naming two elements (cells, for a mesh with cells) with the same set of
// vertices, if there are any.
void check_no_duplicate_elements(const Mesh& mesh);

// Vertices on the boundary: on a face that belongs to one tetrahedron, or an edge that belongs
// to one triangle. Returns one flag per vertex.
std::vector<std::uint8_t> boundary_vertices(ElementKind kind, std::span<const VertexId> connectivity,
                                            VertexId num_vertices);
// The same for a mesh's cells (its elements when it has none).
std::vector<std::uint8_t> boundary_vertices(const Mesh& mesh);

// A face of a cell (an edge in 2D): its vertices sorted, -1 after the last, and the cell.
struct CellFace {
    std::array<VertexId, 4> vertices;
    ElementId cell;
    bool operator<(const CellFace& o) const { return vertices != o.vertices ? vertices < o.vertices : cell < o.cell; }
};
// Every face of every cell of a mesh with cells, sorted: the cells sharing a face lie together.
std::vector<CellFace> sorted_cell_faces(const Mesh& mesh);

}  // namespace paloverde
