#include <boost/test/unit_test.hpp>

#include <algorithm>
#include <charconv>
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
#include <utility>
#include <vector>

#include "io/text_scanner.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/mesh.hpp"
#include "support/io_checks.hpp"
#include "support/test_support.hpp"

namespace fs = std::filesystem;
using namespace paloverde;
using paloverde::io::base64_encode;
using namespace paloverde::test;

namespace {

const char* const kSharedMeshes[] = {
    "mesquite/tets/tire.vtk",           "mesquite/tets/cube-clip-5.vtk",   "mesquite/tets/flat-tet-sphere.vtk",
    "mesquite/tets/cub_wedge_like.vtk", "mesquite/tets/tet_4_tangled.vtk", "mesquite/tets/tet_1.vtk",
    "mesquite/tets/two_tets.vtk",       "mesquite/tris/tri_20258.vtk",     "mesquite/tris/shashkov.vtk",
    "mesquite/tris/tri_5_xz.vtk",       "mesquite/tris/tangled_tri.vtk",
};

// Writes `text` to a new .vtu file in `dir`; reading it must fail as check_error expects.
void check_error_text(const ScratchDir& dir, const std::string& text, std::initializer_list<std::string_view> fragments) {
    check_error_in_new_file(dir, ".vtu", text, fragments);
}

// --- Building .vtu files in every layout VTK writes ---------------------------------------

struct Array {
    std::string section;  // PointData, CellData, Points or Cells
    std::string name;
    std::string type;  // VTK XML type name
    int components = 1;
    std::vector<double> values;
};

enum class Form { Ascii, InlineBase64, AppendedRaw, AppendedBase64 };

struct Layout {
    Form form = Form::Ascii;
    bool header64 = true;
    bool big_endian = false;
    std::size_t zlib_block = 0;  // 0: uncompressed; otherwise the uncompressed size of a block
};

bool host_little_endian() {
    const std::uint16_t probe = 1;
    return *reinterpret_cast<const unsigned char*>(&probe) == 1;
}

template <class T>
void put(std::string& out, T value, bool big_endian) {
    char b[sizeof(T)];
    std::memcpy(b, &value, sizeof value);
    if (big_endian == host_little_endian()) std::reverse(b, b + sizeof b);
    out.append(b, sizeof b);
}

std::string packed(const Array& a, bool big) {
    std::string out;
    for (double v : a.values) {
        if (a.type == "Int8")
            put(out, static_cast<std::int8_t>(v), big);
        else if (a.type == "UInt8")
            put(out, static_cast<std::uint8_t>(v), big);
        else if (a.type == "Int16")
            put(out, static_cast<std::int16_t>(v), big);
        else if (a.type == "UInt16")
            put(out, static_cast<std::uint16_t>(v), big);
        else if (a.type == "Int32")
            put(out, static_cast<std::int32_t>(v), big);
        else if (a.type == "UInt32")
            put(out, static_cast<std::uint32_t>(v), big);
        else if (a.type == "Int64")
            put(out, static_cast<std::int64_t>(v), big);
        else if (a.type == "UInt64")
            put(out, static_cast<std::uint64_t>(v), big);
        else if (a.type == "Float32")
            put(out, static_cast<float>(v), big);
        else
            put(out, v, big);
    }
    return out;
}

std::string word(std::uint64_t v, const Layout& l) {
    std::string out;
    if (l.header64)
        put(out, v, l.big_endian);
    else
        put(out, static_cast<std::uint32_t>(v), l.big_endian);
    return out;
}

// A zlib stream of "stored" (uncompressed) deflate blocks: what zlib's inflate reads like any
// other, built without linking zlib into the test.
std::string zlib_stored(std::string_view data) {
    std::string out = "\x78\x01";
    std::size_t pos = 0;
    do {
        const std::size_t n = std::min<std::size_t>(65535, data.size() - pos);
        out += static_cast<char>(pos + n == data.size() ? 1 : 0);
        out += static_cast<char>(n & 0xFF);
        out += static_cast<char>(n >> 8);
        out += static_cast<char>(~n & 0xFF);
        out += static_cast<char>((~n >> 8) & 0xFF);
        out.append(data.substr(pos, n));
        pos += n;
    } while (pos < data.size());
    std::uint32_t a = 1, b = 0;
    for (unsigned char c : data) {
        a = (a + c) % 65521;
        b = (b + a) % 65521;
    }
    put(out, (b << 16) | a, true);
    return out;
}

// The header and the data of one binary array, as VTK lays them out.
std::pair<std::string, std::string> binary_parts(const Array& a, const Layout& l) {
    const std::string data = packed(a, l.big_endian);
    if (l.zlib_block == 0) return {word(data.size(), l), data};
    std::string sizes, body;
    std::size_t blocks = 0;
    for (std::size_t pos = 0; pos < data.size(); pos += l.zlib_block, ++blocks) {
        const std::string block = zlib_stored(std::string_view(data).substr(pos, l.zlib_block));
        sizes += word(block.size(), l);
        body += block;
    }
    return {word(blocks, l) + word(l.zlib_block, l) + word(data.size() % l.zlib_block, l) + sizes, body};
}

std::string ascii(const Array& a) {
    std::string out;
    for (double v : a.values) {
        char digits[32];
        const auto r = std::to_chars(digits, digits + sizeof digits, v);
        out.append(digits, r.ptr);
        out += ' ';
    }
    return out;
}

std::string build_vtu(const std::vector<Array>& arrays, int points, int cells, const Layout& l) {
    const bool appended = l.form == Form::AppendedRaw || l.form == Form::AppendedBase64;
    std::string xml = "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"";
    xml += l.big_endian ? "BigEndian" : "LittleEndian";
    xml += std::string("\" header_type=\"") + (l.header64 ? "UInt64" : "UInt32") + "\"";
    if (l.zlib_block) xml += " compressor=\"vtkZLibDataCompressor\"";
    xml += ">\n  <UnstructuredGrid>\n    <Piece NumberOfPoints=\"" + std::to_string(points) + "\" NumberOfCells=\"" +
           std::to_string(cells) + "\">\n";
    std::string data;
    for (const char* section : {"PointData", "CellData", "Points", "Cells"}) {
        xml += std::string("      <") + section + ">\n";
        for (const Array& a : arrays) {
            if (a.section != section) continue;
            xml += "        <DataArray type=\"" + a.type + "\" Name=\"" + a.name + "\" NumberOfComponents=\"" +
                   std::to_string(a.components) + "\" format=\"";
            const auto [header, body] = binary_parts(a, l);
            switch (l.form) {
                case Form::Ascii: xml += "ascii\">\n          " + ascii(a) + "\n        </DataArray>\n"; break;
                case Form::InlineBase64:
                    xml += "binary\">\n          " + base64_encode(header) + base64_encode(body) +
                           "\n        </DataArray>\n";
                    break;
                case Form::AppendedRaw:
                case Form::AppendedBase64:
                    xml += "appended\" offset=\"" + std::to_string(data.size()) + "\"/>\n";
                    data += l.form == Form::AppendedRaw ? header + body : base64_encode(header) + base64_encode(body);
                    break;
            }
        }
        xml += std::string("      </") + section + ">\n";
    }
    xml += "    </Piece>\n  </UnstructuredGrid>\n";
    if (appended)
        xml += std::string("  <AppendedData encoding=\"") + (l.form == Form::AppendedRaw ? "raw" : "base64") +
               "\">\n   _" + data + "\n  </AppendedData>\n";
    return xml + "</VTKFile>\n";
}

// Two tetrahedra, a triangle, a line and a vertex, in a choice of value types.
std::vector<Array> mixed_mesh(std::size_t variant) {
    const char* ids[] = {"Int64", "Int32", "UInt64", "UInt16", "Int8", "UInt32"};
    const char* small[] = {"UInt8", "Int32", "Int8", "UInt64", "Int16"};
    std::vector<double> velocity;
    for (int i = 0; i < 15; ++i) velocity.push_back(0.5 * i - 3);
    return {
        {"PointData", "fixed", small[(variant + 2) % 5], 1, {1, 1, 0, 1, 1}},
        {"PointData", "velocity", "Float32", 3, velocity},
        {"CellData", "id", small[variant % 5], 1, {10, 11, 12, 13, 14}},
        {"Points",
         "Points",
         variant % 2 ? "Float32" : "Float64",
         3,
         {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1.5, 1.25, -0.75}},
        {"Cells", "connectivity", ids[variant % 6], 1, {0, 1, 2, 3, 1, 2, 3, 4, 0, 1, 2, 0, 4, 4}},
        {"Cells", "offsets", ids[(variant + 1) % 6], 1, {4, 8, 11, 13, 14}},
        {"Cells", "types", small[(variant + 1) % 5], 1, {10, 10, 5, 3, 1}},
    };
}

void check_mixed_mesh(const MeshFile& file) {
    BOOST_TEST((file.mesh.kind() == ElementKind::Tetrahedron));
    BOOST_TEST(file.mesh.num_vertices() == 5);
    BOOST_TEST((std::vector<VertexId>(file.mesh.connectivity().begin(), file.mesh.connectivity().end()) ==
                std::vector<VertexId>{0, 1, 2, 3, 1, 2, 3, 4}));
    BOOST_TEST(file.mesh.point(4)[0] == 1.5);
    BOOST_TEST(file.mesh.point(4)[2] == -0.75);
    BOOST_REQUIRE(file.cell_field("id"));
    BOOST_TEST((file.cell_field("id")->values == std::vector<double>{10, 11}));
    BOOST_REQUIRE(file.point_field("velocity"));
    BOOST_TEST(file.point_field("velocity")->components == 3);
    BOOST_TEST(file.point_field("velocity")->values[14] == 4.0);
    BOOST_TEST(file.fixed_from_file);
    BOOST_TEST((std::vector<std::uint8_t>(file.mesh.fixed().begin(), file.mesh.fixed().end()) ==
                std::vector<std::uint8_t>{1, 1, 0, 1, 1}));
}

// A hexahedron (a unit cube), a pyramid on its top and a tetrahedron on the pyramid's side, with
// a quadrilateral on the cube's bottom and a line (both dropped), in a choice of value types.
std::vector<Array> cell_mesh(std::size_t variant) {
    const char* ids[] = {"Int64", "Int32", "UInt64", "UInt16", "Int8", "UInt32"};
    const char* small[] = {"UInt8", "Int32", "Int8", "UInt64", "Int16"};
    return {
        {"CellData", "id", small[variant % 5], 1, {10, 11, 12, 13, 14}},
        {"Points",
         "Points",
         variant % 2 ? "Float32" : "Float64",
         3,
         {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1, 0.5, 0.5, 1.5, 0.5, -0.5, 1.25}},
        {"Cells",
         "connectivity",
         ids[variant % 6],
         1,
         {0, 3, 2, 1, 0, 1, 2, 3, 4, 5, 6, 7, 4, 5, 6, 7, 8, 0, 1, 4, 5, 8, 9}},
        {"Cells", "offsets", ids[(variant + 1) % 6], 1, {4, 12, 17, 19, 23}},
        {"Cells", "types", small[(variant + 1) % 5], 1, {9, 12, 14, 3, 10}},
    };
}

void check_cell_mesh(const MeshFile& file) {
    BOOST_REQUIRE(file.mesh.has_cells());
    const std::vector<CellType> types = {CellType::Hexahedron, CellType::Pyramid, CellType::Tetrahedron};
    BOOST_TEST(std::ranges::equal(file.mesh.cell_types(), types));
    const std::vector<VertexId> cells = {0, 1, 2, 3, 4, 5, 6, 7, 4, 5, 6, 7, 8, 4, 5, 8, 9};
    BOOST_TEST(std::ranges::equal(file.mesh.cell_connectivity(), cells));
    BOOST_TEST(!file.orientation.flipped);
    BOOST_TEST(file.mesh.point(9)[2] == 1.25);
    BOOST_TEST((file.cell_field("id")->values == std::vector<double>{11, 12, 14}));
}

// A hand-written ascii file; the bad-input tests break one thing in it at a known line.
const std::string kAscii =
    "<?xml version=\"1.0\"?>\n"                                                                                 // 1
    "<!-- two tets and a line, <written> by hand -->\n"                                                         // 2
    "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"  // 3
    "  <UnstructuredGrid>\n"                                                                                    // 4
    "    <Piece NumberOfPoints=\"5\" NumberOfCells=\"3\">\n"                                                    // 5
    "      <PointData Scalars=\"fixed\">\n"                                                                     // 6
    "        <DataArray type=\"Int32\" Name=\"fixed\" format=\"ascii\">1 1 0 1 1</DataArray>\n"                 // 7
    "      </PointData>\n"                                                                                      // 8
    "      <CellData>\n"                                                                                        // 9
    "        <DataArray type=\"Float64\" Name=\"quality &amp; &quot;more&quot;\" format=\"ascii\">\n"           // 10
    "          0.5 0.25 -1\n"                                                                                   // 11
    "        </DataArray>\n"                                                                                    // 12
    "      </CellData>\n"                                                                                       // 13
    "      <Points>\n"                                                                                          // 14
    "        <DataArray type=\"Float32\" Name=\"Points\" NumberOfComponents=\"3\" format=\"ascii\">\n"          // 15
    "          0 0 0 1 0 0\n"                                                                                   // 16
    "          0 1 0 0 0 1\n"                                                                                   // 17
    "          1 1 1\n"                                                                                         // 18
    "        </DataArray>\n"                                                                                    // 19
    "      </Points>\n"                                                                                         // 20
    "      <Cells>\n"                                                                                           // 21
    "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n"                               // 22
    "          0 1 2 3\n"                                                                                       // 23
    "          1 2 3 4\n"                                                                                       // 24
    "          0 4\n"                                                                                           // 25
    "        </DataArray>\n"                                                                                    // 26
    "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">4 8 10</DataArray>\n"                  // 27
    "        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10 10 3</DataArray>\n"                   // 28
    "      </Cells>\n"                                                                                          // 29
    "    </Piece>\n"                                                                                            // 30
    "  </UnstructuredGrid>\n"                                                                                   // 31
    "</VTKFile>\n";                                                                                             // 32

// A mesh in appended raw form, and where each array's values start in it.
struct RawFile {
    std::string text;
    std::size_t values_of(std::string_view name) const {
        const std::size_t element = text.find("Name=\"" + std::string(name) + "\"");
        const std::size_t offset = text.find("offset=\"", element) + 8;
        std::size_t value = 0;
        std::from_chars(text.data() + offset, text.data() + text.size(), value);
        return text.find('_', text.find("<AppendedData")) + 1 + value + 8;
    }
};

RawFile raw_file() { return {build_vtu(mixed_mesh(0), 5, 5, {Form::AppendedRaw, true, false, 0})}; }

}  // namespace

BOOST_AUTO_TEST_SUITE(vtu)

BOOST_AUTO_TEST_CASE(reads_every_layout_header_type_byte_order_and_compression) {
    ScratchDir dir("vtu_layouts");
    std::size_t variant = 0;
    for (Form form : {Form::Ascii, Form::InlineBase64, Form::AppendedRaw, Form::AppendedBase64})
        for (bool header64 : {true, false})
            for (bool big : {false, true})
                for (std::size_t zlib : {std::size_t{0}, std::size_t{16}, std::size_t{32768}}) {
                    if (form == Form::Ascii && (!header64 || big || zlib)) continue;
                    const Layout layout{form, header64, big, zlib};
                    BOOST_TEST_CONTEXT("form " << static_cast<int>(form) << " header64 " << header64 << " big-endian "
                                               << big << " zlib block " << zlib << " variant " << variant) {
                        const fs::path path = dir / ("mesh" + std::to_string(variant) + ".vtu");
                        write_file(path, build_vtu(mixed_mesh(variant), 5, 5, layout));
                        check_mixed_mesh(read_mesh(path));
                    }
                    ++variant;
                }
}

BOOST_AUTO_TEST_CASE(reads_cells_in_every_layout) {
    ScratchDir dir("vtu_cell_layouts");
    std::size_t variant = 0;
    for (Form form : {Form::Ascii, Form::InlineBase64, Form::AppendedRaw, Form::AppendedBase64})
        for (bool big : {false, true})
            for (std::size_t zlib : {std::size_t{0}, std::size_t{16}}) {
                if (form == Form::Ascii && (big || zlib)) continue;
                BOOST_TEST_CONTEXT("form " << static_cast<int>(form) << " big-endian " << big << " zlib block " << zlib) {
                    const fs::path path = dir / ("cells" + std::to_string(variant) + ".vtu");
                    write_file(path, build_vtu(cell_mesh(variant), 10, 5, {form, variant % 2 == 0, big, zlib}));
                    check_cell_mesh(read_mesh(path));
                }
                ++variant;
            }
}

BOOST_AUTO_TEST_CASE(reads_data_that_zlib_really_compressed) {
    ScratchDir dir("vtu_deflate");
    // The Points of mixed_mesh() as Float64, compressed by zlib at level 6 in one 32768-byte
    // block, header and data base64-encoded apart as VTK does.
    const std::string deflated = "AQAAAAAAAAAAgAAAAAAAAHgAAAAAAAAAGgAAAAAAAAA=eJxjYMAHPtjjlSZa/geU/gKlX+wHAPGaB58=";
    const std::vector<Array> arrays = mixed_mesh(0);
    const Layout layout{Form::InlineBase64, true, false, 32768};
    const auto [header, body] = binary_parts(arrays[3], layout);
    const std::string text =
        replaced(build_vtu(arrays, 5, 5, layout), base64_encode(header) + base64_encode(body), deflated);
    write_file(dir / "deflated.vtu", text);
    check_mixed_mesh(read_mesh(dir / "deflated.vtu"));
}

BOOST_AUTO_TEST_CASE(reads_a_hand_written_ascii_file) {
    ScratchDir dir("vtu_ascii");
    write_file(dir / "mesh.vtu", kAscii);
    const MeshFile file = read_mesh(dir / "mesh.vtu");
    BOOST_TEST(file.mesh.num_elements() == 2);
    BOOST_REQUIRE(file.cell_field("quality & \"more\""));
    BOOST_TEST((file.cell_field("quality & \"more\"")->values == std::vector<double>{0.5, 0.25}));
    BOOST_TEST(file.mesh.fixed()[2] == 0);
    BOOST_TEST(file.mesh.fixed()[4] == 1);

    // Several pieces of text, comments, CDATA and information keys inside a DataArray.
    write_file(dir / "pieces.vtu",
               replaced(kAscii, "0 1 0 0 0 1\n",
                        "0 1 <!-- a comment --> 0 0 <![CDATA[ 0 ]]> 1 <InformationKey name=\"x\"/>\n"));
    BOOST_TEST(read_mesh(dir / "pieces.vtu").mesh.point(3)[2] == 1.0);
}

BOOST_AUTO_TEST_CASE(round_trips_shared_meshes_in_ascii_and_binary) {
    ScratchDir dir("vtu_round_trip");
    for (const char* name : kSharedMeshes) {
        const MeshFile original = read_mesh(shared_data(name));
        const Mesh& mesh = original.mesh;
        Field quality{"quality", 1, {}};
        for (ElementId e = 0; e < mesh.num_elements(); ++e) quality.values.push_back(1.0 / (3.0 + e) - 1e-300 * e);
        Field velocity{"velocity <m/s>", 3, {}};
        for (double x : mesh.coordinates()) velocity.values.push_back(std::nextafter(x * std::numbers::pi, 1e300));
        velocity.values[0] = 4.9e-324;
        velocity.values[1] = -0.0;
        velocity.values[2] = std::numeric_limits<double>::max();
        const std::vector<Field> point_fields{velocity};
        const std::vector<Field> cell_fields{quality};
        for (Encoding encoding : {Encoding::Ascii, Encoding::Binary}) {
            BOOST_TEST_CONTEXT(name << (encoding == Encoding::Ascii ? " ascii" : " binary")) {
                const fs::path path = dir / "copy.vtu";
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
                const Field* v = copy.point_field("velocity <m/s>");
                BOOST_REQUIRE(q);
                BOOST_REQUIRE(v);
                BOOST_TEST(v->components == 3);
                BOOST_TEST(same_bits(q->values, quality.values));
                BOOST_TEST(same_bits(v->values, velocity.values));
            }
        }
    }
}

BOOST_AUTO_TEST_CASE(writes_the_documented_layouts) {
    ScratchDir dir("vtu_writer");
    const MeshFile file = read_mesh(shared_data("mesquite/tets/two_tets.vtk"));
    WriteOptions options;
    options.encoding = Encoding::Ascii;
    write_mesh(dir / "a.vtu", file.mesh, options);
    const std::string text = read_text(dir / "a.vtu");
    BOOST_TEST(text.find("<VTKFile type=\"UnstructuredGrid\"") != std::string::npos);
    BOOST_TEST(text.find("format=\"ascii\"") != std::string::npos);
    BOOST_TEST(text.find("appended") == std::string::npos);
    BOOST_TEST(text.find("Name=\"fixed\"") != std::string::npos);

    options.encoding = Encoding::Binary;
    write_mesh(dir / "b.vtu", file.mesh, options);
    const std::string binary = read_text(dir / "b.vtu");
    BOOST_TEST(binary.find("header_type=\"UInt64\"") != std::string::npos);
    BOOST_TEST(binary.find("<AppendedData encoding=\"raw\">") != std::string::npos);
    BOOST_TEST(binary.find("format=\"ascii\"") == std::string::npos);
    BOOST_TEST(binary.find("type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"appended\"") !=
               std::string::npos);
    BOOST_TEST(binary.find("type=\"Int64\" Name=\"connectivity\" format=\"appended\"") != std::string::npos);
    BOOST_TEST(binary.find("type=\"Int64\" Name=\"offsets\" format=\"appended\"") != std::string::npos);
    BOOST_TEST(binary.find("type=\"UInt8\" Name=\"types\" format=\"appended\"") != std::string::npos);
}

BOOST_AUTO_TEST_CASE(malformed_xml_and_structure) {
    ScratchDir dir("vtu_bad_structure");
    check_error_text(dir, "", {"empty"});
    check_error_text(dir, "# vtk DataFile Version 2.0\nlegacy\nASCII\n", {":1:", "text outside the root element"});
    check_error_text(dir, "<?xml version=\"1.0\"?>\n<html></html>\n", {":2:", "<html>, not <VTKFile>"});
    check_error_text(dir, replaced(kAscii, "\"UnstructuredGrid\"", "\"PolyData\""),
                     {":3:", "PolyData", "UnstructuredGrid"});
    check_error_text(dir, replaced(kAscii, "LittleEndian", "MiddleEndian"), {":3:", "MiddleEndian"});
    check_error_text(dir, replaced(kAscii, "\"UInt64\"", "\"UInt16\""), {":3:", "header_type \"UInt16\""});
    check_error_text(dir, replaced(kAscii, "version=\"1.0\" byte", "compressor=\"vtkLZ4DataCompressor\" byte"),
                     {":3:", "vtkLZ4DataCompressor", "not supported"});
    check_error_text(dir,
                     replaced(kAscii, "  </UnstructuredGrid>",
                              "<Piece NumberOfPoints=\"0\" NumberOfCells=\"0\"/>\n  </UnstructuredGrid>"),
                     {":31:", "2 pieces"});
    const std::size_t points_begin = kAscii.find("      <Points>");
    std::string no_points = kAscii;
    no_points.erase(points_begin, kAscii.find("      <Cells>") - points_begin);
    check_error_text(dir, no_points, {":5:", "no <Points>"});
    check_error_text(dir, replaced(kAscii, "\"connectivity\"", "\"conn\""),
                     {":21:", "no DataArray named 'connectivity'"});
    check_error_text(dir, replaced(kAscii, "\"Float32\"", "\"Float16\""), {":15:", "unknown type \"Float16\""});
    check_error_text(dir, replaced(kAscii, " format=\"ascii\">1 1", ">1 1"), {":7:", "no format attribute"});
    check_error_text(dir, replaced(kAscii, "format=\"ascii\">1 1", "format=\"appended\" offset=\"0\">1 1"),
                     {":7:", "no <AppendedData>"});
    check_error_text(dir, kAscii.substr(0, kAscii.find("          1 1 1")),
                     {":18:", "ends inside the <DataArray> element opened at line 15"});
    check_error_text(dir, replaced(kAscii, "</Points>", "</Point>"),
                     {":20:", "</Point> does not match <Points> opened at line 14"});
    check_error_text(dir, replaced(kAscii, "format=\"ascii\">4 8", "format=\"ascii>4 8"),
                     {":27:", "'<' in the value of attribute format"});
    check_error_text(dir, replaced(kAscii, "Name=\"offsets\"", "Name=\"offsets\" Name=\"x\""),
                     {":27:", "appears twice"});
    check_error_text(dir, replaced(kAscii, "&amp;", "&bogus;"), {":10:", "unknown entity"});
    check_error_text(dir, replaced(kAscii, "by hand -->", "by hand --"), {":2:", "unterminated comment"});
}

BOOST_AUTO_TEST_CASE(malformed_ascii_values) {
    ScratchDir dir("vtu_bad_ascii");
    check_error_text(dir, replaced(kAscii, "0 1 0 0 0 1\n", "0 1 0 0 x 1\n"), {":17:", "expected a number, found 'x'"});
    check_error_text(dir, replaced(kAscii, "0 1 0 0 0 1\n", "0 1 0 0 0 inf\n"),
                     {":17:", "point 3 has a non-finite coordinate"});
    check_error_text(dir, replaced(kAscii, "1 1 1\n", "1 nan 1\n"), {":18:", "point 4 has a non-finite coordinate"});
    check_error_text(dir, replaced(kAscii, "NumberOfPoints=\"5\"", "NumberOfPoints=\"6\""),
                     {":15:", "NumberOfPoints=6"});
    check_error_text(dir, replaced(kAscii, "NumberOfPoints=\"5\"", "NumberOfPoints=\"-5\""),
                     {":5:", "not a non-negative integer"});
    check_error_text(dir, replaced(kAscii, "1 2 3 4\n", "1 2 3 5\n"),
                     {":24:", "cell 1 refers to point 5, outside 0..4"});
    check_error_text(dir, replaced(kAscii, "0 4\n", "0 4.5\n"), {":25:", "expected an integer, found '4.5'"});
    check_error_text(dir, replaced(kAscii, ">4 8 10<", ">4 3 10<"),
                     {":27:", "offset 3 of cell 1", "previous offset (4)"});
    check_error_text(dir, replaced(kAscii, ">4 8 10<", ">4 8 9<"), {":27:", "the cells use 9", "has 10"});
    check_error_text(dir, replaced(kAscii, ">4 8 10<", ">4 8<"), {":27:", "NumberOfCells=3"});
    check_error_text(dir, replaced(kAscii, "type=\"Int64\" Name=\"offsets\"", "type=\"Float32\" Name=\"offsets\""),
                     {":27:", "integer type"});
    check_error_text(dir, replaced(kAscii, ">10 10 3<", ">10 12 3<"),
                     {":28:", "cell 1 has VTK type 12 (hexahedron) but 4 points; a hexahedron has 8"});
    check_error_text(dir, replaced(kAscii, ">10 10 3<", ">10 42 3<"),
                     {":28:", "cell 1 has VTK type 42 (polyhedron); Paloverde handles triangle (5)"});
    check_error_text(dir, replaced(kAscii, ">10 10 3<", ">10 10 5<"),
                     {":28:", "cell 2 has VTK type 5 (triangle) but 2 points"});
    check_error_text(dir, replaced(kAscii, "0.5 0.25 -1", "0.5 0.25"), {":10:", "3 tuples of 1 were expected"});
}

BOOST_AUTO_TEST_CASE(malformed_binary_data) {
    ScratchDir dir("vtu_bad_binary");
    const RawFile raw = raw_file();
    write_file(dir / "good.vtu", raw.text);
    check_mixed_mesh(read_mesh(dir / "good.vtu"));

    // An offset past the appended data is reported on the DataArray's line.
    const std::string far = replaced(raw.text, "offset=\"0\"", "offset=\"99999\"");
    check_error_text(dir, far, {":6:", "offset 99999, past the end of the appended data"});
    // A byte count that runs past the data: the header's byte.
    std::string bad = raw.text;
    const std::size_t header = raw.values_of("types") - 8;
    bad[header + 1] = 1;  // 20 + 256 bytes
    check_error_text(dir, bad, {"(byte " + std::to_string(header) + ")", "declares 276 bytes"});
    // A value: its own byte.
    bad = raw.text;
    const std::size_t y1 = raw.values_of("Points") + 8 * 4;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    std::memcpy(bad.data() + y1, &nan, 8);
    check_error_text(dir, bad, {"(byte " + std::to_string(y1) + ")", "point 1 has a non-finite coordinate"});
    bad = raw.text;
    const std::size_t id = raw.values_of("connectivity") + 8 * 5;
    bad[id] = 7;
    check_error_text(dir, bad, {"(byte " + std::to_string(id) + ")", "cell 1 refers to point 7"});
    bad = raw.text;
    const std::size_t type = raw.values_of("types") + 4 * 2;  // Int32 in variant 0
    bad[type] = 13;
    check_error_text(dir, bad, {"(byte " + std::to_string(type) + ")", "cell 2 has VTK type 13 (wedge)"});
    // Truncated in the appended data.
    check_error_text(dir, raw.text.substr(0, raw.text.size() - 40), {"no closing </AppendedData>"});
    check_error_text(dir, replaced(raw.text, "   _", "   "), {"expected '_'"});
    check_error_text(dir, replaced(raw.text, "encoding=\"raw\"", "encoding=\"hex\""), {"encoding \"hex\""});
    // A byte count that is not a whole number of values.
    bad = raw.text;
    bad[raw.values_of("Points") - 8] = 119;
    check_error_text(dir, bad, {"not a whole number of Float64 values"});

    // Inline base64 that is not base64.
    const std::string inline_text = build_vtu(mixed_mesh(0), 5, 5, {Form::InlineBase64, true, false, 0});
    const std::size_t points = inline_text.find("Name=\"Points\"");
    std::string garbled = inline_text;
    garbled[inline_text.find('\n', points) + 14] = '*';
    check_error_text(dir, garbled, {":19:", "invalid base64"});
    // Appended base64 that is not base64.
    const std::string appended64 = build_vtu(mixed_mesh(0), 5, 5, {Form::AppendedBase64, true, false, 0});
    garbled = appended64;
    garbled[appended64.find('_', appended64.find("<AppendedData")) + 3] = '#';
    check_error_text(dir, garbled, {"(byte ", "invalid base64"});
}

BOOST_AUTO_TEST_CASE(malformed_compressed_data) {
    ScratchDir dir("vtu_bad_zlib");
    const Layout layout{Form::AppendedRaw, false, false, 32768};
    const std::string text = build_vtu(mixed_mesh(0), 5, 5, layout);
    write_file(dir / "good.vtu", text);
    check_mixed_mesh(read_mesh(dir / "good.vtu"));
    const std::size_t data = text.find('_', text.find("<AppendedData")) + 1;
    // The first array (fixed: 5 Int8 values in variant 0) has a 16-byte header, then its zlib
    // stream: flip a byte of the stored data so that the checksum fails.
    std::string bad = text;
    bad[data + 16 + 7] ^= 0x55;
    check_error_text(dir, bad, {"(byte " + std::to_string(data + 16) + ")", "zlib block 0 is corrupt"});
    // A block claiming far more than zlib could have compressed into it.
    bad = text;
    bad[data + 4 + 3] = 0x7F;  // a block size of about 2 GB
    bad[data + 8] = 0;         // and the last (only) block is a full one
    check_error_text(dir, bad, {"claims"});
    // More blocks than the data can hold.
    bad = text;
    bad[data + 3] = 0x40;
    check_error_text(dir, bad, {"(byte " + std::to_string(data) + ")", "blocks, more than the data can hold"});
}

BOOST_AUTO_TEST_CASE(failed_writes_leave_no_partial_file) {
    ScratchDir dir("vtu_write_failure");
    const MeshFile file = read_mesh(shared_data("mesquite/tets/two_tets.vtk"));
    BOOST_CHECK_THROW(write_mesh(dir / "missing" / "out.vtu", file.mesh), FileError);
    BOOST_TEST(!fs::exists(dir / "missing"));

    write_file(dir / "keep.vtu", "precious");
    const std::vector<Field> clash{{"same", 1, {1, 2}}, {"same", 3, std::vector<double>(6, 0.0)}};
    for (Encoding encoding : {Encoding::Ascii, Encoding::Binary}) {
        WriteOptions options;
        options.encoding = encoding;
        BOOST_CHECK_THROW(write_mesh(dir / "keep.vtu", file.mesh, options, {}, clash), Error);
        BOOST_TEST(read_text(dir / "keep.vtu") == "precious");
    }
    BOOST_TEST(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()) == 1);
}

// Truncations, flipped bytes, inserted digits and cut spans must give a clean error (or a valid
// mesh), never a crash, a hang or a giant allocation.
BOOST_AUTO_TEST_CASE(corrupted_files_fail_cleanly) {
    ScratchDir dir("vtu_corrupted");
    std::vector<std::string> originals{kAscii, raw_file().text,
                                       build_vtu(mixed_mesh(3), 5, 5, {Form::InlineBase64, false, true, 16}),
                                       build_vtu(mixed_mesh(4), 5, 5, {Form::AppendedBase64, true, false, 0})};
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
            write_file(dir / "corrupt.vtu", text);
            try {
                read_mesh(dir / "corrupt.vtu");
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
