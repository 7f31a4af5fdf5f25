#pragma once
// What every reader produces before the mesh is assembled: points, the simplices found (of both
// kinds, in file order), and the fields. finish_mesh() picks the highest-dimensional simplices,
// validates, and sets the fixed flags and global ids.
#include <cstddef>
#include <iosfwd>
#include <span>
#include <string>
#include <vector>

#include "paloverde/io/mesh_io.hpp"

namespace paloverde::io {

struct RawMesh {
    std::vector<double> coordinates;    // 3 per point
    std::vector<VertexId> tetrahedra;   // 4 per tetrahedron, 0-based point indices
    std::vector<VertexId> triangles;    // 3 per triangle
    // Position of each tetrahedron / triangle in the file's own cell list, so that cell fields
    // (one tuple per file cell, all kinds) can be narrowed to the kept elements.
    std::vector<std::size_t> tetrahedron_cells;
    std::vector<std::size_t> triangle_cells;
    std::vector<Field> point_fields;
    std::vector<Field> cell_fields;
};

// Everything a writer needs.
struct MeshToWrite {
    const SimplexMesh& mesh;
    std::span<const VertexId> connectivity;  // corners() per element, in the file's order
    std::span<const Field> point_fields;  // includes `fixed` when requested
    std::span<const Field> cell_fields;
};

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
