#pragma once
// Every element type a mesh can hold, described once: corner count, faces, the corner frames its
// quality is judged by, its codes in each file format. Readers, writers, the boundary finder and
// the metrics read this table instead of switching on types.
//
// Quality of a cell comes from its corner Jacobians (Knupp): at each corner, the edge vectors to
// its neighbours form a frame A, a corner simplex (a tetrahedron in 3D, a triangle in 2D). The
// frame of the ideal element there is W; a constant map M = W^-1 W_regular carries the corner to
// the regular simplex's shape, so every simplex metric rates a corner against the ideal element's
// own corner. A cell's quality is its worst corner's; it is inverted when any corner's Jacobian
// has a non-positive determinant. A triangle or a tetrahedron is the one-corner case (M = I).
// Vertex orders are VTK's (a hexahedron's face 0-1-2-3 points to 4-5-6-7; a wedge's 0-1-2 points
// away from 3-4-5; a pyramid's base 0-1-2-3 points to the apex 4).
#include <array>
#include <cstdint>
#include <span>
#include <string_view>

#include "paloverde/core/types.hpp"

namespace paloverde {

enum class CellType : std::uint8_t { Triangle, Quadrilateral, Tetrahedron, Hexahedron, Wedge, Pyramid };
inline constexpr int kCellTypeCount = 6;
inline constexpr int kMaxCellCorners = 8;

struct CellInfo {
    CellType type;
    std::string_view name;   // "hexahedron"
    int dimension;           // 2 or 3
    int corners;             // vertex count
    ElementKind simplex;     // the kind of its corner simplices
    // Corner simplices, each as the corner vertex then its edge neighbours (3 in 3D, 2 in 2D, the
    // rest -1), ordered so that the ideal element's frames are positive. The pyramid's apex has
    // no frame of its own: its four edges are in the base corners' frames (the trilinear map's
    // Jacobian vanishes at the apex, so there is no corner Jacobian to take there).
    std::span<const std::array<int, 4>> frames;
    // Faces (3D) or edges (2D), as cell-local vertex lists (the rest -1): a face on one cell only
    // is on the boundary.
    std::span<const std::array<int, 4>> faces;
    // The mirror image: cell vertex i becomes vertex mirror[i] (an involution that reverses the
    // orientation of every corner).
    std::array<int, kMaxCellCorners> mirror;
    // Codes in the file formats, and the order of a Gmsh or Medit element's vertices: the cell's
    // vertex i is the file's vertex gmsh_order[i].
    int vtk;
    int gmsh;
    std::string_view medit;
    std::array<int, kMaxCellCorners> gmsh_order;
};

const CellInfo& cell_info(CellType type);
std::span<const CellInfo> all_cell_infos();
// Whether the type is a simplex (each element its own corner, with no map).
constexpr bool is_simplex(CellType type) noexcept { return type == CellType::Triangle || type == CellType::Tetrahedron; }
constexpr CellType simplex_cell(ElementKind kind) noexcept {
    return kind == ElementKind::Triangle ? CellType::Triangle : CellType::Tetrahedron;
}

// The maps M of the corner frames, numbered from 1 (0 is the identity of a simplex's own frame):
// frame f of type t has number corner_map_id(t, f). A corner (x0, x1, .., xd) maps to
// y0 = x0, y_i = x0 + sum_j (x_j - x0) M[j][i] (j, i from 1 to d): the corner simplex a simplex
// metric rates in its place.
using CornerMap = std::array<std::array<double, 3>, 3>;  // M[j - 1][i - 1]
std::uint8_t corner_map_id(CellType type, int frame);
const CornerMap& corner_map(std::uint8_t id);
// The cell type and frame a map number belongs to.
CellType corner_map_cell(std::uint8_t id);
int corner_map_count();  // including the identity

// The ideal element (all edges of unit length, square faces square), its vertices' coordinates.
std::span<const std::array<double, 3>> ideal_cell(CellType type);

}  // namespace paloverde
