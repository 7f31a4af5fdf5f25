// Cells other than simplices (issue 18): quadrilaterals, hexahedra, wedges and pyramids, alone
// or mixed with triangles and tetrahedra, through every writer and encoding and back; the shared
// Mesquite meshes of those types; files of the mirror convention; hostile cell lists.
#include <boost/test/data/test_case.hpp>
#include <boost/test/unit_test.hpp>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <map>
#include <numbers>
#include <ostream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "fuzz/fuzz_input.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/orientation.hpp"
#include "support/io_checks.hpp"
#include "support/test_support.hpp"

namespace fs = std::filesystem;
namespace bdata = boost::unit_test::data;
using namespace paloverde;
using namespace paloverde::test;

namespace {

// A mesh as its cells, in the canonical (VTK) vertex order.
struct CellMesh {
    std::vector<double> xyz;
    std::vector<CellType> types;
    std::vector<VertexId> cells;
    void add(CellType type, std::initializer_list<VertexId> vertices) {
        types.push_back(type);
        cells.insert(cells.end(), vertices);
    }
};

// Thirds, square roots, a -0.0 and a small bump: what a text format must keep bit for bit. The
// scaling is positive and the bump small, so no corner turns over; a 2D mesh stays in its plane.
std::vector<double> awkward(std::vector<double> xyz, bool planar) {
    for (std::size_t v = 0; v < xyz.size() / 3; ++v) {
        const double bump = planar ? 0.0 : 1e-4;
        xyz[3 * v] = xyz[3 * v] / 3.0 + bump * std::sin(v + 1.0);
        xyz[3 * v + 1] = xyz[3 * v + 1] * std::numbers::sqrt2 / 7.0 + bump * std::cos(v + 0.0);
        xyz[3 * v + 2] = xyz[3 * v + 2] * std::numbers::pi / 5.0;
    }
    xyz[2] = -0.0;
    return xyz;
}

// The points of an nx by ny by nz block of unit cubes; p(i, j, k) is the index of point (i, j, k).
struct Grid {
    int nx, ny, nz;
    VertexId p(int i, int j, int k) const { return i + (nx + 1) * (j + (ny + 1) * k); }
    std::vector<double> points() const {
        std::vector<double> xyz;
        for (int k = 0; k <= nz; ++k)
            for (int j = 0; j <= ny; ++j)
                for (int i = 0; i <= nx; ++i) xyz.insert(xyz.end(), {double(i), double(j), double(k)});
        return xyz;
    }
};

CellMesh hexahedra() {
    const Grid g{2, 2, 1};
    CellMesh m{awkward(g.points(), false), {}, {}};
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i)
            m.add(CellType::Hexahedron, {g.p(i, j, 0), g.p(i + 1, j, 0), g.p(i + 1, j + 1, 0), g.p(i, j + 1, 0),
                                         g.p(i, j, 1), g.p(i + 1, j, 1), g.p(i + 1, j + 1, 1), g.p(i, j + 1, 1)});
    return m;
}

// Each cube of a 2 by 1 block cut into two wedges along a diagonal; a VTK wedge's first triangle
// turns clockwise seen from the second.
CellMesh wedges() {
    const Grid g{2, 1, 1};
    CellMesh m{awkward(g.points(), false), {}, {}};
    for (int i = 0; i < 2; ++i) {
        const VertexId a = g.p(i, 0, 0), b = g.p(i + 1, 0, 0), c = g.p(i + 1, 1, 0), d = g.p(i, 1, 0);
        const VertexId up = g.p(0, 0, 1) - g.p(0, 0, 0);
        m.add(CellType::Wedge, {a, d, b, a + up, d + up, b + up});
        m.add(CellType::Wedge, {b, d, c, b + up, d + up, c + up});
    }
    return m;
}

// A cube cut into six pyramids, one per face, their apex at its centre (point 8).
CellMesh pyramids() {
    const Grid g{1, 1, 1};  // point x + 2y + 4z
    std::vector<double> xyz = g.points();
    xyz.insert(xyz.end(), {0.5, 0.5, 0.5});
    CellMesh m{awkward(xyz, false), {}, {}};
    for (const auto& base : {std::array<VertexId, 4>{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 2, 6, 4},
                             {1, 5, 7, 3}})
        m.add(CellType::Pyramid, {base[0], base[1], base[2], base[3], 8});
    return m;
}

CellMesh quadrilaterals() {
    const Grid g{3, 2, 0};
    CellMesh m{awkward(g.points(), true), {}, {}};
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 3; ++i)
            m.add(CellType::Quadrilateral, {g.p(i, j, 0), g.p(i + 1, j, 0), g.p(i + 1, j + 1, 0), g.p(i, j + 1, 0)});
    return m;
}

// A cube, a pyramid on its top face, and a tetrahedron on two of the pyramid's sides, listed
// with the types interleaved (a Medit file groups them).
CellMesh hex_pyramid_tet() {
    const Grid g{1, 1, 1};  // point x + 2y + 4z
    std::vector<double> xyz = g.points();
    xyz.insert(xyz.end(), {0.5, 0.5, 1.5, 0.5, -0.5, 1.2, 1.5, 0.5, 1.2});  // apex 8, tips 9 and 10
    CellMesh m{awkward(xyz, false), {}, {}};
    m.add(CellType::Tetrahedron, {4, 5, 8, 9});
    m.add(CellType::Hexahedron, {0, 1, 3, 2, 4, 5, 7, 6});
    m.add(CellType::Tetrahedron, {5, 7, 8, 10});
    m.add(CellType::Pyramid, {4, 5, 7, 6, 8});
    return m;
}

// Two quadrilaterals with two triangles on top, interleaved.
CellMesh quad_tri() {
    CellMesh m{awkward({0, 0, 0, 1, 0, 0, 2, 0, 0, 0, 1, 0, 1, 1, 0, 2, 1, 0, 1, 2, 0}, true), {}, {}};
    m.add(CellType::Triangle, {3, 4, 6});
    m.add(CellType::Quadrilateral, {0, 1, 4, 3});
    m.add(CellType::Triangle, {4, 5, 6});
    m.add(CellType::Quadrilateral, {1, 2, 5, 4});
    return m;
}

Mesh build(const CellMesh& m) { return Mesh::from_cells(m.xyz, m.types, m.cells); }

// Every cell mirrored (CellInfo::mirror): a file of the mirror convention.
CellMesh mirrored(CellMesh m) {
    std::size_t at = 0;
    for (CellType type : m.types) {
        const CellInfo& info = cell_info(type);
        const std::vector<VertexId> cell(m.cells.begin() + at, m.cells.begin() + at + info.corners);
        for (int i = 0; i < info.corners; ++i) m.cells[at + i] = cell[info.mirror[i]];
        at += info.corners;
    }
    return m;
}

struct Case {
    const char* name;
    CellMesh (*make)();
};
std::ostream& operator<<(std::ostream& out, const Case& c) { return out << c.name; }
const Case kCases[] = {{"quadrilaterals", quadrilaterals}, {"hexahedra", hexahedra},
                       {"wedges", wedges},                 {"pyramids", pyramids},
                       {"hex_pyramid_tet", hex_pyramid_tet}, {"quad_tri", quad_tri}};
const Case k3dCases[] = {{"hexahedra", hexahedra}, {"wedges", wedges}, {"pyramids", pyramids},
                         {"hex_pyramid_tet", hex_pyramid_tet}};

struct Target {
    const char* name;
    Encoding encoding;
    bool medit;  // no fields but `ref`, no fixed flags, cells grouped by type
};
const Target kTargets[] = {{"a.vtk", Encoding::Ascii, false}, {"b.vtk", Encoding::Binary, false},
                           {"c.vtu", Encoding::Ascii, false}, {"d.vtu", Encoding::Binary, false},
                           {"e.msh", Encoding::Ascii, false}, {"f.msh", Encoding::Binary, false},
                           {"g.mesh", Encoding::Ascii, true}};

// The cell order of a Medit file: grouped by type, in mesh order within a type.
std::vector<ElementId> medit_order(const Mesh& mesh) {
    std::vector<ElementId> order(static_cast<std::size_t>(mesh.num_cells()));
    for (std::size_t c = 0; c < order.size(); ++c) order[c] = static_cast<ElementId>(c);
    std::stable_sort(order.begin(), order.end(), [&](ElementId a, ElementId b) { return mesh.cell_type(a) < mesh.cell_type(b); });
    return order;
}

void check_same_cells(const fuzz::Cells& a, const fuzz::Cells& b) {
    BOOST_TEST((a.types == b.types));
    BOOST_TEST(a.vertices == b.vertices, boost::test_tools::per_element());
}

const Field& field(const MeshFile& file, const char* name, bool cell) {
    const Field* f = cell ? file.cell_field(name) : file.point_field(name);
    BOOST_REQUIRE_MESSAGE(f, "no field " << name);
    return *f;
}

// Two hexahedra side by side in each format, for the hostile inputs: hex 1 is the second cell.
const Grid kTwo{2, 1, 1};
const std::vector<VertexId> kTwoHexes = {0, 1, 4, 3, 6, 7, 10, 9, 1, 2, 5, 4, 7, 8, 11, 10};

std::string number(double value) {
    char digits[32];
    return std::string(digits, std::to_chars(digits, digits + sizeof digits, value).ptr);
}
std::string points_text(std::string_view end_of_line) {
    std::string t;
    const std::vector<double> xyz = kTwo.points();
    for (std::size_t i = 0; i < xyz.size(); i += 3)
        t += number(xyz[i]) + " " + number(xyz[i + 1]) + " " + number(xyz[i + 2]) + std::string(end_of_line) + "\n";
    return t;
}
std::string ids(std::size_t cell, int base) {
    std::string t;
    for (std::size_t i = 0; i < 8; ++i) t += " " + std::to_string(kTwoHexes[8 * cell + i] + base);
    return t;
}
std::string vtk_hexes() {
    return "# vtk DataFile Version 2.0\nhexes\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 12 double\n" + points_text("") +
           "CELLS 2 18\n8" + ids(0, 0) + "\n8" + ids(1, 0) + "\nCELL_TYPES 2\n12\n12\n";
}
std::string vtu_hexes() {
    std::string t = "<VTKFile type=\"UnstructuredGrid\">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\"12\" "
                    "NumberOfCells=\"2\">\n<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n" +
                    points_text("") + "</DataArray></Points>\n<Cells>\n";
    t += "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">" + ids(0, 0) + ids(1, 0) + "</DataArray>\n";
    t += "<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">8 16</DataArray>\n";
    t += "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">12 12</DataArray>\n";
    return t + "</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
}
std::string gmsh_hexes() {
    std::string t = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n12\n";
    const std::vector<double> xyz = kTwo.points();
    for (std::size_t v = 0; v < 12; ++v)
        t += std::to_string(v + 1) + " " + number(xyz[3 * v]) + " " + number(xyz[3 * v + 1]) + " " + number(xyz[3 * v + 2]) + "\n";
    return t + "$EndNodes\n$Elements\n2\n11 5 2 0 1" + ids(0, 1) + "\n12 5 2 0 1" + ids(1, 1) + "\n$EndElements\n";
}
std::string medit_hexes() {
    return "MeshVersionFormatted 2\nDimension 3\nVertices\n12\n" + points_text(" 0") + "Hexahedra\n2\n" + ids(0, 1).substr(1) +
           " 0\n" + ids(1, 1).substr(1) + " 0\nEnd\n";
}

}  // namespace

BOOST_AUTO_TEST_SUITE(cells)

BOOST_AUTO_TEST_CASE(the_test_meshes_are_valid) {
    for (const Case& c : kCases) {
        BOOST_TEST_CONTEXT(c.name) {
            const Mesh mesh = build(c.make());
            BOOST_TEST(mesh.has_cells());
            BOOST_TEST(count_orientations(mesh).inverted == 0);
            BOOST_TEST(count_orientations(mesh).degenerate == 0);
            // A planar mesh's normal follows its cells: mirrored, it is as valid.
            const ElementId inverted = mesh.kind() == ElementKind::Tetrahedron ? mesh.num_cells() : 0;
            BOOST_TEST(count_orientations(build(mirrored(c.make()))).inverted == inverted);
        }
    }
}

// Coordinates bit for bit, cell types and vertices, point and cell fields and fixed flags are
// what was written, in every format and encoding. A Medit file holds a section per type (the
// cells come back grouped by type) and no fields but `ref`; its fixed flags are the boundary.
BOOST_DATA_TEST_CASE(every_cell_type_round_trips_through_every_format, bdata::make(kCases), c) {
    Mesh mesh = build(c.make());
    std::vector<std::uint8_t> fixed(static_cast<std::size_t>(mesh.num_vertices()));
    for (std::size_t v = 0; v < fixed.size(); ++v) fixed[v] = v % 3 == 0;
    mesh.set_fixed(fixed);
    const auto n = static_cast<std::size_t>(mesh.num_vertices()), m = static_cast<std::size_t>(mesh.num_cells());
    std::vector<Field> points{{"temperature", 1, {}}, {"velocity", 3, {}}};
    for (std::size_t v = 0; v < n; ++v) {
        points[0].values.push_back(v / 3.0);
        points[1].values.insert(points[1].values.end(), {-0.0, std::sqrt(v + 2.0), 1e-310 * v});
    }
    std::vector<Field> cells{{"quality", 1, {}}, {"ref", 1, {}}};
    for (std::size_t i = 0; i < m; ++i) {
        cells[0].values.push_back(0.1 + i / 7.0);
        cells[1].values.push_back(static_cast<double>(i % 3 + 1));
    }
    const ScratchDir dir(std::string("cells_round_trip_") + c.name);
    for (const Target& target : kTargets) {
        BOOST_TEST_CONTEXT(c.name << " -> " << target.name) {
            WriteOptions options;
            options.encoding = target.encoding;
            write_mesh(dir / target.name, mesh, options, points, cells);
            const MeshFile copy = read_mesh(dir / target.name);
            BOOST_TEST(copy.mesh.has_cells());
            BOOST_TEST((copy.mesh.kind() == mesh.kind()));
            BOOST_TEST(!copy.orientation.flipped);
            BOOST_TEST(same_bits(copy.mesh.coordinates(), mesh.coordinates()));
            const std::vector<ElementId> order = target.medit ? medit_order(mesh) : std::vector<ElementId>{};
            check_same_cells(fuzz::cells_of(copy.mesh), fuzz::cells_of(mesh, order));
            BOOST_REQUIRE_EQUAL(field(copy, "ref", true).values.size(), m);
            for (std::size_t i = 0; i < m; ++i)
                BOOST_TEST(field(copy, "ref", true).values[i] == cells[1].values[order.empty() ? i : order[i]]);
            if (target.medit) {
                BOOST_TEST(std::ranges::equal(copy.mesh.fixed(), boundary_vertices(mesh)));
                continue;
            }
            BOOST_TEST(std::ranges::equal(copy.mesh.fixed(), mesh.fixed()));
            BOOST_TEST(same_bits(field(copy, "temperature", false).values, points[0].values));
            BOOST_TEST(field(copy, "velocity", false).components == 3);
            BOOST_TEST(same_bits(field(copy, "velocity", false).values, points[1].values));
            BOOST_TEST(same_bits(field(copy, "quality", true).values, cells[0].values));
        }
    }
}

// A file whose every cell is mirrored is flipped on reading in every format (3D cells: a planar
// mesh's orientation follows its own cells), and written back in its own order.
BOOST_DATA_TEST_CASE(a_mirrored_file_is_flipped_on_reading_and_written_back_as_it_was, bdata::make(k3dCases), c) {
    const Mesh original = build(c.make());
    const Mesh mirror = build(mirrored(c.make()));
    ReadOptions as_is;
    as_is.orientation = OrientationMode::AsIs;
    const ScratchDir dir(std::string("cells_mirrored_") + c.name);
    for (const Target& target : kTargets) {
        BOOST_TEST_CONTEXT(c.name << " -> " << target.name) {
            WriteOptions options;
            options.encoding = target.encoding;
            write_mesh(dir / target.name, mirror, options);
            const MeshFile read = read_mesh(dir / target.name);
            BOOST_TEST(read.orientation.flipped);
            BOOST_TEST(read.mesh.elements_flipped());
            const std::vector<ElementId> order = target.medit ? medit_order(original) : std::vector<ElementId>{};
            check_same_cells(fuzz::cells_of(read.mesh), fuzz::cells_of(original, order));
            BOOST_TEST(count_orientations(read.mesh).inverted == 0);
            BOOST_TEST(count_orientations(read_mesh(dir / target.name, as_is).mesh).inverted == original.num_cells());
            const std::string again = std::string("again_") + target.name;
            write_mesh(dir / again, read.mesh, options);
            check_same_cells(fuzz::cells_of(read_mesh(dir / again, as_is).mesh), fuzz::cells_of(mirror, order));
        }
    }
}

struct SharedCells {
    const char* path;
    VertexId vertices;
    std::map<CellType, ElementId> cells;
};
std::ostream& operator<<(std::ostream& out, const SharedCells& s) { return out << s.path; }
const SharedCells kShared[] = {
    {"mesquite/hexes/1000hex-block-internal-bias.vtk", 1331, {{CellType::Hexahedron, 1000}}},
    {"mesquite/hexes/cub_fru.vtk", 12753, {{CellType::Hexahedron, 10752}}},
    {"mesquite/hexes/hex_5_tangled.vtk", 216, {{CellType::Hexahedron, 125}}},
    {"mesquite/hexes/hexes_4by2by2.vtk", 45, {{CellType::Hexahedron, 16}}},
    {"mesquite/hexes/large_box_hex_1000.vtk", 1331, {{CellType::Hexahedron, 1000}}},
    {"mesquite/hexes/sph-10-zsquare.vtk", 247, {{CellType::Quadrilateral, 216}}},  // a quad surface, in hexes/
    {"mesquite/quads/hole_in_square.vtk", 168, {{CellType::Quadrilateral, 140}}},
    {"mesquite/quads/horse20x10_2_4.vtk", 231, {{CellType::Quadrilateral, 200}}},
    {"mesquite/quads/inverted-hole-1.vtk", 96, {{CellType::Quadrilateral, 64}}},
    {"mesquite/quads/quads_4by2.vtk", 15, {{CellType::Quadrilateral, 8}}},
    {"mesquite/quads/tangled_horse1.vtk", 231, {{CellType::Quadrilateral, 200}}},
    {"mesquite/quads/tangled_quad.vtk", 36, {{CellType::Quadrilateral, 25}}},
    {"mesquite/prisms/6-wedge-prism.vtk", 14, {{CellType::Wedge, 6}}},
    {"mesquite/pyramids/12-pyramid-unit-sphere.vtk", 15, {{CellType::Pyramid, 12}}},
    {"mesquite/mixed/hybrid_3quad_1tri_tangled.vtk", 9, {{CellType::Quadrilateral, 3}, {CellType::Triangle, 1}}},
    {"mesquite/mixed/mixed-hex-pyr-tet.vtk",
     683,
     {{CellType::Hexahedron, 305}, {CellType::Pyramid, 190}, {CellType::Tetrahedron, 445}}},
};

// Every shared mesh of cells is read with its cells' types and counts, and survives a round trip
// through every format.
BOOST_DATA_TEST_CASE(shared_meshes_of_cells_are_read_and_round_trip, bdata::make(kShared), shared) {
    const MeshFile file = read_mesh(shared_data(shared.path));
    BOOST_TEST(file.mesh.has_cells());
    BOOST_TEST(file.mesh.num_vertices() == shared.vertices);
    std::map<CellType, ElementId> counts;
    for (CellType type : file.mesh.cell_types()) ++counts[type];
    BOOST_TEST((counts == shared.cells));
    for (const Field& f : file.cell_fields)
        BOOST_TEST(f.values.size() == static_cast<std::size_t>(file.mesh.num_cells() * f.components));
    // Mesquite's `fixed` flags, in float, int and bit arrays.
    if (const Field* fixed = file.point_field("fixed")) {
        BOOST_TEST(file.fixed_from_file);
        for (std::size_t v = 0; v < fixed->values.size(); ++v) BOOST_TEST(file.mesh.fixed()[v] == (fixed->values[v] != 0.0));
    }
    const ScratchDir dir("cells_shared");
    for (const Target& target : kTargets) {
        BOOST_TEST_CONTEXT(shared.path << " -> " << target.name) {
            WriteOptions options;
            options.encoding = target.encoding;
            write_mesh(dir / target.name, file.mesh, options);
            const MeshFile copy = read_mesh(dir / target.name);
            BOOST_TEST(copy.orientation.flipped == file.orientation.flipped);
            BOOST_TEST(same_bits(copy.mesh.coordinates(), file.mesh.coordinates()));
            const std::vector<ElementId> order = target.medit ? medit_order(file.mesh) : std::vector<ElementId>{};
            check_same_cells(fuzz::cells_of(copy.mesh), fuzz::cells_of(file.mesh, order));
            if (!target.medit) BOOST_TEST(std::ranges::equal(copy.mesh.fixed(), file.mesh.fixed()));
        }
    }
}

// The pyramid file stores its `fixed` flags as VTK bits: 1 for the 14 points on the sphere, 0
// for the centre.
BOOST_AUTO_TEST_CASE(bit_arrays_are_read) {
    const MeshFile file = read_mesh(shared_data("mesquite/pyramids/12-pyramid-unit-sphere.vtk"));
    BOOST_TEST(file.mesh.num_free_vertices() == 1);
    BOOST_TEST(file.mesh.fixed()[14] == 0);
    // Binary: packed 8 to a byte, the first value in the high bit (here 1 0 1 1 0 0 0 0, 0 1).
    const ScratchDir dir("cells_bits");
    WriteOptions binary;
    binary.encoding = Encoding::Binary;
    write_mesh(dir / "tet.vtk", build(hex_pyramid_tet()), binary);
    std::string text = read_text(dir / "tet.vtk");
    text = text.substr(0, text.find("POINT_DATA")) + "POINT_DATA 11\nSCALARS b bit 1\nLOOKUP_TABLE default\n";
    text += std::string{static_cast<char>(0xB0), static_cast<char>(0x40)} + "\n";
    write_file(dir / "bits.vtk", text);
    const MeshFile bits = read_mesh(dir / "bits.vtk");
    const std::vector<double> expected = {1, 0, 1, 1, 0, 0, 0, 0, 0, 1, 0};
    BOOST_TEST(field(bits, "b", false).values == expected, boost::test_tools::per_element());
}

// Polyhedra and second-order cells are refused by name, with the types that are handled.
BOOST_AUTO_TEST_CASE(other_cell_types_are_refused_by_name) {
    const ScratchDir dir("cells_refused");
    check_error_text(dir, "polyhedron.vtk", replaced(vtk_hexes(), "12\n12\n", "12\n42\n"),
                     {":23:", "cell 1 has VTK type 42 (polyhedron); Paloverde handles triangle (5), quadrilateral (9), "
                              "tetrahedron (10), hexahedron (12), wedge (13) and pyramid (14)"});
    check_error_text(dir, "hex20.vtu", replaced(vtu_hexes(), ">12 12<", ">12 25<"),
                     {"cell 1 has VTK type 25 (quadratic hexahedron); Paloverde handles"});
    check_error_text(dir, "hex27.msh", replaced(gmsh_hexes(), "12 5 2 0 1", "12 12 2 0 1"),
                     {"element 12 has type 12 (27-node second-order hexahedron)", "gmsh -order 1"});
}

// A hexahedron that refers to a point out of range, repeats one, or is cut short: a FileError
// naming the file and the cell, in every format.
BOOST_AUTO_TEST_CASE(hostile_hexahedra_are_refused_naming_the_cell) {
    const ScratchDir dir("cells_hostile");
    for (const auto& [name, text] : {std::pair{"good.vtk", vtk_hexes()}, {"good.vtu", vtu_hexes()},
                                     {"good.msh", gmsh_hexes()}, {"good.mesh", medit_hexes()}}) {
        write_file(dir / name, text);
        BOOST_TEST(read_mesh(dir / name).mesh.num_cells() == 2, name);
    }
    // Out of range.
    check_error_text(dir, "range.vtk", replaced(vtk_hexes(), "8 1 2 5 4 7 8 11 10", "8 1 2 5 4 7 8 11 99"),
                     {":20:", "cell 1 refers to point 99, outside 0..11"});
    check_error_text(dir, "range.vtu", replaced(vtu_hexes(), " 11 10<", " 11 99<"),
                     {"cell 1 refers to point 99, outside 0..11"});
    check_error_text(dir, "range.msh", replaced(gmsh_hexes(), "9 12 11\n", "9 12 99\n"),
                     {":22:", "element 12 refers to node 99, which is not in $Nodes"});
    check_error_text(dir, "range.mesh", replaced(medit_hexes(), "9 12 11 0", "9 12 99 0"),
                     {":20:", "hexahedron 2 refers to vertex 99; vertices are numbered 1 to 12"});
    // A repeated vertex.
    check_error_text(dir, "repeat.vtk", replaced(vtk_hexes(), "8 1 2 5 4 7 8 11 10", "8 1 2 5 4 7 8 11 4"),
                     {"cell 1 (hexahedron) repeats vertex 4"});
    check_error_text(dir, "repeat.vtu", replaced(vtu_hexes(), " 11 10<", " 11 4<"), {"cell 1 (hexahedron) repeats vertex 4"});
    check_error_text(dir, "repeat.msh", replaced(gmsh_hexes(), "9 12 11\n", "9 12 5\n"),
                     {"element 12 (hexahedron) repeats vertex 4"});
    check_error_text(dir, "repeat.mesh", replaced(medit_hexes(), "9 12 11 0", "9 12 5 0"),
                     {"hexahedron 2 repeats vertex 4"});
    // Cut short. Where the declared counts no longer fit in what is left, that is the message;
    // padded so that they do, the end of the file names the cell it cuts.
    const std::string vtk_cut = vtk_hexes().substr(0, vtk_hexes().find("7 8 11 10"));
    check_error_text(dir, "cut.vtk", vtk_cut, {":18:", "the CELLS size of 18 cannot fit"});
    check_error_text(dir, "padded.vtk", vtk_cut + std::string(40, ' '),
                     {"unexpected end of file", "(in cell 1)"});
    check_error_text(dir, "cut.vtu", replaced(vtu_hexes(), " 7 8 11 10<", "<"),
                     {"offset 16 of cell 1", "connectivity size (12)"});
    const std::string gmsh_cut = gmsh_hexes().substr(0, gmsh_hexes().find("9 12 11"));
    check_error_text(dir, "cut.msh", gmsh_cut, {"unexpected end of file", "(in element 12)"});
    const std::string medit_cut = medit_hexes().substr(0, medit_hexes().find("9 12 11"));
    check_error_text(dir, "cut.mesh", medit_cut, {"the number of hexahedra of 2 cannot fit"});
    check_error_text(dir, "padded.mesh", medit_cut + std::string(40, ' '), {"unexpected end of file", "(in hexahedron 2)"});
    // A cell list shorter than it says, followed by the next section.
    check_error_text(dir, "short.vtk", replaced(vtk_hexes(), "CELLS 2 18", "CELLS 3 27") + std::string(40, ' '),
                     {"found 'CELL_TYPES'", "(in cell 2)"});
    check_error_text(dir, "short.msh", replaced(gmsh_hexes(), "$Elements\n2\n", "$Elements\n3\n"),
                     {"found '$EndElements'", "(in element number 3 of the list)"});
}

// A face of three cells no vertex placement can make valid: refused in every format, naming the
// face and the cells.
BOOST_AUTO_TEST_CASE(a_face_of_three_cells_is_refused) {
    const Grid g{1, 1, 3};  // point x + 2y + 4z
    CellMesh m{g.points(), {}, {}};
    m.add(CellType::Hexahedron, {0, 1, 3, 2, 4, 5, 7, 6});
    m.add(CellType::Hexahedron, {4, 5, 7, 6, 8, 9, 11, 10});
    m.add(CellType::Hexahedron, {4, 5, 7, 6, 12, 13, 15, 14});
    const Mesh mesh = build(m);
    const ScratchDir dir("cells_non_manifold");
    for (const Target& target : kTargets) {
        write_mesh(dir / target.name, mesh);
        check_error(dir / target.name, {"the face of vertices 4, 5, 6 and 7 belongs to 3 cells (0, 1 and 2)", "non-manifold"});
    }
}

BOOST_AUTO_TEST_SUITE_END()
