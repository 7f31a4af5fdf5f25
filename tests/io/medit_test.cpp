#include <boost/test/unit_test.hpp>

#include <algorithm>
#include <chrono>
#include <cstdint>
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

const std::string kSmall =
    "MeshVersionFormatted 2\n"
    "Dimension 3\n"
    "Vertices\n"
    "5\n"
    "0 0 0 1\n"
    "1 0 0 1\n"
    "0 1 0 2\n"
    "0 0 1 2\n"
    "1 1 1 3\n"
    "Tetrahedra\n"
    "2\n"
    "1 2 3 4 7\n"
    "2 3 4 5 8\n"
    "End\n";

}  // namespace

BOOST_AUTO_TEST_SUITE(medit)

BOOST_AUTO_TEST_CASE(tetwild_meshes_read_with_positive_orientation) {
    struct Case {
        const char* name;
        VertexId vertices;
        ElementId tets;
    };
    for (const Case& c : {Case{"tetwild/armadillo.mesh", 18319, 74040}, Case{"tetwild/octopus-vol.mesh", 12273, 45359}}) {
        BOOST_TEST_CONTEXT(c.name) {
            const auto start = std::chrono::steady_clock::now();
            const MeshFile file = read_mesh(shared_data(c.name));
            const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            BOOST_TEST_MESSAGE(c.name << " read in " << seconds * 1e3 << " ms");
            BOOST_TEST((file.mesh.kind() == ElementKind::Tetrahedron));
            BOOST_TEST(file.mesh.num_vertices() == c.vertices);
            BOOST_TEST(file.mesh.num_elements() == c.tets);
            // Medit (as TetWild writes it) uses Paloverde's orientation: every tet is positive.
            BOOST_TEST(positive_tets(file.mesh) == c.tets);
            const Field* vertex_refs = file.point_field("ref");
            BOOST_REQUIRE(vertex_refs);
            BOOST_TEST(vertex_refs->values.size() == static_cast<std::size_t>(c.vertices));
            const Field* tet_refs = file.cell_field("ref");
            BOOST_REQUIRE(tet_refs);
            BOOST_TEST(tet_refs->values.size() == static_cast<std::size_t>(c.tets));
            BOOST_TEST(!file.fixed_from_file);
            BOOST_TEST(file.mesh.num_free_vertices() > 0);
            BOOST_TEST(file.mesh.num_free_vertices() < file.mesh.num_vertices());
        }
    }
}

BOOST_AUTO_TEST_CASE(two_dimensional_triangles_lie_in_z_zero) {
    const ScratchDir dir("medit_2d");
    write_file(dir / "square.mesh",
               "MeshVersionFormatted 1\nDimension 2\nVertices\n4\n0 0 1\n2 0 1\n2 1.5 2\n0 1.5 2\n"
               "Edges\n4\n1 2 1\n2 3 1\n3 4 1\n4 1 1\nTriangles\n2\n1 2 3 10\n1 3 4 20\nEnd\n");
    const MeshFile file = read_mesh(dir / "square.mesh");
    BOOST_TEST((file.mesh.kind() == ElementKind::Triangle));
    BOOST_REQUIRE_EQUAL(file.mesh.num_vertices(), 4);
    BOOST_REQUIRE_EQUAL(file.mesh.num_elements(), 2);
    const std::vector<double> xyz = {0, 0, 0, 2, 0, 0, 2, 1.5, 0, 0, 1.5, 0};
    BOOST_TEST(std::equal(xyz.begin(), xyz.end(), file.mesh.coordinates().begin()));
    const std::vector<VertexId> triangles = {0, 1, 2, 0, 2, 3};
    BOOST_TEST(std::equal(triangles.begin(), triangles.end(), file.mesh.connectivity().begin()));
    BOOST_TEST(file.mesh.is_planar());
    // Counterclockwise in the file, so the normal that orients the triangles is +z.
    BOOST_TEST(file.mesh.plane_normal()[2] == 1.0);
    const std::vector<double> vertex_refs = {1, 1, 2, 2};
    BOOST_TEST(file.point_field("ref")->values == vertex_refs, boost::test_tools::per_element());
    const std::vector<double> triangle_refs = {10, 20};
    BOOST_TEST(file.cell_field("ref")->values == triangle_refs, boost::test_tools::per_element());
}

BOOST_AUTO_TEST_CASE(comments_case_and_skipped_sections) {
    const ScratchDir dir("medit_comments");
    const std::string text = R"(# written by hand
meshversionformatted
  2
DIMENSION 3   # three
# the points
vertices 5
0 0 0 1
1 0 0 1   # a comment after a vertex
0 1 0 2
# a comment between vertices
0 0 1 2
1 1 1 3
Corners 2 1 5
Ridges
1
3
RequiredVertices 1 4
Edges 2
1 2 0
2 3 0
RequiredEdges 1 1
Normals 1
0 0 1
NormalAtVertices 1
1 1
Tangents 1 1 0 0
TangentAtVertices 1 2 1
Quadrilaterals 0
Hexahedra
0
Triangles
2
1 2 3 5
2 3 4 6
TetraHedra
2
1 2 3 4 7
2 3 4 5 8
end
anything after End is ignored
)";
    write_file(dir / "commented.mesh", text);
    const MeshFile file = read_mesh(dir / "commented.mesh");
    BOOST_TEST((file.mesh.kind() == ElementKind::Tetrahedron));
    BOOST_REQUIRE_EQUAL(file.mesh.num_vertices(), 5);
    BOOST_REQUIRE_EQUAL(file.mesh.num_elements(), 2);
    const std::vector<VertexId> tets = {0, 1, 2, 3, 1, 2, 3, 4};
    BOOST_TEST(std::equal(tets.begin(), tets.end(), file.mesh.connectivity().begin()));
    BOOST_TEST(positive_tets(file.mesh) == 2);
    // Refs of the kept kind only: the triangles' 5 and 6 are gone.
    const std::vector<double> tet_refs = {7, 8};
    BOOST_TEST(file.cell_field("ref")->values == tet_refs, boost::test_tools::per_element());
    const std::vector<double> vertex_refs = {1, 1, 2, 2, 3};
    BOOST_TEST(file.point_field("ref")->values == vertex_refs, boost::test_tools::per_element());
}

// Every element section, in any order, with boundary quadrilaterals and triangles (dropped). A
// Medit prism turns its first triangle towards the second, the mirror of a VTK wedge: read, it is
// the wedge (9, 11, 10, 12, 14, 13), valid, not flipped.
BOOST_AUTO_TEST_CASE(reads_every_element_section) {
    const ScratchDir dir("medit_cells");
    const std::string text =
        "MeshVersionFormatted 2\nDimension 3\nVertices\n23\n"
        "0 0 0 0\n1 0 0 0\n1 1 0 0\n0 1 0 0\n0 0 1 0\n1 0 1 0\n1 1 1 0\n0 1 1 0\n"  // hexahedron
        "2 0 0 0\n3 0 0 0\n2 1 0 0\n2 0 1 0\n3 0 1 0\n2 1 1 0\n"                      // prism
        "4 0 0 0\n5 0 0 0\n5 1 0 0\n4 1 0 0\n4.5 0.5 1 0\n"                              // pyramid
        "6 0 0 0\n7 0 0 0\n6 1 0 0\n6 0 1 0\n"                                          // tetrahedron
        "Tetrahedra 1\n20 21 22 23 4\nHexahedra 1\n1 2 3 4 5 6 7 8 5\nPrisms 1\n9 10 11 12 13 14 6\n"
        "Pyramids 1\n15 16 17 18 19 7\nQuadrilaterals 1\n1 4 3 2 8\nTriangles 1\n9 11 10 9\nEnd\n";
    write_file(dir / "cells.mesh", text);
    const MeshFile file = read_mesh(dir / "cells.mesh");
    BOOST_REQUIRE_EQUAL(file.mesh.num_cells(), 4);
    const std::vector<CellType> types = {CellType::Tetrahedron, CellType::Hexahedron, CellType::Wedge, CellType::Pyramid};
    BOOST_TEST(std::ranges::equal(file.mesh.cell_types(), types));
    const std::vector<VertexId> wedge = {8, 10, 9, 11, 13, 12};
    BOOST_TEST(std::ranges::equal(file.mesh.cell(2), wedge));
    BOOST_TEST(!file.orientation.flipped);
    BOOST_TEST(count_orientations(file.mesh).inverted == 0);
    const std::vector<double> refs = {4, 5, 6, 7};
    BOOST_TEST(file.cell_field("ref")->values == refs, boost::test_tools::per_element());

    // Written back: a section per type, the prism in Medit's order.
    write_mesh(dir / "copy.mesh", file.mesh, {}, file.point_fields, file.cell_fields);
    const std::string copy = read_text(dir / "copy.mesh");
    BOOST_TEST(copy.find("\nPrisms\n1\n9 10 11 12 13 14 6\n") != std::string::npos);
    BOOST_TEST(copy.find("\nTetrahedra\n1\n20 21 22 23 4\n") < copy.find("\nHexahedra\n"));

    // A 2D file of quadrilaterals and triangles.
    write_file(dir / "flat.mesh",
               "MeshVersionFormatted 2\nDimension 2\nVertices 7\n0 0 0\n1 0 0\n2 0 0\n0 1 0\n1 1 0\n2 1 0\n1 2 0\n"
               "Quadrilaterals 2\n1 2 5 4 1\n2 3 6 5 2\nTriangles 2\n4 5 7 3\n5 6 7 4\nEdges 1\n1 2 0\nEnd\n");
    const MeshFile flat = read_mesh(dir / "flat.mesh");
    BOOST_TEST((flat.mesh.kind() == ElementKind::Triangle));
    BOOST_REQUIRE_EQUAL(flat.mesh.num_cells(), 4);
    BOOST_TEST((flat.mesh.cell_type(0) == CellType::Quadrilateral));
    BOOST_TEST((flat.mesh.cell_type(3) == CellType::Triangle));
    BOOST_TEST(flat.mesh.cell(1)[2] == 5);
    BOOST_TEST(count_orientations(flat.mesh).inverted == 0);
}

BOOST_AUTO_TEST_CASE(shared_meshes_round_trip_exactly) {
    const ScratchDir dir("medit_round_trip");
    for (const char* name : {"stellar/house2.node", "tetwild/armadillo.mesh", "tetwild/octopus-vol.mesh"}) {
        BOOST_TEST_CONTEXT(name) {
            const MeshFile original = read_mesh(shared_data(name));
            write_mesh(dir / "copy.mesh", original.mesh, {}, original.point_fields, original.cell_fields);
            const MeshFile copy = read_mesh(dir / "copy.mesh");
            check_same_mesh(original.mesh, copy.mesh);
            BOOST_TEST(std::equal(original.mesh.fixed().begin(), original.mesh.fixed().end(), copy.mesh.fixed().begin()));
            if (const Field* refs = original.cell_field("ref")) {
                BOOST_TEST(copy.cell_field("ref")->values == refs->values, boost::test_tools::per_element());
                BOOST_TEST(copy.point_field("ref")->values == original.point_field("ref")->values,
                           boost::test_tools::per_element());
            }
        }
    }
}

BOOST_AUTO_TEST_CASE(triangle_mesh_round_trips_with_refs) {
    const ScratchDir dir("medit_round_trip_tri");
    Mesh mesh = awkward_triangles();
    std::vector<std::uint8_t> fixed(static_cast<std::size_t>(mesh.num_vertices()), 1);
    mesh.set_fixed(fixed);  // not representable in Medit: boundary detection decides on reading
    Field vertex_refs{"ref", 1, {}};
    for (VertexId v = 0; v < mesh.num_vertices(); ++v) vertex_refs.values.push_back(v % 4 - 1);
    Field triangle_refs{"ref", 1, {}};
    for (ElementId e = 0; e < mesh.num_elements(); ++e) triangle_refs.values.push_back(100 + e);
    const Field other{"velocity", 3, std::vector<double>(3 * static_cast<std::size_t>(mesh.num_vertices()), 1.0)};
    const Field points[] = {other, vertex_refs};
    const Field cells[] = {triangle_refs};
    write_mesh(dir / "tri.mesh", mesh, {}, points, cells);

    const MeshFile file = read_mesh(dir / "tri.mesh");
    check_same_mesh(mesh, file.mesh);
    BOOST_TEST(file.point_field("ref")->values == vertex_refs.values, boost::test_tools::per_element());
    BOOST_TEST(file.cell_field("ref")->values == triangle_refs.values, boost::test_tools::per_element());
    BOOST_TEST(!file.point_field("velocity"));
    BOOST_TEST(!file.fixed_from_file);
    const auto boundary = boundary_vertices(mesh.kind(), mesh.connectivity(), mesh.num_vertices());
    BOOST_TEST(std::equal(boundary.begin(), boundary.end(), file.mesh.fixed().begin()));
}

BOOST_AUTO_TEST_CASE(writer_output_without_refs) {
    const ScratchDir dir("medit_writer");
    const Mesh mesh(ElementKind::Tetrahedron, {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0.1}, {0, 1, 2, 3});
    write_mesh(dir / "one.mesh", mesh);
    BOOST_TEST(read_text(dir / "one.mesh") ==
               "MeshVersionFormatted 2\n\nDimension 3\n\nVertices\n4\n0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 0.1 0\n\n"
               "Tetrahedra\n1\n1 2 3 4 0\n\nEnd\n");
}

BOOST_AUTO_TEST_CASE(refs_that_are_not_integers_cannot_be_written) {
    const ScratchDir dir("medit_bad_refs");
    const Mesh mesh(ElementKind::Tetrahedron, {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, 1, 2, 3});
    const Field fractional[] = {Field{"ref", 1, {0.5}}};
    BOOST_CHECK_THROW(write_mesh(dir / "bad.mesh", mesh, {}, {}, fractional), Error);
    const Field vector[] = {Field{"ref", 2, {1, 2, 3, 4, 5, 6, 7, 8}}};
    BOOST_CHECK_THROW(write_mesh(dir / "bad.mesh", mesh, {}, vector), Error);
    BOOST_TEST(!fs::exists(dir / "bad.mesh"));
}

BOOST_AUTO_TEST_CASE(malformed_files_name_file_line_and_problem) {
    const ScratchDir dir("medit_bad");
    write_file(dir / "good.mesh", kSmall);
    BOOST_REQUIRE_NO_THROW(read_mesh(dir / "good.mesh"));

    check_error_text(dir, "empty.mesh", "", {"empty file", "MeshVersionFormatted"});
    check_error_text(dir, "comments_only.mesh", "# nothing\n# here\n", {"empty file"});
    check_error_text(dir, "no_version.mesh", replaced(kSmall, "MeshVersionFormatted 2\n", ""),
                     {":1:", "expected MeshVersionFormatted", "'Dimension'"});
    check_error_text(dir, "version.mesh", replaced(kSmall, "MeshVersionFormatted 2", "MeshVersionFormatted 9"),
                     {":1:", "MeshVersionFormatted 9"});
    check_error_text(dir, "dimension.mesh", replaced(kSmall, "Dimension 3", "Dimension 4"), {":2:", "Dimension 4"});
    check_error_text(dir, "no_dimension.mesh", replaced(kSmall, "Dimension 3\n", ""), {":2:", "Vertices comes before Dimension"});
    check_error_text(dir, "no_vertices.mesh", "MeshVersionFormatted 2\nDimension 3\nEnd\n", {"no Vertices section"});
    check_error_text(dir, "tets_first.mesh", "MeshVersionFormatted 2\nDimension 3\nTetrahedra\n0\nEnd\n",
                     {":3:", "Tetrahedra comes before Vertices"});

    const std::string word = replaced(kSmall, "0 1 0 2", "0 one 0 2");
    check_error_text(dir, "word.mesh", word, {line_of(word, "one"), "expected a vertex coordinate", "'one'"});
    const std::string nan = replaced(kSmall, "0 1 0 2", "0 1 NaN 2");
    check_error_text(dir, "nan.mesh", nan, {line_of(nan, "NaN"), "vertex 3", "non-finite"});
    const std::string inf = replaced(kSmall, "1 1 1 3", "1 inf 1 3");
    check_error_text(dir, "inf.mesh", inf, {line_of(inf, "inf"), "vertex 5", "non-finite"});
    const std::string ref = replaced(kSmall, "1 1 1 3", "1 1 1 3.5");
    check_error_text(dir, "ref.mesh", ref, {line_of(ref, "3.5"), "vertex reference", "'3.5'"});

    const std::string zero = replaced(kSmall, "2 3 4 5 8", "2 3 0 5 8");
    check_error_text(dir, "zero.mesh", zero, {line_of(zero, "2 3 0 5"), "tetrahedron 2", "vertex 0", "1 to 5"});
    const std::string beyond = replaced(kSmall, "1 2 3 4 7", "1 2 3 6 7");
    check_error_text(dir, "beyond.mesh", beyond, {line_of(beyond, "1 2 3 6"), "tetrahedron 1", "vertex 6", "1 to 5"});
    const std::string negative = replaced(kSmall, "1 2 3 4 7", "1 2 -3 4 7");
    check_error_text(dir, "negative.mesh", negative, {line_of(negative, "-3"), "tetrahedron 1", "vertex -3"});

    const std::string huge = replaced(kSmall, "Vertices\n5\n", "Vertices\n123456789012\n");
    check_error_text(dir, "huge.mesh", huge, {line_of(huge, "123456789012"), "number of vertices", "cannot fit"});
    const std::string huge_tets = replaced(kSmall, "Tetrahedra\n2\n", "Tetrahedra\n9000000000000000000\n");
    check_error_text(dir, "huge_tets.mesh", huge_tets, {line_of(huge_tets, "9000000000000000000"), "cannot fit"});
    const std::string huge_edges = replaced(kSmall, "End\n", "Edges 4000000000\n1 2 0\nEnd\n");
    check_error_text(dir, "huge_edges.mesh", huge_edges, {line_of(huge_edges, "4000000000"), "Edges", "cannot fit"});
    const std::string minus = replaced(kSmall, "Vertices\n5\n", "Vertices\n-5\n");
    check_error_text(dir, "minus.mesh", minus, {line_of(minus, "-5"), "negative"});

    // Padded so that the declared counts still fit in what is left: the end of file is what fails.
    const std::string padded = replaced(replaced(kSmall, "1 2 3 4 7\n2 3 4 5 8", "1  2  3  4  7\n2  3  4  5  8"),
                                        "End\n", "Edges 3\n1 2 0\n                    \nEnd\n");
    const std::string truncated = padded.substr(0, padded.find("2  3  4  5  8") + 6);
    check_error_text(dir, "truncated.mesh", truncated, {last_line(truncated), "end of file", "vertex number"});
    const std::string truncated_edges = padded.substr(0, padded.find("End\n"));
    check_error_text(dir, "truncated_edges.mesh", truncated_edges,
                     {last_line(truncated_edges), "end of file", "an entry of Edges"});
    // Cut in the vertices: the declared count no longer fits.
    const std::string cut_vertices = kSmall.substr(0, kSmall.find("0 0 1 2"));
    check_error_text(dir, "cut_vertices.mesh", cut_vertices, {":4:", "number of vertices of 5", "cannot fit"});

    // Cells with a repeated vertex are named by section and number, as Medit counts them.
    const std::string hexahedra = replaced(kSmall, "End\n", "Hexahedra\n1\n1 2 3 4 5 1 2 3 0\nEnd\n");
    check_error_text(dir, "hexahedra.mesh", hexahedra, {"hexahedron 1 repeats vertex 0"});
    const std::string prisms = replaced(kSmall, "End\n", "Prisms 1\n1 2 3 4 5 1 0\nEnd\n");
    check_error_text(dir, "prisms.mesh", prisms, {"prism 1 repeats vertex"});
    const std::string hexahedron_vertex = replaced(kSmall, "End\n", "Hexahedra 1\n1 2 3 4 5 6 7 9 0\nEnd\n");
    check_error_text(dir, "hexahedron_vertex.mesh", hexahedron_vertex,
                     {line_of(hexahedron_vertex, "1 2 3 4 5 6 7 9"), "hexahedron 1 refers to vertex 6", "1 to 5"});
    const std::string second_hexahedra = replaced(kSmall, "End\n", "Hexahedra 0\nHexahedra 0\nEnd\n");
    check_error_text(dir, "second_hexahedra.mesh", second_hexahedra, {"a second Hexahedra section"});
    // Second-order sections are not read.
    const std::string p2 = replaced(kSmall, "End\n", "TetrahedraP2\n0\nEnd\n");
    check_error_text(dir, "p2.mesh", p2, {line_of(p2, "TetrahedraP2"), "unknown Medit keyword 'TetrahedraP2'"});
    const std::string unknown = replaced(kSmall, "End\n", "Identifier\n\"x\"\nEnd\n");
    check_error_text(dir, "unknown.mesh", unknown, {line_of(unknown, "Identifier"), "unknown Medit keyword 'Identifier'"});
    const std::string extra = replaced(kSmall, "1 1 1 3\n", "1 1 1 3\n0.5 0.5 0.5 1\n");
    check_error_text(dir, "extra.mesh", extra, {line_of(extra, "0.5 0.5"), "unknown Medit keyword '0.5'"});
    const std::string twice = replaced(kSmall, "End\n", "Vertices 0\nEnd\n");
    check_error_text(dir, "twice.mesh", twice, {line_of(twice, "Vertices 0"), "second Vertices"});
    const std::string no_elements = "MeshVersionFormatted 2\nDimension 3\nVertices\n1\n0 0 0 0\nEnd\n";
    check_error_text(dir, "no_elements.mesh", no_elements, {"no triangles, quadrilaterals, tetrahedra", "(empty mesh)"});
    const std::string duplicate = replaced(kSmall, "2 3 4 5 8", "4 3 2 1 8");
    check_error_text(dir, "duplicate.mesh", duplicate, {"same"});
}

BOOST_AUTO_TEST_SUITE_END()
