#include <boost/test/unit_test.hpp>
#include <string>

#include "paloverde/core/error.hpp"
#include "paloverde/mesh/openmesh_adapter.hpp"
#include "paloverde/mesh/orientation.hpp"
#include "paloverde/mesh/mesh.hpp"

namespace pv = paloverde;

namespace {
// Two tets sharing the face (1,2,3), both positively oriented.
pv::Mesh two_tets() {
    return pv::Mesh(pv::ElementKind::Tetrahedron, {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1},
                    {0, 1, 2, 3, 1, 4, 2, 3});
}
// A 3x3 grid of vertices in the plane z = 2, 8 triangles; vertex 4 is the only interior one.
pv::Mesh grid(double flip = 1.0) {
    std::vector<double> xyz;
    for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) xyz.insert(xyz.end(), {double(i), flip * double(j), 2.0});
    std::vector<pv::VertexId> tris;
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) {
            const int a = 3 * j + i;
            tris.insert(tris.end(), {a, a + 1, a + 4, a, a + 4, a + 3});
        }
    return pv::Mesh(pv::ElementKind::Triangle, xyz, tris);
}
bool message_has(const std::exception& e, const std::string& word) {
    return std::string(e.what()).find(word) != std::string::npos;
}
}  // namespace

BOOST_AUTO_TEST_SUITE(mesh_type)

BOOST_AUTO_TEST_CASE(adjacency_lists_every_incident_element) {
    const auto mesh = two_tets();
    BOOST_TEST(mesh.num_vertices() == 5);
    BOOST_TEST(mesh.num_elements() == 2);
    BOOST_TEST(mesh.elements_of(0).size() == 1u);
    BOOST_TEST(mesh.elements_of(1).size() == 2u);
    BOOST_TEST(mesh.elements_of(4).size() == 1u);
    BOOST_TEST(mesh.elements_of(4)[0] == 1);
}

BOOST_AUTO_TEST_CASE(boundary_of_two_tets_is_every_vertex_and_of_a_grid_all_but_the_centre) {
    auto tets = two_tets();
    tets.fix_boundary();
    BOOST_TEST(tets.num_free_vertices() == 0);
    auto tris = grid();
    tris.fix_boundary();
    BOOST_TEST(tris.num_free_vertices() == 1);
    BOOST_TEST(tris.fixed()[4] == 0);
}

BOOST_AUTO_TEST_CASE(planar_triangles_are_oriented_by_the_majority_normal) {
    const auto up = grid();
    BOOST_TEST(up.is_planar());
    BOOST_TEST(up.plane_normal()[2] == 1.0);
    BOOST_TEST(pv::count_orientations(up).inverted == 0);
    const auto down = grid(-1.0);  // mirrored: the plane normal flips, nothing is inverted
    BOOST_TEST(down.plane_normal()[2] == -1.0);
    BOOST_TEST(pv::count_orientations(down).inverted == 0);
    // Fold the centre vertex past a corner: exactly the triangles around it that flip count.
    auto folded = grid();
    folded.coordinates()[3 * 4] = 2.5;
    folded.coordinates()[3 * 4 + 1] = 2.5;
    const auto counts = pv::count_orientations(folded);
    BOOST_TEST(counts.inverted > 0);
    BOOST_TEST(counts.inverted < 4);
}

BOOST_AUTO_TEST_CASE(exact_orientation_sees_a_flat_tet_as_degenerate) {
    auto mesh = two_tets();
    mesh.coordinates()[3 * 3 + 2] = 0.0;  // vertex 3 into the plane of 0,1,2
    const auto counts = pv::count_orientations(mesh);
    BOOST_TEST(counts.degenerate == 1);
    mesh.coordinates()[3 * 3 + 2] = -1e-300;  // below it by the smallest amount
    BOOST_TEST(pv::count_orientations(mesh).inverted == 1);
}

BOOST_AUTO_TEST_CASE(invalid_arrays_are_rejected_naming_the_culprit) {
    using pv::ElementKind;
    BOOST_CHECK_EXCEPTION(pv::Mesh(ElementKind::Tetrahedron, {0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 2, 7}),
                          pv::MeshError, [](const auto& e) { return message_has(e, "element 0") && message_has(e, "vertex 7"); });
    BOOST_CHECK_EXCEPTION(pv::Mesh(ElementKind::Triangle, {0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 1}), pv::MeshError,
                          [](const auto& e) { return message_has(e, "repeats vertex 1"); });
    BOOST_CHECK_EXCEPTION(pv::Mesh(ElementKind::Triangle, {0, 0, 0, 1, NAN, 0, 0, 1, 0}, {0, 1, 2}), pv::MeshError,
                          [](const auto& e) { return message_has(e, "vertex 1"); });
    BOOST_CHECK_THROW(pv::Mesh(ElementKind::Triangle, {0, 0, 0, 1}, {}), pv::MeshError);
    const pv::Mesh dup(ElementKind::Triangle, {0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 2, 2, 0, 1});
    BOOST_CHECK_EXCEPTION(pv::check_no_duplicate_elements(dup), pv::MeshError,
                          [](const auto& e) { return message_has(e, "elements 0 and 1"); });
    auto mesh = two_tets();
    BOOST_CHECK_THROW(mesh.set_fixed({1, 0}), pv::MeshError);
}

BOOST_AUTO_TEST_CASE(openmesh_triangles_copy_in_and_out_through_the_batch_interface) {
    pv::OpenMeshTriangles om;
    std::vector<pv::OpenMeshTriangles::VertexHandle> v;
    for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) v.push_back(om.add_vertex({double(i), double(j), 0.0}));
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) {
            const int a = 3 * j + i;
            om.add_face(v[a], v[a + 1], v[a + 4]);
            om.add_face(v[a], v[a + 4], v[a + 3]);
        }
    pv::OpenMeshAdapter adapter(om);
    auto copy = pv::Mesh::copy_of(adapter);
    BOOST_TEST(copy.num_vertices() == 9);
    BOOST_TEST(copy.num_elements() == 8);
    BOOST_TEST(copy.num_free_vertices() == 1);  // the centre; OpenMesh knows the boundary
    BOOST_TEST(copy.fixed()[4] == 0);
    BOOST_TEST(pv::count_orientations(copy).inverted == 0);
    // Move the centre in the copy and write it back.
    const pv::VertexId centre[] = {4};
    const double moved[] = {1.25, 0.75, 0.0};
    copy.set_coordinates(centre, moved);
    std::vector<double> xyz(3);
    copy.get_coordinates(centre, xyz);
    adapter.set_coordinates(centre, xyz);
    BOOST_TEST(om.point(v[4])[0] == 1.25);
    BOOST_TEST(om.point(v[4])[1] == 0.75);
}

BOOST_AUTO_TEST_SUITE_END()
