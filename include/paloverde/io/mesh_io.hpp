#pragma once
// Reading and writing meshes. Formats are chosen from the file extension unless named:
//   .vtk (legacy, ASCII or binary)   .vtu (XML; ASCII, inline base64 or appended raw/base64)
//   .msh (Gmsh 2.2 / 4.1 read, 2.2 write)   .mesh (Medit, ASCII)   .node/.ele (TetGen, read)
// Cells: triangles and quadrilaterals, or tetrahedra, hexahedra, wedges and pyramids, alone or
// mixed (cell_types.hpp; TetGen: triangles or tetrahedra). Files may hold cells of lower dimension
// (boundary triangles and quadrilaterals, edges, points); the mesh keeps its highest-dimensional
// cells. Any other cell type (polyhedra, second-order cells) is an error.
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "paloverde/mesh/mesh.hpp"
#include "paloverde/mesh/orientation.hpp"

namespace paloverde {

// Values attached to points or cells: `components` doubles per entity.
struct Field {
    std::string name;
    int components = 1;
    std::vector<double> values;
};

enum class MeshFormat { FromExtension, VtkLegacy, Vtu, Gmsh, Medit, TetGen };
enum class Encoding { Ascii, Binary };

MeshFormat format_from_extension(const std::filesystem::path& path);
std::string_view to_string(MeshFormat format);

struct ReadOptions {
    MeshFormat format = MeshFormat::FromExtension;
    // Without a `fixed` point field in the file, fix the boundary vertices (else all are free).
    bool fix_boundary = true;
    // The file's orientation convention (orientation.hpp): auto flips the elements when their
    // total signed volume is negative. Written meshes get the file's order back.
    OrientationMode orientation = OrientationMode::Auto;
};

struct WriteOptions {
    MeshFormat format = MeshFormat::FromExtension;
    Encoding encoding = Encoding::Binary;  // .mesh (Medit) is always text: its binary form is .meshb
    // (Gmsh files are written in format version 2.2, which every Gmsh since 2.x and meshio read.)
    // Writes a `fixed` point field (where the format can hold one) so a round trip keeps them.
    bool write_fixed = true;
    void validate(const std::filesystem::path& path) const;  // throws OptionError
};

struct MeshFile {
    Mesh mesh;
    std::vector<Field> point_fields;  // as read, including `fixed` if present
    std::vector<Field> cell_fields;   // one tuple per cell of `mesh` (mesh.num_cells())
    bool fixed_from_file = false;     // whether a `fixed` point field set the fixed flags
    OrientationDecision orientation;  // whether every element was flipped, and why

    const Field* point_field(std::string_view name) const;
    const Field* cell_field(std::string_view name) const;
};

// Throws FileError (with path and line or byte offset) on any malformed content, MeshError for a
// structurally invalid mesh.
MeshFile read_mesh(const std::filesystem::path& path, const ReadOptions& options = {});

// Writes to a temporary file beside `path` and renames it over `path` only once complete, so a
// failure never leaves a partial file or destroys an existing one. A mesh whose elements were
// flipped on reading (Mesh::elements_flipped()) is written in its file's order. The cells
// are written (a simplex mesh's elements are its cells); cell fields have one tuple per cell.
void write_mesh(const std::filesystem::path& path,
                const Mesh& mesh,
                const WriteOptions& options = {},
                std::span<const Field> point_fields = {},
                std::span<const Field> cell_fields = {});

}  // namespace paloverde
