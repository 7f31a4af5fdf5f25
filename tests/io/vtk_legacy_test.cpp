#include <boost/test/unit_test.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <initializer_list>
#include <iterator>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "paloverde/core/error.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/mesh.hpp"
#include "support/io_checks.hpp"
#include "support/test_support.hpp"

namespace fs = std::filesystem;
using namespace paloverde;
using namespace paloverde::test;

namespace {

struct SharedMesh {
    const char* path;
    VertexId vertices;
    ElementId elements;
};

const SharedMesh kSharedTets[] = {
    {"mesquite/tets/tire.vtk", 2570, 11098},
    {"mesquite/tets/cube-clip-5.vtk", 3408, 16637},
    {"mesquite/tets/flat-tet-sphere.vtk", 4793, 23636},
    {"mesquite/tets/cub_wedge_like.vtk", 21156, 112393},
    {"mesquite/tets/tet_4_tangled.vtk", 129, 408},
    {"mesquite/tets/tet_1.vtk", 5, 4},
    {"mesquite/tets/tet_2_with_bound.vtk", 27, 49},
    {"mesquite/tets/two_tets.vtk", 5, 2},
    {"mesquite/tets/two_tets_shape.vtk", 7, 2},
};

const SharedMesh kSharedTriangles[] = {
    {"mesquite/tris/bad_circle_tri.vtk", 33, 48},  {"mesquite/tris/equil_tri.vtk", 7, 6},
    {"mesquite/tris/shashkov.vtk", 4225, 8192},    {"mesquite/tris/tangled_tri.vtk", 40, 58},
    {"mesquite/tris/tri_20258.vtk", 10300, 20258}, {"mesquite/tris/tri_5_xz.vtk", 80, 130},
};

// Builds BINARY legacy files: text headers and big-endian values.
struct BigEndian {
    std::string data;
    BigEndian& text(std::string_view s) {
        data += s;
        return *this;
    }
    template <class T>
    BigEndian& put(T value) {
        char b[sizeof(T)];
        std::memcpy(b, &value, sizeof value);
        const std::uint16_t probe = 1;
        if (*reinterpret_cast<const unsigned char*>(&probe) == 1) std::reverse(b, b + sizeof b);
        data.append(b, sizeof b);
        return *this;
    }
    BigEndian& i32(std::int32_t v) { return put(v); }
    BigEndian& i64(std::int64_t v) { return put(v); }
    BigEndian& f32(float v) { return put(v); }
    BigEndian& f64(double v) { return put(v); }
};

// Writes `text` to a new .vtk file in `dir`; reading it must fail as check_error expects.
void check_error_text(const ScratchDir& dir, const std::string& text, std::initializer_list<std::string_view> fragments) {
    check_error_in_new_file(dir, ".vtk", text, fragments);
}

std::size_t count_nonzero(const Field& f) {
    return static_cast<std::size_t>(std::count_if(f.values.begin(), f.values.end(), [](double v) { return v != 0.0; }));
}

std::size_t count_fixed(const Mesh& mesh) {
    return static_cast<std::size_t>(std::count(mesh.fixed().begin(), mesh.fixed().end(), std::uint8_t{1}));
}

// A valid two-tetrahedron file; the bad-input tests each break one thing in it.
const std::string kTwoTets =
    "# vtk DataFile Version 2.0\n"  // 1
    "two tets\n"                    // 2
    "ASCII\n"                       // 3
    "DATASET UNSTRUCTURED_GRID\n"   // 4
    "POINTS 5 float\n"              // 5
    "0 0 0\n"                       // 6
    "1 0 0\n"                       // 7
    "0 1 0\n"                       // 8
    "0 0 1\n"                       // 9
    "1 1 1\n"                       // 10
    "CELLS 2 10\n"                  // 11
    "4 0 1 2 3\n"                   // 12
    "4 1 2 3 4\n"                   // 13
    "CELL_TYPES 2\n"                // 14
    "10\n"                          // 15
    "10\n"                          // 16
    "POINT_DATA 5\n"                // 17
    "SCALARS fixed int\n"           // 18
    "LOOKUP_TABLE default\n"        // 19
    "1 1 1 1 0\n"                   // 20
    "CELL_DATA 2\n"                 // 21
    "SCALARS quality double 1\n"    // 22
    "LOOKUP_TABLE default\n"        // 23
    "0.5 0.25\n";                   // 24

}  // namespace

BOOST_AUTO_TEST_SUITE(vtk_legacy)

BOOST_AUTO_TEST_CASE(reads_every_shared_tetrahedral_mesh) {
    for (const SharedMesh& shared : kSharedTets) {
        BOOST_TEST_CONTEXT(shared.path) {
            const MeshFile file = read_mesh(shared_data(shared.path));
            BOOST_TEST((file.mesh.kind() == ElementKind::Tetrahedron));
            BOOST_TEST(file.mesh.num_vertices() == shared.vertices);
            BOOST_TEST(file.mesh.num_elements() == shared.elements);
            BOOST_TEST(file.fixed_from_file);
            const Field* fixed = file.point_field("fixed");
            BOOST_REQUIRE(fixed);
            BOOST_TEST(fixed->components == 1);
            BOOST_TEST(count_fixed(file.mesh) == count_nonzero(*fixed));
            BOOST_TEST(count_fixed(file.mesh) > 0u);
        }
    }
}

BOOST_AUTO_TEST_CASE(reads_every_shared_triangle_mesh) {
    for (const SharedMesh& shared : kSharedTriangles) {
        BOOST_TEST_CONTEXT(shared.path) {
            const MeshFile file = read_mesh(shared_data(shared.path));
            BOOST_TEST((file.mesh.kind() == ElementKind::Triangle));
            BOOST_TEST(file.mesh.num_vertices() == shared.vertices);
            BOOST_TEST(file.mesh.num_elements() == shared.elements);
            BOOST_TEST(file.fixed_from_file);
            BOOST_TEST(count_fixed(file.mesh) == count_nonzero(*file.point_field("fixed")));
        }
    }
}

BOOST_AUTO_TEST_CASE(shared_quad_mesh_is_read_as_quadrilaterals) {
    // horseshoe.vtk (in tris/) holds quadrilaterals (VTK type 9).
    const MeshFile file = read_mesh(shared_data("mesquite/tris/horseshoe.vtk"));
    BOOST_TEST(file.mesh.has_cells());
    BOOST_TEST(file.mesh.num_cells() == 4);
    for (ElementId c = 0; c < file.mesh.num_cells(); ++c) BOOST_TEST((file.mesh.cell_type(c) == CellType::Quadrilateral));
}

BOOST_AUTO_TEST_CASE(values_and_fields_of_a_shared_mesh) {
    const MeshFile file = read_mesh(shared_data("mesquite/tets/flat-tet-sphere.vtk"));
    // POINTS 4793 double; the first point is "-4.8 0.1 -5.816880181e-16".
    BOOST_TEST(file.mesh.coordinates()[0] == -4.8);
    BOOST_TEST(file.mesh.coordinates()[1] == 0.1);
    BOOST_TEST(file.mesh.coordinates()[2] == -5.816880181e-16);
    // SCALARS GLOBAL_ID int 1 becomes the global ids ("1" first, "4501" last in the file).
    BOOST_TEST(file.mesh.global_ids()[0] == 1);
    BOOST_TEST(file.mesh.global_ids()[4792] == 4501);
    const Field* cell_ids = file.cell_field("GLOBAL_ID");
    BOOST_REQUIRE(cell_ids);
    BOOST_TEST(cell_ids->values.size() == 23636u);
    BOOST_TEST(cell_ids->values[3] == 4.0);
    // tet_1.vtk: first tet "4 3 2 1 0", point 0 free, the others fixed.
    const MeshFile tet = read_mesh(shared_data("mesquite/tets/tet_1.vtk"));
    const std::vector<VertexId> first(tet.mesh.element(0).begin(), tet.mesh.element(0).end());
    BOOST_TEST((first == std::vector<VertexId>{3, 2, 1, 0}));
    BOOST_TEST(tet.mesh.fixed()[0] == 0);
    BOOST_TEST(tet.mesh.fixed()[1] == 1);
}

BOOST_AUTO_TEST_CASE(round_trips_every_shared_mesh_in_ascii_and_binary) {
    ScratchDir dir("vtk_legacy_round_trip");
    std::vector<SharedMesh> all(std::begin(kSharedTets), std::end(kSharedTets));
    all.insert(all.end(), std::begin(kSharedTriangles), std::end(kSharedTriangles));
    for (const SharedMesh& shared : all) {
        const MeshFile original = read_mesh(shared_data(shared.path));
        const Mesh& mesh = original.mesh;
        // Values that only survive a text round trip with 17 significant digits.
        Field quality{"quality", 1, {}};
        for (ElementId e = 0; e < mesh.num_elements(); ++e) quality.values.push_back(1.0 / (3.0 + e) - 1e-300 * e);
        Field velocity{"velocity", 3, {}};
        for (double x : mesh.coordinates()) velocity.values.push_back(std::nextafter(x * std::numbers::pi, 1e300));
        velocity.values[0] = 4.9e-324;
        velocity.values[1] = -0.0;
        const std::vector<Field> point_fields{velocity};
        const std::vector<Field> cell_fields{quality};
        for (Encoding encoding : {Encoding::Ascii, Encoding::Binary}) {
            BOOST_TEST_CONTEXT(shared.path << (encoding == Encoding::Ascii ? " ascii" : " binary")) {
                const fs::path path = dir / "copy.vtk";
                WriteOptions options;
                options.encoding = encoding;
                write_mesh(path, mesh, options, point_fields, cell_fields);
                const MeshFile copy = read_mesh(path);
                BOOST_TEST((copy.mesh.kind() == mesh.kind()));
                BOOST_TEST(same_bits(copy.mesh.coordinates(), mesh.coordinates()));
                BOOST_TEST(std::ranges::equal(copy.mesh.connectivity(), mesh.connectivity()));
                BOOST_TEST(copy.fixed_from_file);
                BOOST_TEST(std::ranges::equal(copy.mesh.fixed(), mesh.fixed()));
                const Field* q = copy.cell_field("quality");
                const Field* v = copy.point_field("velocity");
                BOOST_REQUIRE(q);
                BOOST_REQUIRE(v);
                BOOST_TEST(q->components == 1);
                BOOST_TEST(v->components == 3);
                BOOST_TEST(same_bits(q->values, quality.values));
                BOOST_TEST(same_bits(v->values, velocity.values));
            }
        }
    }
}

BOOST_AUTO_TEST_CASE(writes_a_classic_header_that_old_readers_accept) {
    ScratchDir dir("vtk_legacy_header");
    const MeshFile file = read_mesh(shared_data("mesquite/tets/two_tets.vtk"));
    const std::vector<Field> point_fields{{"my field", 1, {1, 2, 3, 4, 5}}, {"dir", 2, std::vector<double>(10, 0.5)}};
    const std::vector<Field> cell_fields{{"q", 1, {0.1, 0.2}}};
    WriteOptions options;
    options.encoding = Encoding::Ascii;
    write_mesh(dir / "out.vtk", file.mesh, options, point_fields, cell_fields);
    const std::string text = read_text(dir / "out.vtk");
    BOOST_TEST(text.starts_with("# vtk DataFile Version 3.0\n"));
    BOOST_TEST(text.find("\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 5 double\n") != std::string::npos);
    BOOST_TEST(text.find("\nCELLS 2 10\n4 ") != std::string::npos);
    BOOST_TEST(text.find("\nCELL_TYPES 2\n10\n10\n") != std::string::npos);
    BOOST_TEST(text.find("\nPOINT_DATA 5\nSCALARS my_field double 1\nLOOKUP_TABLE default\n") != std::string::npos);
    BOOST_TEST(text.find("\nSCALARS fixed double 1\nLOOKUP_TABLE default\n") != std::string::npos);
    BOOST_TEST(text.find("\nFIELD FieldData 1\ndir 2 5 double\n") != std::string::npos);
    BOOST_TEST(text.find("\nCELL_DATA 2\nSCALARS q double 1\n") != std::string::npos);
    BOOST_TEST(text.find("0.10000000000000001") != std::string::npos);  // 17 significant digits
    BOOST_TEST(text.find("OFFSETS") == std::string::npos);
    const MeshFile copy = read_mesh(dir / "out.vtk");
    BOOST_REQUIRE(copy.point_field("my_field"));
    BOOST_TEST(copy.point_field("my_field")->values[4] == 5.0);
    BOOST_TEST(copy.point_field("dir")->components == 2);

    options.encoding = Encoding::Binary;
    write_mesh(dir / "out.vtk", file.mesh, options, point_fields, cell_fields);
    const std::string bytes = read_text(dir / "out.vtk");
    BOOST_TEST(bytes.starts_with("# vtk DataFile Version 3.0\nWritten by Paloverde\nBINARY\n"));
    BOOST_TEST(bytes.find("\nCELLS 2 10\n") != std::string::npos);
}

BOOST_AUTO_TEST_CASE(reads_the_vtk_5_cells_form_with_metadata) {
    ScratchDir dir("vtk_legacy_51");
    const std::string text =
        "# vtk DataFile Version 5.1\n"
        "written by VTK 9\n"
        "ASCII\n"
        "DATASET UNSTRUCTURED_GRID\n"
        "FIELD FieldData 1\n"
        "TimeValue 1 1 double\n"
        "2.5\n"
        "POINTS 5 float\n"
        "0 0 0 1 0 0 0 1 0\n"
        "0 0 1 1 1 1\n"
        "METADATA\n"
        "INFORMATION 0\n"
        "\n"
        "CELLS 4 9\n"
        "OFFSETS vtktypeint64\n"
        "0 4 8 9\n"
        "CONNECTIVITY vtktypeint64\n"
        "0 1 2 3\n"
        "1 2 3 4\n"
        "4\n"
        "CELL_TYPES 3\n"
        "10\n"
        "10\n"
        "1\n"
        "CELL_DATA 3\n"
        "FIELD FieldData 2\n"
        "id 1 3 int\n"
        "7 8 9\n"
        "METADATA\n"
        "COMPONENT_NAMES\n"
        "NAME0 x\n"
        "\n"
        "dir 3 3 double\n"
        "1 2 3 4 5 6 7 8 9\n"
        "POINT_DATA 5\n"
        "SCALARS fixed unsigned_char 1\n"
        "LOOKUP_TABLE default\n"
        "1 0 1 1 1\n";
    write_file(dir / "v51.vtk", text);
    const MeshFile file = read_mesh(dir / "v51.vtk");
    BOOST_TEST(file.mesh.num_vertices() == 5);
    BOOST_TEST(file.mesh.num_elements() == 2);
    BOOST_TEST((std::vector<VertexId>(file.mesh.element(1).begin(), file.mesh.element(1).end()) ==
                std::vector<VertexId>{1, 2, 3, 4}));
    BOOST_TEST((file.cell_field("id")->values == std::vector<double>{7, 8}));
    BOOST_TEST((file.cell_field("dir")->values == std::vector<double>{1, 2, 3, 4, 5, 6}));
    BOOST_TEST(file.fixed_from_file);
    BOOST_TEST(file.mesh.fixed()[1] == 0);
    BOOST_TEST(file.point_fields.size() == 1u);  // the dataset's TimeValue is not a point field

    // VTK 9's type names by size read as the classic names of the same sizes (meshio writes them).
    std::string sized = replaced(text, "OFFSETS vtktypeint64", "OFFSETS vtktypeint32");
    sized = replaced(sized, "CONNECTIVITY vtktypeint64", "CONNECTIVITY vtktypeuint32");
    sized = replaced(sized, "id 1 3 int", "id 1 3 vtktypeint16");
    sized = replaced(sized, "dir 3 3 double", "dir 3 3 vtktypefloat32");
    sized = replaced(sized, "SCALARS fixed unsigned_char 1", "SCALARS fixed vtktypeuint8 1");
    write_file(dir / "sized.vtk", sized);
    const MeshFile same = read_mesh(dir / "sized.vtk");
    BOOST_TEST((std::vector<VertexId>(same.mesh.connectivity().begin(), same.mesh.connectivity().end()) ==
                std::vector<VertexId>(file.mesh.connectivity().begin(), file.mesh.connectivity().end())));
    BOOST_TEST((same.cell_field("id")->values == std::vector<double>{7, 8}));
    BOOST_TEST((same.cell_field("dir")->values == std::vector<double>{1, 2, 3, 4, 5, 6}));
    BOOST_TEST((std::vector<std::uint8_t>(same.mesh.fixed().begin(), same.mesh.fixed().end()) ==
                std::vector<std::uint8_t>(file.mesh.fixed().begin(), file.mesh.fixed().end())));
    check_error_text(dir, replaced(text, "OFFSETS vtktypeint64", "OFFSETS vtktypefloat64"), {":15:", "integer type"});

    // Wrong offsets and ids are reported on their line, naming the cell.
    check_error_text(dir, replaced(text, "0 4 8 9\n", "0 4 3 9\n"), {":16:", "offset 2 (3)", "previous offset (4)"});
    check_error_text(dir, replaced(text, "0 4 8 9\n", "1 4 8 9\n"), {":16:", "first offset must be 0"});
    check_error_text(dir, replaced(text, "0 4 8 9\n", "0 4 8 8\n"), {":16:", "cell count/size mismatch"});
    check_error_text(dir, replaced(text, "1 2 3 4\n4\n", "1 2 3 4\n5\n"), {":20:", "cell 2 refers to point 5"});
    check_error_text(dir, replaced(text, "OFFSETS vtktypeint64", "OFFSETS float"), {":15:", "integer type"});
    check_error_text(dir, replaced(text, "OFFSETS vtktypeint64", "OFFSET vtktypeint64"), {":15:", "'OFFSETS'"});
}

BOOST_AUTO_TEST_CASE(reads_binary_files) {
    ScratchDir dir("vtk_legacy_binary");
    // Classic CELLS form; float points, int fixed flags, double vectors, a FIELD array.
    BigEndian b;
    b.text("# vtk DataFile Version 3.0\nbinary\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 5 float\n");
    for (float x : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 1.f, 1.f, 1.f}) b.f32(x);
    b.text("\nCELLS 3 13\n");
    for (int v : {4, 0, 1, 2, 3, 4, 1, 2, 3, 4, 2, 0, 4}) b.i32(v);
    b.text("\nCELL_TYPES 3\n").i32(10).i32(10).i32(3);
    b.text("\nPOINT_DATA 5\nSCALARS fixed int\nLOOKUP_TABLE default\n");
    for (int v : {1, 1, 0, 1, 1}) b.i32(v);
    b.text("\nCELL_DATA 3\nVECTORS normal double\n");
    for (int i = 0; i < 9; ++i) b.f64(0.1 * i);
    b.text("\nFIELD FieldData 1\nlabel 1 3 short\n").put<std::int16_t>(-3).put<std::int16_t>(4).put<std::int16_t>(5);
    b.text("\n");
    write_file(dir / "classic.vtk", b.data);
    const MeshFile file = read_mesh(dir / "classic.vtk");
    BOOST_TEST(file.mesh.num_elements() == 2);
    BOOST_TEST(file.mesh.point(4)[2] == 1.0);
    BOOST_TEST(file.mesh.fixed()[2] == 0);
    BOOST_TEST(file.mesh.fixed()[3] == 1);
    BOOST_TEST((file.cell_field("label")->values == std::vector<double>{-3, 4}));
    BOOST_TEST(file.cell_field("normal")->components == 3);
    BOOST_TEST(file.cell_field("normal")->values[5] == 0.1 * 5);

    // VTK 5.1 form with 64-bit offsets and ids.
    BigEndian n;
    n.text("# vtk DataFile Version 5.1\nbinary\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n");
    for (double x : {0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1.}) n.f64(x);
    n.text("\nCELLS 2 4\nOFFSETS vtktypeint64\n").i64(0).i64(4);
    n.text("\nCONNECTIVITY vtktypeint64\n").i64(3).i64(2).i64(1).i64(0);
    n.text("\nCELL_TYPES 1\n").i32(10).text("\n");
    write_file(dir / "v51.vtk", n.data);
    const MeshFile five = read_mesh(dir / "v51.vtk");
    BOOST_TEST(five.mesh.num_elements() == 1);
    BOOST_TEST(five.mesh.element(0)[0] == 3);
    BOOST_TEST(!five.fixed_from_file);

    // Errors in binary data name the byte.
    std::string bad = b.data;
    const std::size_t id_byte = bad.find("\nCELLS 3 13\n") + 12 + 4 * 7;  // cell 1's second id
    bad[id_byte + 3] = 9;
    write_file(dir / "bad_id.vtk", bad);
    check_error(dir / "bad_id.vtk", {"(byte " + std::to_string(id_byte) + ")", "cell 1 refers to point 9"});

    bad = b.data;
    const std::size_t type_byte = bad.find("\nCELL_TYPES 3\n") + 14 + 4;
    bad[type_byte + 3] = 12;
    write_file(dir / "bad_type.vtk", bad);
    check_error(dir / "bad_type.vtk",
                {"(byte " + std::to_string(type_byte) + ")", "cell 1 has VTK type 12 (hexahedron)"});

    bad = b.data;
    const std::size_t nan_byte = bad.find("POINTS 5 float\n") + 15 + 4 * 7;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    BigEndian nan_bytes;
    nan_bytes.f32(nan);
    bad.replace(nan_byte, 4, nan_bytes.data);
    write_file(dir / "nan.vtk", bad);
    check_error(dir / "nan.vtk", {"(byte " + std::to_string(nan_byte) + ")", "point 2", "non-finite"});

    // Past the first binary block line numbers mean nothing: header errors name the byte too.
    bad = replaced(b.data, "\nCELL_TYPES 3\n", "\nCELL_TYPES 4\n");
    write_file(dir / "bad_count.vtk", bad);
    check_error(dir / "bad_count.vtk",
                {"(byte " + std::to_string(bad.find("\nCELL_TYPES 4\n") + 13) + ")", "CELL_TYPES lists 4"});

    const std::string cut = b.data.substr(0, b.data.find("\nCELLS 3 13\n") + 12 + 20);
    write_file(dir / "cut.vtk", cut);
    check_error(dir / "cut.vtk", {"(byte " + std::to_string(cut.size() - 20) + ")", "ends inside", "52 bytes needed"});
}

BOOST_AUTO_TEST_CASE(mixed_cells_keep_the_highest_dimension_and_narrow_cell_fields) {
    ScratchDir dir("vtk_legacy_mixed");
    const std::string text =
        "# vtk DataFile Version 2.0\nmixed\nASCII\nDATASET UNSTRUCTURED_GRID\n"
        "POINTS 5 int\n0 0 0 1 0 0 0 1 0 0 0 1 1 1 1\n"
        "CELLS 7 24\n1 4\n2 0 4\n3 0 1 2\n4 0 1 2 3\n3 0 1 3\n4 1 2 3 4\n0\n"
        "CELL_TYPES 7\n1 3 5 10 5 10 0\n"
        "CELL_DATA 7\nSCALARS id float\nLOOKUP_TABLE default\n0 1 2 3 4 5 6\n"
        "VECTORS v float\n0 0 0 1 1 1 2 2 2 3 3 3 4 4 4 5 5 5 6 6 6\n";
    write_file(dir / "mixed.vtk", text);
    const MeshFile tets = read_mesh(dir / "mixed.vtk");
    BOOST_TEST((tets.mesh.kind() == ElementKind::Tetrahedron));
    BOOST_TEST(tets.mesh.num_elements() == 2);
    BOOST_TEST((tets.cell_field("id")->values == std::vector<double>{3, 5}));
    BOOST_TEST((tets.cell_field("v")->values == std::vector<double>{3, 3, 3, 5, 5, 5}));

    // Without the tets, the triangles are kept.
    write_file(dir / "tris.vtk", replaced(text, "CELL_TYPES 7\n1 3 5 10 5 10 0\n", "CELL_TYPES 7\n1 3 5 4 5 4 0\n"));
    const MeshFile tris = read_mesh(dir / "tris.vtk");
    BOOST_TEST((tris.mesh.kind() == ElementKind::Triangle));
    BOOST_TEST(tris.mesh.num_elements() == 2);
    BOOST_TEST((tris.cell_field("id")->values == std::vector<double>{2, 4}));
}

BOOST_AUTO_TEST_CASE(reads_every_attribute_kind) {
    ScratchDir dir("vtk_legacy_attributes");
    const std::string text = kTwoTets +
                             "NORMALS n float\n0 0 1 0 0 1\n"
                             "TEXTURE_COORDINATES uv 2 float\n0 0 1 1\n"
                             "TENSORS t double\n1 0 0 0 1 0 0 0 1 2 0 0 0 2 0 0 0 2\n"
                             "COLOR_SCALARS rgb 3\n1 0 0 0 1 0\n"
                             "LOOKUP_TABLE colors 2\n0 0 0 1 1 1 1 1\n"
                             "GLOBAL_IDS gid vtkIdType\n100 101\n"
                             "SCALARS pair%20of%20values long 2\nLOOKUP_TABLE default\n1 2 3 4\n"
                             "POINT_DATA 5\n"
                             "VECTORS vel double\n0 0 0 1 1 1 2 2 2 3 3 3 4 4 4\n"
                             "METADATA\nINFORMATION 1\nNAME L2_NORM_RANGE LOCATION vtkDataArray\nDATA 2 0 6.9282\n\n"
                             "SCALARS w unsigned_short 1\nLOOKUP_TABLE default\n1 2 3 4 5\n";
    write_file(dir / "attributes.vtk", text);
    const MeshFile file = read_mesh(dir / "attributes.vtk");
    BOOST_TEST(file.cell_field("quality")->values[1] == 0.25);
    BOOST_TEST(file.cell_field("n")->components == 3);
    BOOST_TEST(file.cell_field("uv")->components == 2);
    BOOST_TEST(file.cell_field("t")->components == 9);
    BOOST_TEST(file.cell_field("rgb")->components == 3);
    BOOST_TEST(file.cell_field("gid")->values[1] == 101.0);
    BOOST_REQUIRE(file.cell_field("pair of values"));
    BOOST_TEST(file.cell_field("pair of values")->components == 2);
    BOOST_TEST(file.point_field("vel")->values[14] == 4.0);
    BOOST_TEST(file.point_field("w")->values[4] == 5.0);
    BOOST_TEST(file.mesh.fixed()[4] == 0);
}

BOOST_AUTO_TEST_CASE(reads_windows_line_endings_and_lower_case_keywords) {
    ScratchDir dir("vtk_legacy_crlf");
    std::string text;
    for (char c : kTwoTets) text += c == '\n' ? std::string("\r\n") : std::string(1, c);
    // An empty title line, too.
    write_file(dir / "crlf.vtk", replaced(replaced(replaced(text, "two tets", ""), "CELL_TYPES", "cell_types"),
                                          "POINT_DATA", "Point_Data"));
    const MeshFile file = read_mesh(dir / "crlf.vtk");
    BOOST_TEST(file.mesh.num_elements() == 2);
    BOOST_TEST((file.cell_field("quality")->values == std::vector<double>{0.5, 0.25}));
    BOOST_TEST(file.mesh.fixed()[4] == 0);
}

BOOST_AUTO_TEST_CASE(malformed_headers_and_sections) {
    ScratchDir dir("vtk_legacy_bad_headers");
    check_error_text(dir, "", {"empty"});
    check_error_text(dir, "<?xml version=\"1.0\"?>\n", {":1:", "# vtk DataFile Version"});
    check_error_text(dir, "# vtk DataFile Version 2.0\n", {"expected a title line"});
    check_error_text(dir, replaced(kTwoTets, "ASCII", "TEXT"), {":3:", "ASCII or BINARY", "'TEXT'"});
    check_error_text(dir, replaced(kTwoTets, "UNSTRUCTURED_GRID", "POLYDATA"),
                     {":4:", "DATASET POLYDATA", "UNSTRUCTURED_GRID"});
    check_error_text(dir, replaced(kTwoTets, "POINTS 5 float", "POINTS 5 float16"),
                     {":5:", "unsupported data type 'float16'"});
    check_error_text(dir, replaced(kTwoTets, "CELL_DATA 2", "CELL_STUFF 2"), {":21:", "unknown keyword 'CELL_STUFF'"});
    check_error_text(
        dir, replaced(kTwoTets, "SCALARS quality double 1\nLOOKUP_TABLE default\n", "SCALARS quality double 1\n"),
        {":23:", "LOOKUP_TABLE", "'0.5'"});
    check_error_text(dir, replaced(kTwoTets, "SCALARS fixed int", "SCALARS fixed"), {":18:", "SCALARS name type"});
    check_error_text(dir, replaced(kTwoTets, "POINT_DATA 5", "POINT_DATA 6"), {":17:", "POINT_DATA 6", "5 points"});
    check_error_text(dir, replaced(kTwoTets, "CELL_DATA 2", "CELL_DATA 3"), {":21:", "CELL_DATA 3", "2 cells"});
    // Missing sections.
    const std::string no_points = kTwoTets.substr(0, kTwoTets.find("POINTS"));
    check_error_text(dir, no_points, {"no POINTS section"});
    check_error_text(dir, kTwoTets.substr(0, kTwoTets.find("CELLS")), {"no CELLS section"});
    check_error_text(dir, kTwoTets.substr(0, kTwoTets.find("CELL_TYPES")), {"no CELL_TYPES section"});
    check_error_text(dir, replaced(kTwoTets, "CELL_TYPES 2", "CELL_TYPES 3"),
                     {":14:", "CELL_TYPES lists 3", "CELLS declares 2"});
    check_error_text(dir, no_points + "CELLS 1 5\n4 0 1 2 3\n", {":5:", "CELLS comes before POINTS"});
}

BOOST_AUTO_TEST_CASE(malformed_values) {
    ScratchDir dir("vtk_legacy_bad_values");
    // Truncated inside POINTS.
    check_error_text(dir, kTwoTets.substr(0, kTwoTets.find("1 1 1\n")),
                     {":10:", "unexpected end of file", "point coordinate"});
    check_error_text(dir, replaced(kTwoTets, "0 1 0\n", "0 x 0\n"), {":8:", "'x'"});
    check_error_text(dir, replaced(kTwoTets, "0 1 0\n", "0 nan 0\n"), {":8:", "point 2 has a non-finite coordinate"});
    check_error_text(dir, replaced(kTwoTets, "0 0 1\n", "0 0 -inf\n"), {":9:", "point 3 has a non-finite coordinate"});
    check_error_text(dir, replaced(kTwoTets, "0 0 1\n", "0 0 1e999\n"), {":9:", "point 3 has a non-finite coordinate"});
    // A count that cannot fit in the rest of the file fails before anything is allocated.
    check_error_text(dir, replaced(kTwoTets, "POINTS 5", "POINTS 100000000000000"), {":5:", "cannot fit"});
    check_error_text(dir, replaced(kTwoTets, "CELLS 2 10", "CELLS 2 10000000000000"), {":11:", "cannot fit"});
    check_error_text(dir, replaced(kTwoTets, "CELL_TYPES 2", "CELL_TYPES 99999999999"), {":14:", "cannot fit"});
    check_error_text(dir, replaced(kTwoTets, "SCALARS quality double 1", "SCALARS quality double 100000000"),
                     {":22:", "cannot fit"});
    check_error_text(dir, replaced(kTwoTets, "POINTS 5", "POINTS -5"), {":5:", "negative"});
    // Cells.
    check_error_text(dir, replaced(kTwoTets, "4 1 2 3 4\n", "4 1 2 3 5\n"),
                     {":13:", "cell 1 refers to point 5", "0..4"});
    check_error_text(dir, replaced(kTwoTets, "4 1 2 3 4\n", "4 1 2 -3 4\n"), {":13:", "cell 1 refers to point -3"});
    check_error_text(dir, replaced(kTwoTets, "4 1 2 3 4\n", "4 1 2 3.5 4\n"), {":13:", "'3.5'"});
    check_error_text(dir, replaced(kTwoTets, "CELLS 2 10", "CELLS 2 11"),
                     {":13:", "cell count/size mismatch", "size 11"});
    check_error_text(dir, replaced(kTwoTets, "CELLS 2 10", "CELLS 2 9"),
                     {":13:", "cell 1 claims 4 points", "3 values are left"});
    check_error_text(dir, replaced(kTwoTets, "CELLS 2 10", "CELLS 3 10"),
                     {":13:", "cell count/size mismatch", "only 2 cells"});
    check_error_text(dir, replaced(kTwoTets, "CELLS 2 10", "CELLS 2 1"), {":11:", "size must count"});
    check_error_text(dir, replaced(kTwoTets, "10\n10\nPOINT", "10\n12\nPOINT"),
                     {":16:", "cell 1 has VTK type 12 (hexahedron) but 4 points; a hexahedron has 8"});
    check_error_text(dir, replaced(kTwoTets, "10\n10\nPOINT", "10\n42\nPOINT"),
                     {":16:", "cell 1 has VTK type 42 (polyhedron); Paloverde handles triangle (5), quadrilateral (9), "
                              "tetrahedron (10), hexahedron (12), wedge (13) and pyramid (14)"});
    check_error_text(dir, replaced(kTwoTets, "10\n10\nPOINT", "10\n24\nPOINT"),
                     {":16:", "cell 1 has VTK type 24 (quadratic tetrahedron); Paloverde handles"});
    check_error_text(dir, replaced(kTwoTets, "10\n10\nPOINT", "10\n5\nPOINT"),
                     {":16:", "cell 1 has VTK type 5 (triangle) but 4 points"});
    check_error_text(dir, replaced(kTwoTets, "10\n10\nPOINT", "10\n-1\nPOINT"), {":16:", "type -1 (unknown)"});
    // At the end of the file the line is the one after the last newline.
    check_error_text(dir, replaced(kTwoTets, "0.5 0.25\n", "0.5\n"), {":25:", "unexpected end of file", "quality"});
    check_error_text(dir, replaced(kTwoTets, "1 1 1 1 0\n", "1 1 1 one 0\n"), {":20:", "'one'"});
}

BOOST_AUTO_TEST_CASE(failed_writes_leave_no_partial_file) {
    ScratchDir dir("vtk_legacy_write_failure");
    const MeshFile file = read_mesh(shared_data("mesquite/tets/two_tets.vtk"));
    BOOST_CHECK_THROW(write_mesh(dir / "missing" / "out.vtk", file.mesh), FileError);
    BOOST_TEST(!fs::exists(dir / "missing"));

    write_file(dir / "keep.vtk", "precious");
    // "a b" and "a_b" would both be written as a_b: the writer refuses midway.
    const std::vector<Field> clash{{"a b", 1, std::vector<double>(5, 1.0)}, {"a_b", 1, std::vector<double>(5, 2.0)}};
    for (Encoding encoding : {Encoding::Ascii, Encoding::Binary}) {
        WriteOptions options;
        options.encoding = encoding;
        BOOST_CHECK_THROW(write_mesh(dir / "keep.vtk", file.mesh, options, clash), Error);
        BOOST_TEST(read_text(dir / "keep.vtk") == "precious");
    }
    BOOST_TEST(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()) == 1);
}

// Truncations, flipped bytes, inserted digits and cut spans must give a clean error (or a valid
// mesh), never a crash, a hang or a giant allocation.
BOOST_AUTO_TEST_CASE(corrupted_files_fail_cleanly) {
    ScratchDir dir("vtk_legacy_corrupted");
    const MeshFile mesh = read_mesh(shared_data("mesquite/tets/tet_2_with_bound.vtk"));
    const std::vector<Field> cell_fields{{"q", 1, std::vector<double>(49, 0.5)}};
    std::vector<std::string> originals;
    for (Encoding encoding : {Encoding::Ascii, Encoding::Binary}) {
        WriteOptions options;
        options.encoding = encoding;
        write_mesh(dir / "base.vtk", mesh.mesh, options, {}, cell_fields);
        originals.push_back(read_text(dir / "base.vtk"));
    }
    std::mt19937 random(12345);
    int errors = 0;
    for (const std::string& original : originals) {
        for (int attempt = 0; attempt < 250; ++attempt) {
            std::string text = original;
            const std::size_t at = random() % text.size();
            switch (random() % 4) {
                case 0: text.resize(at); break;
                case 1: text[at] = static_cast<char>(random()); break;
                case 2: text.insert(at, std::to_string(random() * 1000003ull)); break;
                case 3: text.erase(at, random() % 20); break;
            }
            write_file(dir / "corrupt.vtk", text);
            try {
                read_mesh(dir / "corrupt.vtk");
            } catch (const Error&) {
                ++errors;
            } catch (const std::exception& e) {
                BOOST_ERROR("attempt " << attempt << " threw " << e.what());
            }
        }
    }
    BOOST_TEST(errors > 0);
}

BOOST_AUTO_TEST_SUITE_END()
