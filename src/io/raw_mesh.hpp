#pragma once
// What every reader produces before the mesh is assembled: points, the cells found (of every type
// a mesh can hold, in file order), and the fields. finish_mesh() keeps the cells of the highest
// dimension, validates, and sets the fixed flags and global ids.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <span>
#include <string>
#include <vector>

#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/cell_types.hpp"

namespace paloverde::io {

struct RawMesh {
    std::vector<double> coordinates;  // 3 per point
    // The cells, each with its vertices (0-based point indices) in the canonical (VTK) order.
    // Lower-dimensional cells (points, lines) never get here; triangles and quadrilaterals beside
    // 3D cells do, and finish_mesh() drops them.
    std::vector<CellType> cell_types;
    std::vector<VertexId> cell_connectivity;
    // Position of each cell in the file's own cell list, so that cell fields (one tuple per file
    // cell, all kinds) can be narrowed to the kept cells.
    std::vector<std::size_t> cell_positions;
    std::vector<Field> point_fields;
    std::vector<Field> cell_fields;
    // How messages name the file's cell at a position, where "cell 12 (hexahedron)" would not say
    // it the way the format does (Gmsh names elements by tag, Medit counts them by section).
    std::function<std::string(std::size_t position, CellType type)> cell_name;

    // Appends a cell whose vertices are in the canonical order.
    void add_cell(CellType type, const VertexId* vertices, std::size_t position);
    // Appends a cell whose vertices are in Gmsh's and Medit's order (CellInfo::gmsh_order).
    void add_file_cell(CellType type, const VertexId* file_vertices, std::size_t position);
};

// The cell type with this code in a format, or nullptr for one a mesh cannot hold:
// find_cell([&](const CellInfo& c) { return c.vtk == code; }).
template <class Match>
const CellInfo* find_cell(Match&& match) {
    for (const CellInfo& info : all_cell_infos())
        if (match(info)) return &info;
    return nullptr;
}

// The cell types a mesh can hold with their codes in a format, for messages: "triangle (5),
// quadrilateral (9), ... and pyramid (14)" for handled_cells(&CellInfo::vtk).
std::string handled_cells(int CellInfo::*code);

// Everything a writer needs. The cells are the mesh's cells, or its elements when it has none;
// their vertices are in `connectivity`, in the canonical order of the file's convention (mirrored
// back for a mesh flipped on reading).
struct MeshToWrite {
    const Mesh& mesh;
    std::span<const VertexId> connectivity;  // every cell's vertices, cell after cell
    std::span<const Field> point_fields;     // includes `fixed` when requested
    std::span<const Field> cell_fields;      // one tuple per cell

    std::size_t cells() const { return static_cast<std::size_t>(mesh.num_cells()); }
    CellType type(std::size_t c) const { return mesh.cell_type(static_cast<ElementId>(c)); }
    std::span<const VertexId> cell(std::size_t c) const {
        if (!mesh.has_cells()) {
            const auto k = static_cast<std::size_t>(mesh.corners());
            return connectivity.subspan(c * k, k);
        }
        const auto offsets = mesh.cell_offsets();
        return connectivity.subspan(static_cast<std::size_t>(offsets[c]),
                                    static_cast<std::size_t>(offsets[c + 1] - offsets[c]));
    }
    // Where cell c ends in `connectivity` (VTK offsets).
    std::int64_t end_of(std::size_t c) const {
        return mesh.has_cells() ? mesh.cell_offsets()[c + 1] : static_cast<std::int64_t>(c + 1) * mesh.corners();
    }
};

// Cell c's vertices in Gmsh's and Medit's order: out[gmsh_order[i]] = cell[i].
void to_file_order(CellType type, std::span<const VertexId> cell, VertexId* out);

MeshFile finish_mesh(RawMesh&& raw, const std::string& path, const ReadOptions& options);

// One reader and (where the format allows) one writer per format. `path` names the file in
// error messages. Writers get a stream that AtomicFile commits.
RawMesh read_vtk_legacy(const std::string& path);
RawMesh read_vtu(const std::string& path);
RawMesh read_gmsh(const std::string& path);
RawMesh read_medit(const std::string& path);
RawMesh read_tetgen(const std::string& path);  // path of the .node or the .ele file

void write_vtk_legacy(std::ostream& out, const MeshToWrite& mesh, Encoding encoding);
void write_vtu(std::ostream& out, const MeshToWrite& mesh, Encoding encoding);
void write_gmsh(std::ostream& out, const MeshToWrite& mesh, Encoding encoding);
void write_medit(std::ostream& out, const MeshToWrite& mesh);

}  // namespace paloverde::io
