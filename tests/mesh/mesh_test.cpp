#include <boost/test/unit_test.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <set>
#include <string>
#include <utility>

#include "paloverde/core/error.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/mesh.hpp"
#include "paloverde/mesh/openmesh_adapter.hpp"
#include "paloverde/mesh/orientation.hpp"
#include "paloverde/mesh/renumber.hpp"
#include "support/mesh_checks.hpp"

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
const std::string shared = PALOVERDE_SHARED_DATA;

// The vertex graph the slow way: every edge of every element (with `cell_edges`, only those from
// corner 0 of each element, the cell edges), in ordered sets.
pv::VertexGraph reference_graph(const pv::Mesh& mesh, bool cell_edges) {
    std::vector<std::set<pv::VertexId>> rows(static_cast<std::size_t>(mesh.num_vertices()));
    for (pv::ElementId e = 0; e < mesh.num_elements(); ++e) {
        const auto c = mesh.element(e);
        for (std::size_t i = 0; i < (cell_edges && mesh.has_cells() ? 1 : c.size()); ++i)
            for (std::size_t j = i + 1; j < c.size(); ++j) {
                rows[static_cast<std::size_t>(c[i])].insert(c[j]);
                rows[static_cast<std::size_t>(c[j])].insert(c[i]);
            }
    }
    pv::VertexGraph g;
    g.offsets.push_back(0);
    for (const auto& row : rows) {
        g.neighbours.insert(g.neighbours.end(), row.begin(), row.end());
        g.offsets.push_back(static_cast<std::int64_t>(g.neighbours.size()));
    }
    return g;
}
// The mesh with `extra` unused vertices appended (a file may list points no element uses).
pv::Mesh with_unused_vertices(const pv::Mesh& mesh, int extra) {
    std::vector<double> xyz(mesh.coordinates().begin(), mesh.coordinates().end());
    for (int i = 0; i < 3 * extra; ++i) xyz.push_back(0.001 * i);
    return pv::Mesh(mesh.kind(), std::move(xyz),
                    std::vector<pv::VertexId>(mesh.connectivity().begin(), mesh.connectivity().end()));
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

BOOST_AUTO_TEST_CASE(degrees_of_freedom_say_where_a_vertex_moves_and_survive_renumbering) {
    auto mesh = two_tets();
    mesh.set_degrees_of_freedom({0, 3, 2, 1, 0});
    BOOST_TEST(mesh.fixed()[0] == 1);
    BOOST_TEST(mesh.fixed()[2] == 0);
    BOOST_TEST(mesh.num_free_vertices() == 3);
    BOOST_TEST(!mesh.can_move(4));
    BOOST_TEST(mesh.can_move(3));
    BOOST_TEST((!mesh.slides(1) && mesh.slides(2) && mesh.slides(3) && !mesh.slides(0)));
    // A renumbered copy keeps each vertex's freedom under its new id.
    const auto order = pv::locality_order(mesh);
    const auto copy = pv::renumbered(mesh, order);
    for (pv::VertexId v = 0; v < copy.num_vertices(); ++v)
        BOOST_TEST(copy.degrees_of_freedom(v) == mesh.degrees_of_freedom(order.old_vertex[v]));
    // Fixed flags alone: 0 or 3 again.
    mesh.set_fixed({1, 0, 0, 0, 1});
    BOOST_TEST(mesh.degrees_of_freedom(2) == 3);
    BOOST_TEST(!mesh.slides(3));
    try {
        mesh.set_degrees_of_freedom({0, 3, 4, 1, 0});
        BOOST_FAIL("no error for 4 degrees of freedom");
    } catch (const pv::MeshError& e) {
        BOOST_TEST(message_has(e, "vertex 2"));
    }
    BOOST_CHECK_THROW(mesh.set_degrees_of_freedom({0, 3}), pv::MeshError);
}

BOOST_AUTO_TEST_CASE(vertex_graph_lists_each_vertex_neighbours_once_in_order) {
    // Tetrahedra (with unused vertices: empty rows), triangles, and a mesh of hexahedra, pyramids
    // and tetrahedra with and without the cell-edges-only graph.
    const auto tire = pv::read_mesh(shared + "/mesquite/tets/tire.vtk").mesh;
    const auto mixed = pv::read_mesh(shared + "/mesquite/mixed/mixed-hex-pyr-tet.vtk").mesh;
    const auto hexes = pv::read_mesh(shared + "/mesquite/hexes/hex_5_tangled.vtk").mesh;
    for (const pv::Mesh* mesh : {&tire, &mixed, &hexes})
        for (bool cell_edges : {false, true}) {
            const auto g = pv::vertex_graph(*mesh, cell_edges), want = reference_graph(*mesh, cell_edges);
            BOOST_TEST(g.offsets == want.offsets);
            BOOST_TEST(g.neighbours == want.neighbours);
        }
    BOOST_TEST(mixed.has_cells());
    BOOST_TEST(pv::vertex_graph(mixed, true).neighbours.size() < pv::vertex_graph(mixed, false).neighbours.size());
    const auto unused = with_unused_vertices(tire, 1000);
    const auto g = pv::vertex_graph(unused);
    BOOST_TEST(g.offsets == reference_graph(unused, false).offsets);
    BOOST_TEST(g.offsets.back() == pv::vertex_graph(tire).offsets.back());
    const auto t = pv::read_mesh(shared + "/mesquite/tris/" + std::string("bad_circle_tri.vtk")).mesh;
    BOOST_TEST(pv::vertex_graph(t).neighbours == reference_graph(t, false).neighbours);
}

BOOST_AUTO_TEST_CASE(locality_order_is_a_permutation_with_many_unused_vertices) {
    // Each unused vertex is a component of its own: thousands of them, each visited alone.
    const auto tire = pv::read_mesh(shared + "/mesquite/tets/tire.vtk").mesh;
    const auto mesh = with_unused_vertices(tire, 20000);
    auto order = pv::locality_vertex_order(mesh);
    BOOST_TEST(order.size() == static_cast<std::size_t>(mesh.num_vertices()));
    std::sort(order.begin(), order.end());
    std::vector<pv::VertexId> every(order.size());
    std::iota(every.begin(), every.end(), pv::VertexId{0});
    BOOST_TEST(order == every);
    // The used vertices keep the order they have without the unused ones around them.
    std::vector<pv::VertexId> used;
    for (pv::VertexId v : pv::locality_vertex_order(mesh))
        if (v < tire.num_vertices()) used.push_back(v);
    BOOST_TEST(used == pv::locality_vertex_order(tire));
    BOOST_TEST(pv::locality_order(mesh).old_vertex == pv::locality_vertex_order(mesh));
}

BOOST_AUTO_TEST_CASE(canonical_element_positions_sort_the_sorted_vertex_keys) {
    // Keys below 2^32 (packed two to a word) and the same keys beyond 2^40 take different paths to
    // the same order, that of one sort.
    const auto tire = pv::read_mesh(shared + "/mesquite/tets/tire.vtk").mesh;
    const auto order = pv::locality_vertex_order(tire);
    std::vector<pv::GlobalId> key(order.size()), far(order.size());
    for (std::size_t i = 0; i < order.size(); ++i) {
        key[static_cast<std::size_t>(order[i])] = static_cast<pv::GlobalId>(i);
        far[static_cast<std::size_t>(order[i])] = static_cast<pv::GlobalId>(i) + (pv::GlobalId{1} << 40);
    }
    const auto positions = pv::canonical_element_positions(tire, key);
    BOOST_TEST(positions == pv::canonical_element_positions(tire, far));
    std::vector<std::pair<std::array<pv::GlobalId, 4>, pv::ElementId>> sorted;
    for (pv::ElementId e = 0; e < tire.num_elements(); ++e) {
        std::array<pv::GlobalId, 4> k{};
        for (int i = 0; i < 4; ++i) k[static_cast<std::size_t>(i)] = key[static_cast<std::size_t>(tire.element(e)[static_cast<std::size_t>(i)])];
        std::sort(k.begin(), k.end());
        sorted.emplace_back(k, e);
    }
    std::sort(sorted.begin(), sorted.end());
    bool same = true;
    for (std::size_t i = 0; i < sorted.size(); ++i) same = same && positions[static_cast<std::size_t>(sorted[i].second)] == static_cast<pv::GlobalId>(i);
    BOOST_TEST(same);
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

// Solvers renumber the caller's mesh in place and back: every field must follow its vertex or
// element there, and come back bit for bit.
BOOST_AUTO_TEST_CASE(permuting_in_place_carries_every_field_and_undoes_exactly) {
    pv::Mesh mesh = pv::read_mesh(shared + "/mesquite/mixed/mixed-hex-pyr-tet.vtk").mesh;
    const auto n = static_cast<std::size_t>(mesh.num_vertices());
    const auto m = static_cast<std::size_t>(mesh.num_elements());
    std::vector<std::uint8_t> freedom(n);
    std::vector<pv::GlobalId> ids(n);
    std::vector<double> reference(3 * n), lengths(n), metrics;
    for (std::size_t v = 0; v < n; ++v) {
        freedom[v] = static_cast<std::uint8_t>(v % 4);
        ids[v] = static_cast<pv::GlobalId>(1000 + 7 * v);
        for (int c = 0; c < 3; ++c) reference[3 * v + c] = mesh.coordinates()[3 * v + c] + 0.001 * double(v);
        lengths[v] = 1.0 + 0.01 * double(v);
        metrics.insert(metrics.end(), {1.0 + double(v), 2.0, 3.0, 0.1, 0.0, 0.2});
    }
    mesh.set_degrees_of_freedom(freedom);
    mesh.set_global_ids(ids);
    mesh.set_reference_coordinates(reference);
    mesh.set_target_edge_lengths(lengths);
    mesh.set_target_metrics(metrics);
    std::vector<pv::CornerMap> maps(m), roots(m);
    std::vector<double> volumes(m);
    for (std::size_t e = 0; e < m; ++e) {
        maps[e] = {{{1.0 + 0.01 * double(e), 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}}};
        roots[e] = {{{1.0, 0.0, 0.0}, {0.0, 2.0 + 0.01 * double(e), 0.0}, {0.0, 0.0, 1.0}}};
        volumes[e] = 0.5 + 0.001 * double(e);
    }
    mesh.set_targets(maps, volumes, roots);
    mesh.set_locality_ordered(true);
    const pv::Mesh before = mesh;

    // Reversed vertices, elements in a scrambled order.
    std::vector<pv::VertexId> old_vertex(n);
    std::vector<pv::ElementId> old_element(m);
    for (std::size_t i = 0; i < n; ++i) old_vertex[i] = static_cast<pv::VertexId>(n - 1 - i);
    for (std::size_t i = 0; i < m; ++i) old_element[i] = static_cast<pv::ElementId>((7 * i + 3) % m);
    BOOST_REQUIRE(std::gcd(std::size_t{7}, m) == 1u);
    mesh.permute(old_vertex, old_element);
    std::vector<pv::VertexId> new_id(n);
    for (std::size_t i = 0; i < n; ++i) new_id[static_cast<std::size_t>(old_vertex[i])] = static_cast<pv::VertexId>(i);
    for (std::size_t i = 0; i < m; ++i) {
        const auto e = static_cast<pv::ElementId>(i), old = old_element[i];
        for (std::size_t c = 0; c < 4; ++c) BOOST_TEST(mesh.element(e)[c] == new_id[before.element(old)[c]]);
        BOOST_TEST(mesh.cell_of(e) == before.cell_of(old));
        BOOST_TEST(mesh.corner_maps()[i] == before.corner_maps()[old]);
        BOOST_TEST(mesh.target_volumes()[i] == before.target_volumes()[old]);
        BOOST_TEST((mesh.target_maps()[i] == before.target_maps()[old] && mesh.target_metric_roots()[i] == before.target_metric_roots()[old]));
    }
    for (std::size_t i = 0; i < n; ++i) {
        const auto v = static_cast<pv::VertexId>(i), old = old_vertex[i];
        BOOST_TEST((mesh.point(v) == before.point(old)));
        BOOST_TEST(mesh.degrees_of_freedom(v) == before.degrees_of_freedom(old));
        BOOST_TEST(mesh.global_ids()[i] == before.global_ids()[old]);
        BOOST_TEST(mesh.reference_coordinates()[3 * i + 2] == before.reference_coordinates()[3 * old + 2]);
        BOOST_TEST(mesh.target_edge_lengths()[i] == before.target_edge_lengths()[old]);
        BOOST_TEST(mesh.target_metrics()[6 * i] == before.target_metrics()[6 * old]);
        for (pv::ElementId e : mesh.elements_of(v))
            BOOST_TEST((std::find(mesh.element(e).begin(), mesh.element(e).end(), v) != mesh.element(e).end()));
        BOOST_TEST(mesh.elements_of(v).size() == before.elements_of(old).size());
    }
    for (std::size_t i = 0; i < mesh.cell_connectivity().size(); ++i)
        BOOST_TEST(mesh.cell_connectivity()[i] == new_id[before.cell_connectivity()[i]]);

    // Back: the inverse orders give the mesh it was.
    std::vector<pv::ElementId> new_element(m);
    for (std::size_t i = 0; i < m; ++i) new_element[static_cast<std::size_t>(old_element[i])] = static_cast<pv::ElementId>(i);
    mesh.permute(new_id, new_element);
    pv::test::check_same_mesh(mesh, before);

    // Orders that are not permutations change nothing.
    old_element[1] = old_element[0];
    BOOST_CHECK_EXCEPTION(mesh.permute(old_vertex, old_element), pv::MeshError,
                          [](const auto& e) { return message_has(e, "not a permutation"); });
    BOOST_CHECK_THROW(mesh.permute(std::vector<pv::VertexId>(n - 1, 0), new_element), pv::MeshError);
    old_vertex[0] = static_cast<pv::VertexId>(n);
    BOOST_CHECK_THROW(mesh.permute(old_vertex, new_element), pv::MeshError);
    pv::test::check_same_mesh(mesh, before);
    // Vertices kept, elements moved.
    mesh.permute({}, new_element);
    for (std::size_t i = 0; i < m; ++i)
        BOOST_TEST(mesh.element(static_cast<pv::ElementId>(i))[0] == before.element(new_element[i])[0]);
}

BOOST_AUTO_TEST_SUITE_END()

BOOST_AUTO_TEST_SUITE(surface_normals)

// Surface normals are per element, of unit length, for triangle meshes only; flipping the
// elements turns them with the elements, and a mesh renumbered carries them.
BOOST_AUTO_TEST_CASE(surface_normals_are_checked_and_carried) {
    pv::Mesh mesh(pv::ElementKind::Triangle, {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, 1, 2, 0, 1, 3});
    BOOST_CHECK_THROW(mesh.set_surface_normals({{0, 0, 1}}), pv::MeshError);             // one for two triangles
    BOOST_CHECK_THROW(mesh.set_surface_normals({{0, 0, 1}, {0, 0, 2}}), pv::MeshError);  // not a unit vector
    BOOST_CHECK_THROW(mesh.set_surface_normals({{0, 0, 1}, {0, NAN, 1}}), pv::MeshError);
    BOOST_TEST(!mesh.has_surface_normals());
    mesh.set_surface_normals({{0, 0, 1}, {0, -1, 0}});
    BOOST_TEST(mesh.surface_normals()[1][1] == -1.0);
    mesh.flip_elements();
    BOOST_TEST(mesh.surface_normals()[0][2] == -1.0);
    BOOST_TEST(mesh.surface_normals()[1][1] == 1.0);
    mesh.clear_surface_normals();
    BOOST_TEST(!mesh.has_surface_normals());
    pv::Mesh tets(pv::ElementKind::Tetrahedron, {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, 1, 2, 3});
    BOOST_CHECK_THROW(tets.set_surface_normals({{0, 0, 1}}), pv::MeshError);
}

BOOST_AUTO_TEST_SUITE_END()
