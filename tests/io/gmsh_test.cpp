#include <boost/test/unit_test.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <initializer_list>
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

// Builds binary files byte by byte; `swap` writes every binary value in the other byte order.
struct Bytes {
    std::string data;
    bool swap = false;
    Bytes& text(std::string_view s) {
        data += s;
        return *this;
    }
    template <class T>
    Bytes& put(T value) {
        char b[sizeof(T)];
        std::memcpy(b, &value, sizeof value);
        if (swap) std::reverse(b, b + sizeof b);
        data.append(b, sizeof b);
        return *this;
    }
    Bytes& i32(std::int32_t v) { return put(v); }
    Bytes& u64(std::uint64_t v) { return put(v); }
    Bytes& f64(double v) { return put(v); }
};

// Writes `mesh` with a fixed-flag pattern that boundary detection would not give, a 3-component
// point field and a cell field, reads it back, and checks that everything survived exactly.
void check_gmsh_round_trip(const Mesh& original, const ScratchDir& dir, Encoding encoding) {
    Mesh mesh = original;
    const auto n = static_cast<std::size_t>(mesh.num_vertices());
    const auto m = static_cast<std::size_t>(mesh.num_elements());
    std::vector<std::uint8_t> fixed(n);
    for (std::size_t v = 0; v < n; ++v) fixed[v] = v % 3 == 1;
    mesh.set_fixed(fixed);
    Field velocity{"velocity", 3, {}};
    for (std::size_t v = 0; v < n; ++v) velocity.values.insert(velocity.values.end(), {v / 7.0, -1.0 / (v + 1.0), std::sqrt(v + 0.5)});
    Field quality{"quality", 1, {}};
    for (std::size_t e = 0; e < m; ++e) quality.values.push_back(1.0 / (e + 3.0));

    const fs::path path = dir / (encoding == Encoding::Ascii ? "round_trip_ascii.msh" : "round_trip_binary.msh");
    WriteOptions options;
    options.encoding = encoding;
    const Field points[] = {velocity};
    const Field cells[] = {quality};
    write_mesh(path, mesh, options, points, cells);

    const MeshFile file = read_mesh(path);
    check_same_mesh(mesh, file.mesh);
    BOOST_TEST(file.fixed_from_file);
    BOOST_TEST(std::equal(file.mesh.fixed().begin(), file.mesh.fixed().end(), fixed.begin()));
    const Field* read_velocity = file.point_field("velocity");
    BOOST_REQUIRE(read_velocity);
    BOOST_TEST(read_velocity->components == 3);
    check_same_values(read_velocity->values, velocity.values);
    const Field* read_quality = file.cell_field("quality");
    BOOST_REQUIRE(read_quality);
    BOOST_TEST(read_quality->components == 1);
    check_same_values(read_quality->values, quality.values);
    BOOST_REQUIRE(file.point_field("fixed"));
}

// A valid MSH 2.2 ASCII file that the error cases below modify.
const std::string kSmall22 =
    "$MeshFormat\n"
    "2.2 0 8\n"
    "$EndMeshFormat\n"
    "$Nodes\n"
    "5\n"
    "1 0 0 0\n"
    "2 1 0 0\n"
    "3 0 1 0\n"
    "4 0 0 1\n"
    "5 1 1 1\n"
    "$EndNodes\n"
    "$Elements\n"
    "2\n"
    "1 4 2 0 1 1 2 3 4\n"
    "2 4 2 0 1 2 3 4 5\n"
    "$EndElements\n";

// The same two tetrahedra as MSH 2.2 binary; `swap` writes them in the other byte order.
// `element_offset` receives the byte offset of the second tetrahedron's record.
std::string small22_binary(bool swap, std::int32_t second_tet_last_node = 5, std::size_t* element_offset = nullptr) {
    Bytes b;
    b.swap = swap;
    b.text("$MeshFormat\n2.2 1 8\n").i32(1).text("\n$EndMeshFormat\n$Nodes\n5\n");
    const double xyz[5][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
    for (int i = 0; i < 5; ++i) b.i32(i + 1).f64(xyz[i][0]).f64(xyz[i][1]).f64(xyz[i][2]);
    b.text("\n$EndNodes\n$Elements\n4\n");
    b.i32(2).i32(1).i32(2).i32(1).i32(0).i32(1).i32(1).i32(2).i32(3);   // one triangle, 2 tags
    b.i32(4).i32(2).i32(3);                                             // two tets, 3 tags each
    b.i32(2).i32(0).i32(1).i32(7).i32(1).i32(2).i32(3).i32(4);
    if (element_offset) *element_offset = b.data.size();
    b.i32(3).i32(0).i32(1).i32(7).i32(2).i32(3).i32(4).i32(second_tet_last_node);
    b.i32(15).i32(1).i32(2).i32(9).i32(0).i32(1).i32(5);                // one point element
    b.text("\n$EndElements\n");
    b.text("$NodeData\n1\n\"pressure\"\n1\n0.5\n3\n0\n1\n5\n");
    for (int i = 5; i >= 1; --i) b.i32(i).f64(i * 0.25);
    b.text("\n$EndNodeData\n");
    b.text("$ElementData\n1\n\"material\"\n1\n0.5\n3\n0\n1\n2\n").i32(3).f64(33.0).i32(2).f64(22.0);
    b.text("\n$EndElementData\n");
    return b.data;
}

}  // namespace

BOOST_AUTO_TEST_SUITE(gmsh)

BOOST_AUTO_TEST_CASE(msh22_ascii_with_sparse_unordered_tags) {
    const ScratchDir dir("gmsh_sparse");
    const std::string text = R"($MeshFormat
2.2 0 8
$EndMeshFormat
$PhysicalNames
2
2 1 "boundary face"
3 2 "volume"
$EndPhysicalNames
$Comments
anything at all, even $Nodes-like words
$EndComments
$Nodes
5
10 0 0 0
3 1 0 0
42 0 1 0
7 0 0 1
100 1 1 1
$EndNodes
$Elements
5
1 15 2 0 1 10
2 1 2 0 1 10 3
3 2 2 1 1 10 3 42
8 4 2 2 1 10 3 42 7
5 4 3 2 1 4 3 42 7 100
$EndElements
$NodeData
1
"temperature"
1
0.0
3
0
1
5
100 5.5
3 1.5
7 4.5
10 0.5
42 3.5
$EndNodeData
$ElementData
1
"material"
1
0.0
3
0
1
2
8 7.5
5 2.5
$EndElementData
$ElementData
1
"material"
1
1.0
3
1
1
2
5 20
8 10
$EndElementData
)";
    write_file(dir / "sparse.msh", text);
    const MeshFile file = read_mesh(dir / "sparse.msh");
    BOOST_TEST((file.mesh.kind() == ElementKind::Tetrahedron));
    BOOST_REQUIRE_EQUAL(file.mesh.num_vertices(), 5);
    BOOST_REQUIRE_EQUAL(file.mesh.num_elements(), 2);
    const std::vector<VertexId> expected = {0, 1, 2, 3, 1, 2, 3, 4};
    BOOST_TEST(std::equal(expected.begin(), expected.end(), file.mesh.connectivity().begin()));
    BOOST_TEST(file.mesh.point(1)[0] == 1.0);
    BOOST_TEST(file.mesh.point(4)[2] == 1.0);
    BOOST_TEST(positive_tets(file.mesh) == 2);

    const Field* temperature = file.point_field("temperature");
    BOOST_REQUIRE(temperature);
    const std::vector<double> t = {0.5, 1.5, 3.5, 4.5, 5.5};
    BOOST_TEST(temperature->values == t, boost::test_tools::per_element());
    // The last time step wins, narrowed to the tetrahedra in mesh order.
    const Field* material = file.cell_field("material");
    BOOST_REQUIRE(material);
    const std::vector<double> mat = {10.0, 20.0};
    BOOST_TEST(material->values == mat, boost::test_tools::per_element());
    BOOST_TEST(!file.fixed_from_file);
}

BOOST_AUTO_TEST_CASE(msh41_ascii_with_entity_blocks_of_mixed_elements) {
    const ScratchDir dir("gmsh_41_ascii");
    const std::string text = R"($MeshFormat
4.1 0 8
$EndMeshFormat
$Entities
1 1 0 1
1 0 0 0 0
1 0 0 0 1 0 0 0 2 1 -1
1 0 0 0 1 1 1 0 0
$EndEntities
$Nodes
3 6 1 6
0 1 0 1
1
0 0 0
1 1 1 2
2
3
1 0 0 0.25
0 1 0 0.75
3 1 0 3
4
6
5
0 0 1
2 2 2
1 1 1
$EndNodes
$Elements
4 6 1 6
0 1 15 1
1 1
1 1 1 1
2 1 2
2 1 2 2
3 1 2 3
4 2 3 4
3 1 4 2
5 1 2 3 4
6 2 3 4 5
$EndElements
$ElementData
1
"region"
1
0
3
0
1
3
6 2
5 1
3 9
$EndElementData
)";
    write_file(dir / "blocks.msh", text);
    const MeshFile file = read_mesh(dir / "blocks.msh");
    BOOST_TEST((file.mesh.kind() == ElementKind::Tetrahedron));
    BOOST_REQUIRE_EQUAL(file.mesh.num_vertices(), 6);  // node 6 is in no element but is kept
    BOOST_REQUIRE_EQUAL(file.mesh.num_elements(), 2);
    // Node order: 1, 2, 3, 4, 6, 5.
    const std::vector<VertexId> expected = {0, 1, 2, 3, 1, 2, 3, 5};
    BOOST_TEST(std::equal(expected.begin(), expected.end(), file.mesh.connectivity().begin()));
    BOOST_TEST(file.mesh.point(5)[0] == 1.0);
    BOOST_TEST(file.mesh.point(4)[0] == 2.0);
    const Field* region = file.cell_field("region");
    BOOST_REQUIRE(region);
    const std::vector<double> r = {1.0, 2.0};
    BOOST_TEST(region->values == r, boost::test_tools::per_element());
}

BOOST_AUTO_TEST_CASE(msh41_binary) {
    const ScratchDir dir("gmsh_41_binary");
    Bytes b;
    b.text("$MeshFormat\n4.1 1 8\n").i32(1).text("\n$EndMeshFormat\n");
    // One volume with a bounding box, no physical tags, no bounding surfaces.
    b.text("$Entities\n").u64(0).u64(0).u64(0).u64(1).i32(1);
    for (double v : {0.0, 0.0, 0.0, 1.0, 1.0, 1.0}) b.f64(v);
    b.u64(0).u64(0).text("\n$EndEntities\n");
    b.text("$Nodes\n").u64(2).u64(5).u64(1).u64(5);
    b.i32(0).i32(1).i32(0).u64(1).u64(1).f64(0).f64(0).f64(0);
    b.i32(3).i32(1).i32(0).u64(4).u64(2).u64(3).u64(4).u64(5);
    for (double v : {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0}) b.f64(v);
    b.text("\n$EndNodes\n");
    b.text("$Elements\n").u64(3).u64(4).u64(1).u64(4);
    b.i32(0).i32(1).i32(15).u64(1).u64(1).u64(1);
    b.i32(2).i32(1).i32(2).u64(1).u64(2).u64(1).u64(2).u64(3);
    b.i32(3).i32(1).i32(4).u64(2).u64(3).u64(1).u64(2).u64(3).u64(4).u64(4).u64(2).u64(3).u64(4).u64(5);
    b.text("\n$EndElements\n");
    b.text("$NodeData\n1\n\"velocity\"\n1\n0\n3\n0\n3\n5\n");
    for (int tag = 1; tag <= 5; ++tag) b.i32(tag).f64(tag).f64(-tag).f64(tag / 8.0);
    b.text("\n$EndNodeData\n");
    b.text("$ElementData\n1\n\"quality\"\n1\n0\n3\n0\n1\n2\n").i32(4).f64(0.75).i32(3).f64(0.5);
    b.text("\n$EndElementData\n");
    write_file(dir / "binary41.msh", b.data);

    const MeshFile file = read_mesh(dir / "binary41.msh");
    BOOST_REQUIRE_EQUAL(file.mesh.num_vertices(), 5);
    BOOST_REQUIRE_EQUAL(file.mesh.num_elements(), 2);
    const std::vector<VertexId> expected = {0, 1, 2, 3, 1, 2, 3, 4};
    BOOST_TEST(std::equal(expected.begin(), expected.end(), file.mesh.connectivity().begin()));
    BOOST_TEST(file.mesh.point(4)[1] == 1.0);
    const Field* velocity = file.point_field("velocity");
    BOOST_REQUIRE(velocity);
    BOOST_TEST(velocity->components == 3);
    BOOST_TEST(velocity->values[3 * 4 + 1] == -5.0);
    BOOST_TEST(velocity->values[3 * 1 + 2] == 0.25);
    const Field* quality = file.cell_field("quality");
    BOOST_REQUIRE(quality);
    const std::vector<double> q = {0.5, 0.75};
    BOOST_TEST(quality->values == q, boost::test_tools::per_element());
}

// A hexahedron, a prism and a pyramid apart, with a boundary quadrangle (dropped), as Gmsh 4.1
// writes them: nodes in Gmsh's order. Gmsh's prism turns its first triangle towards the second,
// the mirror of a VTK wedge: read, it is the wedge (9, 11, 10, 12, 14, 13), valid, not flipped.
const double kCellNodes[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1,  // hexahedron
                             2, 0, 0, 3, 0, 0, 2, 1, 0, 2, 0, 1, 3, 0, 1, 2, 1, 1,                // prism
                             4, 0, 0, 5, 0, 0, 5, 1, 0, 4, 1, 0, 4.5, 0.5, 1};                    // pyramid
struct GmshBlock {
    int dimension, type;
    std::vector<std::int64_t> nodes;  // of its one element
};
const GmshBlock kCellBlocks[] = {{2, 3, {1, 4, 3, 2}},
                                 {3, 5, {1, 2, 3, 4, 5, 6, 7, 8}},
                                 {3, 6, {9, 10, 11, 12, 13, 14}},
                                 {3, 7, {15, 16, 17, 18, 19}}};

void check_gmsh_cells(const MeshFile& file) {
    BOOST_REQUIRE(file.mesh.has_cells());
    BOOST_REQUIRE_EQUAL(file.mesh.num_cells(), 3);
    BOOST_TEST((file.mesh.cell_type(0) == CellType::Hexahedron));
    BOOST_TEST((file.mesh.cell_type(1) == CellType::Wedge));
    BOOST_TEST((file.mesh.cell_type(2) == CellType::Pyramid));
    const std::vector<VertexId> wedge = {8, 10, 9, 11, 13, 12};
    BOOST_TEST(std::ranges::equal(file.mesh.cell(1), wedge));
    BOOST_TEST(file.mesh.cell(2)[4] == 18);
    BOOST_TEST(!file.orientation.flipped);
    BOOST_TEST(count_orientations(file.mesh).inverted == 0);
    const std::vector<double> quality = {0.5, 0.25, 0.125};  // the quadrangle's 1 is dropped
    BOOST_TEST(file.cell_field("quality")->values == quality, boost::test_tools::per_element());
}

BOOST_AUTO_TEST_CASE(msh41_hexahedra_prisms_and_pyramids) {
    const ScratchDir dir("gmsh_41_cells");
    std::string text = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 19 1 19\n3 1 0 19\n";
    for (int tag = 1; tag <= 19; ++tag) text += std::to_string(tag) + "\n";
    for (int i = 0; i < 19; ++i)
        text += std::to_string(kCellNodes[3 * i]) + " " + std::to_string(kCellNodes[3 * i + 1]) + " " +
                std::to_string(kCellNodes[3 * i + 2]) + "\n";
    text += "$EndNodes\n$Elements\n4 4 1 4\n";
    int tag = 1;
    for (const GmshBlock& block : kCellBlocks) {
        text += std::to_string(block.dimension) + " 1 " + std::to_string(block.type) + " 1\n" + std::to_string(tag++);
        for (std::int64_t node : block.nodes) text += " " + std::to_string(node);
        text += "\n";
    }
    text += "$EndElements\n$ElementData\n1\n\"quality\"\n1\n0\n3\n0\n1\n4\n1 1\n2 0.5\n3 0.25\n4 0.125\n$EndElementData\n";
    write_file(dir / "cells41.msh", text);
    check_gmsh_cells(read_mesh(dir / "cells41.msh"));

    Bytes b;
    b.text("$MeshFormat\n4.1 1 8\n").i32(1).text("\n$EndMeshFormat\n");
    b.text("$Nodes\n").u64(1).u64(19).u64(1).u64(19).i32(3).i32(1).i32(0).u64(19);
    for (int t = 1; t <= 19; ++t) b.u64(static_cast<std::uint64_t>(t));
    for (double x : kCellNodes) b.f64(x);
    b.text("\n$EndNodes\n$Elements\n").u64(4).u64(4).u64(1).u64(4);
    tag = 1;
    for (const GmshBlock& block : kCellBlocks) {
        b.i32(block.dimension).i32(1).i32(block.type).u64(1).u64(static_cast<std::uint64_t>(tag++));
        for (std::int64_t node : block.nodes) b.u64(static_cast<std::uint64_t>(node));
    }
    b.text("\n$EndElements\n$ElementData\n1\n\"quality\"\n1\n0\n3\n0\n1\n4\n");
    b.i32(1).f64(1).i32(2).f64(0.5).i32(3).f64(0.25).i32(4).f64(0.125).text("\n$EndElementData\n");
    write_file(dir / "cells41_binary.msh", b.data);
    check_gmsh_cells(read_mesh(dir / "cells41_binary.msh"));

    // Written back (2.2), the prism has Gmsh's order again; a binary file holds a block per type.
    const MeshFile file = read_mesh(dir / "cells41.msh");
    WriteOptions ascii;
    ascii.encoding = Encoding::Ascii;
    write_mesh(dir / "cells22.msh", file.mesh, ascii, {}, file.cell_fields);
    BOOST_TEST(read_text(dir / "cells22.msh").find("\n2 6 2 0 1 9 10 11 12 13 14\n") != std::string::npos);
    check_gmsh_cells(read_mesh(dir / "cells22.msh"));
    write_mesh(dir / "cells22_binary.msh", file.mesh, {}, {}, file.cell_fields);
    check_gmsh_cells(read_mesh(dir / "cells22_binary.msh"));
}

BOOST_AUTO_TEST_CASE(msh22_binary_in_both_byte_orders) {
    const ScratchDir dir("gmsh_22_binary");
    for (bool swap : {false, true}) {
        const fs::path path = dir / (swap ? "swapped.msh" : "native.msh");
        write_file(path, small22_binary(swap));
        const MeshFile file = read_mesh(path);
        BOOST_REQUIRE_EQUAL(file.mesh.num_vertices(), 5);
        BOOST_REQUIRE_EQUAL(file.mesh.num_elements(), 2);
        const std::vector<VertexId> expected = {0, 1, 2, 3, 1, 2, 3, 4};
        BOOST_TEST(std::equal(expected.begin(), expected.end(), file.mesh.connectivity().begin()));
        BOOST_TEST(file.mesh.point(4)[2] == 1.0);
        const Field* pressure = file.point_field("pressure");
        BOOST_REQUIRE(pressure);
        const std::vector<double> p = {0.25, 0.5, 0.75, 1.0, 1.25};
        BOOST_TEST(pressure->values == p, boost::test_tools::per_element());
        const Field* material = file.cell_field("material");
        BOOST_REQUIRE(material);
        const std::vector<double> mat = {22.0, 33.0};
        BOOST_TEST(material->values == mat, boost::test_tools::per_element());
    }
}

BOOST_AUTO_TEST_CASE(partitioned_and_partial_views) {
    const ScratchDir dir("gmsh_views");
    // Two partitions of step 0, then step 1 (which replaces step 0) covering nodes 1 and 2 only.
    const std::string view = "$NodeData\n1\n\"u\"\n1\n0\n4\n0\n1\n2\n1\n1 1\n2 2\n$EndNodeData\n"
                             "$NodeData\n1\n\"u\"\n1\n0\n4\n0\n1\n3\n2\n3 3\n4 4\n5 5\n$EndNodeData\n"
                             "$NodeData\n1\n\"v\"\n1\n0\n3\n0\n1\n5\n1 1\n2 2\n3 3\n4 4\n5 5\n$EndNodeData\n"
                             "$NodeData\n1\n\"v\"\n1\n1\n3\n1\n1\n2\n1 10\n2 20\n$EndNodeData\n";
    write_file(dir / "views.msh", kSmall22 + view);
    const MeshFile file = read_mesh(dir / "views.msh");
    const std::vector<double> u = {1, 2, 3, 4, 5};
    BOOST_TEST(file.point_field("u")->values == u, boost::test_tools::per_element());
    const std::vector<double>& v = file.point_field("v")->values;
    BOOST_REQUIRE_EQUAL(v.size(), 5u);
    BOOST_TEST(v[0] == 10.0);
    BOOST_TEST(v[1] == 20.0);
    BOOST_TEST(std::isnan(v[2]));
    BOOST_TEST(std::isnan(v[4]));
}

BOOST_AUTO_TEST_CASE(windows_line_endings) {
    const ScratchDir dir("gmsh_crlf");
    const std::string unix_text =
        kSmall22 + "$NodeData\n1\n\"fixed\"\n1\n0\n3\n0\n1\n5\n1 1\n2 0\n3 0\n4 0\n5 1\n$EndNodeData\n";
    std::string text;
    for (char c : unix_text) {
        if (c == '\n') text += '\r';
        text += c;
    }
    write_file(dir / "crlf.msh", text);
    const MeshFile file = read_mesh(dir / "crlf.msh");
    BOOST_TEST(file.mesh.num_elements() == 2);
    BOOST_TEST(file.fixed_from_file);  // the name came through without its '\r'
    const std::vector<std::uint8_t> fixed = {1, 0, 0, 0, 1};
    BOOST_TEST(std::equal(fixed.begin(), fixed.end(), file.mesh.fixed().begin()));
}

BOOST_AUTO_TEST_CASE(msh41_binary_with_four_byte_size_t) {
    const ScratchDir dir("gmsh_41_size4");
    Bytes b;
    b.text("$MeshFormat\n4.1 1 4\n").i32(1).text("\n$EndMeshFormat\n");
    b.text("$Nodes\n").i32(1).i32(4).i32(1).i32(4);
    b.i32(3).i32(1).i32(0).i32(4).i32(1).i32(2).i32(3).i32(4);
    for (double v : {0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0}) b.f64(v);
    b.text("\n$EndNodes\n$Elements\n").i32(1).i32(1).i32(1).i32(1);
    b.i32(3).i32(1).i32(4).i32(1).i32(1).i32(4).i32(3).i32(2).i32(1);
    b.text("\n$EndElements\n");
    write_file(dir / "size4.msh", b.data);
    const MeshFile file = read_mesh(dir / "size4.msh");
    const std::vector<VertexId> expected = {3, 2, 1, 0};
    BOOST_TEST(std::equal(expected.begin(), expected.end(), file.mesh.connectivity().begin()));
}

BOOST_AUTO_TEST_CASE(triangle_only_file_gives_a_triangle_mesh) {
    const ScratchDir dir("gmsh_triangles");
    write_file(dir / "tri.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n$EndNodes\n"
                                "$Elements\n4\n1 1 2 0 1 1 2\n2 1 2 0 1 2 3\n3 2 2 0 1 1 2 3\n4 2 2 0 1 1 3 4\n$EndElements\n");
    const MeshFile file = read_mesh(dir / "tri.msh");
    BOOST_TEST((file.mesh.kind() == ElementKind::Triangle));
    BOOST_TEST(file.mesh.num_elements() == 2);
    BOOST_TEST(file.mesh.num_free_vertices() == 0);  // all four are on the boundary
}

BOOST_AUTO_TEST_CASE(shared_meshes_round_trip_exactly) {
    const ScratchDir dir("gmsh_round_trip");
    for (const char* name : {"stellar/house2.ele", "tetwild/armadillo.mesh", "tetwild/octopus-vol.mesh"}) {
        BOOST_TEST_CONTEXT(name) {
            const MeshFile original = read_mesh(shared_data(name));
            check_gmsh_round_trip(original.mesh, dir, Encoding::Ascii);
            check_gmsh_round_trip(original.mesh, dir, Encoding::Binary);
        }
    }
}

BOOST_AUTO_TEST_CASE(triangle_mesh_round_trips_exactly) {
    const ScratchDir dir("gmsh_round_trip_tri");
    const Mesh mesh = awkward_triangles();
    check_gmsh_round_trip(mesh, dir, Encoding::Ascii);
    check_gmsh_round_trip(mesh, dir, Encoding::Binary);
}

BOOST_AUTO_TEST_CASE(without_fixed_field_the_boundary_is_fixed) {
    const ScratchDir dir("gmsh_no_fixed");
    const Mesh mesh = awkward_triangles();
    WriteOptions options;
    options.write_fixed = false;
    write_mesh(dir / "plain.msh", mesh, options);
    const MeshFile file = read_mesh(dir / "plain.msh");
    BOOST_TEST(!file.fixed_from_file);
    BOOST_TEST(!file.point_field("fixed"));
    const auto boundary = boundary_vertices(mesh.kind(), mesh.connectivity(), mesh.num_vertices());
    BOOST_TEST(std::equal(boundary.begin(), boundary.end(), file.mesh.fixed().begin()));
}

BOOST_AUTO_TEST_CASE(ascii_writer_output_is_plain_msh22) {
    const ScratchDir dir("gmsh_ascii_text");
    const Mesh mesh(ElementKind::Tetrahedron, {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0.1}, {0, 1, 2, 3});
    WriteOptions options;
    options.encoding = Encoding::Ascii;
    options.write_fixed = false;
    write_mesh(dir / "one.msh", mesh, options);
    const MeshFile file = read_mesh(dir / "one.msh");
    BOOST_TEST(file.mesh.point(3)[2] == 0.1);
    const std::string text = read_text(dir / "one.msh");
    BOOST_TEST(text == "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 0.1\n$EndNodes\n"
                       "$Elements\n1\n1 4 2 0 1 1 2 3 4\n$EndElements\n");
}

BOOST_AUTO_TEST_CASE(field_name_with_a_quote_cannot_be_written) {
    const ScratchDir dir("gmsh_bad_name");
    const Mesh mesh(ElementKind::Tetrahedron, {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, 1, 2, 3});
    const Field bad[] = {Field{"say \"hi\"", 1, {1, 2, 3, 4}}};
    BOOST_CHECK_THROW(write_mesh(dir / "bad.msh", mesh, {}, bad), Error);
    BOOST_TEST(!fs::exists(dir / "bad.msh"));
}

BOOST_AUTO_TEST_CASE(malformed_ascii_files_name_file_line_and_problem) {
    const ScratchDir dir("gmsh_bad_ascii");
    write_file(dir / "good.msh", kSmall22);
    BOOST_REQUIRE_NO_THROW(read_mesh(dir / "good.msh"));

    check_error_text(dir, "empty.msh", "", {"empty file", "$MeshFormat"});
    check_error_text(dir, "no_format.msh", "$Nodes\n1\n1 0 0 0\n$EndNodes\n", {":1:", "expected $MeshFormat"});
    check_error_text(dir, "version.msh", replaced(kSmall22, "2.2 0 8", "4.0 0 8"), {":2:", "version 4.0"});
    check_error_text(dir, "version1.msh", replaced(kSmall22, "2.2 0 8", "1 0 8"), {":2:", "version 1"});
    check_error_text(dir, "filetype.msh", replaced(kSmall22, "2.2 0 8", "2.2 2 8"), {":2:", "file type 2"});

    const std::string word = replaced(kSmall22, "3 0 1 0", "3 0 abc 0");
    check_error_text(dir, "word.msh", word, {line_of(word, "abc"), "expected a y coordinate", "'abc'"});
    const std::string nan = replaced(kSmall22, "3 0 1 0", "3 0 nan 0");
    check_error_text(dir, "nan.msh", nan, {line_of(nan, "nan"), "node 3", "non-finite"});
    const std::string inf = replaced(kSmall22, "4 0 0 1", "4 0 0 -inf");
    check_error_text(dir, "inf.msh", inf, {line_of(inf, "-inf"), "node 4", "non-finite"});

    const std::string huge = replaced(kSmall22, "$Nodes\n5\n", "$Nodes\n999999999999\n");
    check_error_text(dir, "huge.msh", huge, {line_of(huge, "999999999999"), "number of nodes", "cannot fit"});
    const std::string huge_elements = replaced(kSmall22, "$Elements\n2\n", "$Elements\n4000000000\n");
    check_error_text(dir, "huge_elements.msh", huge_elements, {line_of(huge_elements, "4000000000"), "cannot fit"});
    const std::string negative = replaced(kSmall22, "$Nodes\n5\n", "$Nodes\n-5\n");
    check_error_text(dir, "negative.msh", negative, {line_of(negative, "-5"), "negative"});

    // Cut where the declared count still fits in what is left, so the end of file is what fails.
    const std::string truncated = kSmall22.substr(0, kSmall22.find("2 4 2 0 1 2 3 4 5"));
    check_error_text(dir, "truncated.msh", truncated,
                     {last_line(truncated), "end of file", "expected an element tag"});
    // Cut in the nodes: the declared count no longer fits.
    const std::string cut_nodes = kSmall22.substr(0, kSmall22.find("4 0 0 1"));
    check_error_text(dir, "cut_nodes.msh", cut_nodes, {":5:", "number of nodes of 5", "cannot fit"});
    const std::string cut_element = kSmall22.substr(0, kSmall22.find("2 3 4 5\n$EndElements"));
    check_error_text(dir, "cut_element.msh", cut_element, {"end of file", "node tag"});
    check_error_text(dir, "no_elements.msh", kSmall22.substr(0, kSmall22.find("$Elements")), {"no $Elements section"});
    check_error_text(dir, "no_nodes.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n", {"no $Nodes section"});
    const std::string end_nodes = replaced(kSmall22, "$EndNodes", "$EndNode");
    check_error_text(dir, "end_nodes.msh", end_nodes, {line_of(end_nodes, "$EndNode\n"), "expected $EndNodes", "'$EndNode'"});
    const std::string unclosed = kSmall22 + "$Periodic\n1\n";
    check_error_text(dir, "unclosed.msh", unclosed, {"$Periodic", "no $EndPeriodic"});
    const std::string stray = kSmall22 + "hello\n";
    check_error_text(dir, "stray.msh", stray, {line_of(stray, "hello"), "'hello'"});

    const std::string unknown_node = replaced(kSmall22, "2 4 2 0 1 2 3 4 5", "2 4 2 0 1 2 3 4 99");
    check_error_text(dir, "unknown_node.msh", unknown_node,
                     {line_of(unknown_node, "2 3 4 99"), "element 2", "node 99", "not in $Nodes"});
    const std::string duplicate = replaced(kSmall22, "2 1 0 0", "1 1 0 0");
    check_error_text(dir, "duplicate.msh", duplicate, {"node tag 1 appears more than once"});
    const std::string hexahedron = replaced(kSmall22, "2 4 2 0 1 2 3 4 5", "2 17 2 0 1 1 2 3 4 5 1 2 3");
    check_error_text(dir, "hex20.msh", hexahedron,
                     {line_of(hexahedron, "2 17 2"), "element 2", "type 17", "20-node second-order hexahedron",
                      "triangle (2), quadrilateral (3), tetrahedron (4), hexahedron (5), wedge (6) and pyramid (7)"});
    const std::string prism = replaced(kSmall22, "2 4 2 0 1 2 3 4 5", "2 13 2 0 1 1 2 3 4 5 1");
    check_error_text(dir, "prism18.msh", prism, {line_of(prism, "2 13 2"), "element 2", "type 13", "prism", "gmsh -order 1"});
    const std::string quad = replaced(kSmall22, "2 4 2 0 1 2 3 4 5", "2 16 2 0 1 1 2 3 4");
    check_error_text(dir, "quad8.msh", quad, {"element 2", "type 16", "quadrangle"});
    const std::string unknown_type = replaced(kSmall22, "2 4 2 0 1 2 3 4 5", "2 99 2 0 1 1 2 3 4");
    check_error_text(dir, "type99.msh", unknown_type, {"element 2 has type 99; only triangle (2)"});
    // A hexahedron with a node twice is named by its tag.
    const std::string repeated_hex = replaced(kSmall22, "2 4 2 0 1 2 3 4 5", "7 5 2 0 1 1 2 3 4 5 1 2 3");
    check_error_text(dir, "repeated_hex.msh", repeated_hex, {"element 7 (hexahedron) repeats vertex 0"});
    const std::string tet10 = replaced(kSmall22, "2 4 2 0 1 2 3 4 5", "2 11 2 0 1 1 2 3 4 5 1 2 3 4 5");
    check_error_text(dir, "tet10.msh", tet10, {line_of(tet10, "2 11 2"), "element 2", "10-node", "gmsh -order 1"});
    const std::string tri6 = replaced(kSmall22, "2 4 2 0 1 2 3 4 5", "2 9 2 0 1 1 2 3 4 5 1");
    check_error_text(dir, "tri6.msh", tri6, {"element 2", "type 9", "gmsh -order 1"});
    const std::string element_first = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Elements\n0\n$EndElements\n";
    check_error_text(dir, "element_first.msh", element_first, {":4:", "$Elements comes before $Nodes"});
    const std::string repeated_corner = replaced(kSmall22, "2 4 2 0 1 2 3 4 5", "2 4 2 0 1 2 3 4 4");
    check_error_text(dir, "repeated_corner.msh", repeated_corner, {"repeats vertex"});

    const std::string data = kSmall22 + "$ElementData\n1\n\"q\"\n1\n0\n3\n0\n1\n1\n77 1.5\n$EndElementData\n";
    check_error_text(dir, "data_tag.msh", data, {line_of(data, "77 1.5"), "'q'", "element 77"});
    const std::string few_ints = kSmall22 + "$NodeData\n1\n\"q\"\n1\n0\n2\n0\n1\n$EndNodeData\n";
    check_error_text(dir, "few_ints.msh", few_ints, {"'q'", "2 integer tags"});
    const std::string components = kSmall22 + "$NodeData\n1\n\"q\"\n1\n0\n3\n0\n100000000\n1\n1 0\n$EndNodeData\n";
    check_error_text(dir, "components.msh", components, {line_of(components, "100000000"), "components"});
    const std::string no_elements = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 0 0\n$EndNodes\n"
                                    "$Elements\n1\n1 15 2 0 1 1\n$EndElements\n";
    check_error_text(dir, "only_points.msh", no_elements, {"no triangles, quadrilaterals, tetrahedra", "(empty mesh)"});
}

BOOST_AUTO_TEST_CASE(malformed_msh41_files) {
    const ScratchDir dir("gmsh_bad_41");
    const std::string good = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n"
                             "0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n$EndElements\n";
    write_file(dir / "good.msh", good);
    BOOST_REQUIRE_NO_THROW(read_mesh(dir / "good.msh"));
    const std::string short_block = replaced(good, "3 1 0 4\n", "3 1 0 3\n");
    check_error_text(dir, "short_block.msh", short_block, {"hold 3 nodes", "declares 4"});
    const std::string long_block = replaced(good, "3 1 0 4\n", "3 1 0 5\n");
    check_error_text(dir, "long_block.msh", long_block, {line_of(long_block, "3 1 0 5"), "holds 5 nodes", "declares"});
    const std::string few_blocks = replaced(good, "1 4 1 4\n", "1 5 1 5\n");
    check_error_text(dir, "few_blocks.msh", few_blocks, {"hold 4 nodes", "declares 5"});
    const std::string pyramid = replaced(good, "3 1 4 1\n1 1 2 3 4\n", "3 1 19 1\n1 1 2 3 4 1\n");
    check_error_text(dir, "pyramid.msh", pyramid, {line_of(pyramid, "1 1 2 3 4 1"), "element 1", "type 19", "pyramid"});
    const std::string unknown = replaced(good, "1 1 2 3 4\n", "1 1 2 3 8\n");
    check_error_text(dir, "unknown.msh", unknown, {line_of(unknown, "1 1 2 3 8"), "element 1", "node 8"});
}

BOOST_AUTO_TEST_CASE(malformed_binary_files_name_the_byte_offset) {
    const ScratchDir dir("gmsh_bad_binary");
    const std::string good = small22_binary(false);

    std::string marker = good;
    const std::size_t marker_at = marker.find("2.2 1 8\n") + 8;
    marker[marker_at] = 2;
    check_error_text(dir, "marker.msh", marker, {"(byte ", "endianness marker is 2"});

    check_error_text(dir, "truncated.msh", good.substr(0, good.find("$EndNodes") - 30), {"(byte ", "number of nodes", "cannot fit"});
    check_error_text(dir, "truncated_elements.msh", good.substr(0, good.find("$EndElements") - 20), {"(byte ", "file ends inside"});
    check_error_text(dir, "huge.msh", replaced(good, "$Nodes\n5\n", "$Nodes\n500000000\n"), {"(byte ", "number of nodes", "cannot fit"});

    std::size_t offset = 0;
    const std::string unknown_node = small22_binary(false, 99, &offset);
    check_error_text(dir, "unknown_node.msh", unknown_node,
                     {"(byte " + std::to_string(offset) + ")", "element 3", "node 99"});

    std::string nan_node = good;
    const std::size_t x_of_node_2 = nan_node.find("$Nodes\n5\n") + 9 + 28 + 4;
    const double nan = std::nan("");
    std::memcpy(&nan_node[x_of_node_2], &nan, sizeof nan);
    check_error_text(dir, "nan.msh", nan_node, {"(byte " + std::to_string(x_of_node_2 - 4) + ")", "node 2", "non-finite"});

    // MSH 4.1 with a node count in the billions.
    Bytes b;
    b.text("$MeshFormat\n4.1 1 8\n").i32(1).text("\n$EndMeshFormat\n$Nodes\n").u64(1).u64(4000000000ULL).u64(1).u64(4000000000ULL);
    b.text("\n$EndNodes\n");
    check_error_text(dir, "huge41.msh", b.data, {"(byte ", "number of nodes of 4000000000", "cannot fit"});

    Bytes hex;
    hex.text("$MeshFormat\n4.1 1 8\n").i32(1).text("\n$EndMeshFormat\n$Nodes\n").u64(1).u64(1).u64(1).u64(1);
    hex.i32(0).i32(1).i32(0).u64(1).u64(1).f64(0).f64(0).f64(0).text("\n$EndNodes\n");
    hex.text("$Elements\n").u64(1).u64(1).u64(12).u64(12).i32(3).i32(1).i32(17).u64(1).u64(12);
    for (int i = 0; i < 20; ++i) hex.u64(1);
    hex.text("\n$EndElements\n");
    check_error_text(dir, "hex41.msh", hex.data, {"(byte ", "element 12", "type 17", "hexahedron"});
}

BOOST_AUTO_TEST_SUITE_END()
