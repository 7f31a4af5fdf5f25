// The boundary as a surface to slide on (issue 17, its first part): boundary faces, feature
// curves and corners found on real meshes, and projections back onto the input's boundary.
#include <boost/test/unit_test.hpp>
#include <cmath>
#include <vector>

#include "paloverde/core/error.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/boundary_surface.hpp"
#include "support/surface_meshes.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;

namespace {

// The bundled example (examples/data/tangled_cube.vtk).
pv::Mesh bundled_cube() {
    return pv::read_mesh(std::filesystem::path(PALOVERDE_SOURCE_DIR) / "examples/data/tangled_cube.vtk").mesh;
}

pv::Vec3 at(const pv::Mesh& mesh, pv::VertexId v) {
    const auto x = mesh.coordinates();
    return {x[3 * static_cast<std::size_t>(v)], x[3 * static_cast<std::size_t>(v) + 1], x[3 * static_cast<std::size_t>(v) + 2]};
}

}  // namespace

BOOST_AUTO_TEST_SUITE(boundary_surface)

// The tangled cube (7 x 7 x 7 vertices, its interior moved, its boundary untouched): 8 corners,
// the 5 inner vertices of each of its 12 edges on curves, the 5 x 5 inside each face on the
// surface; its tangled interior does not change that (faces face outward by the mesh's corner
// order, not by the geometry).
BOOST_AUTO_TEST_CASE(a_cube_has_eight_corners_twelve_edges_and_six_faces) {
    const auto mesh = bundled_cube();
    const pv::BoundarySurface surface(mesh);
    BOOST_TEST(surface.count(pv::BoundaryRole::Corner) == 8u);
    BOOST_TEST(surface.count(pv::BoundaryRole::Curve) == 60u);
    BOOST_TEST(surface.count(pv::BoundaryRole::Surface) == 150u);
    BOOST_TEST(surface.count(pv::BoundaryRole::Interior) == 125u);
    BOOST_TEST(surface.boundary_faces() == 6u * 6u * 6u * 2u);
    BOOST_TEST(surface.feature_edges() == 12u * 6u);
    for (pv::VertexId v = 0; v < mesh.num_vertices(); ++v)
        BOOST_TEST((surface.role(v) == pv::BoundaryRole::Interior) == !mesh.fixed()[v], v);
    // Creases sharper than the feature angle only: at 95 degrees the cube is one smooth surface.
    pv::SurfaceOptions blunt;
    blunt.feature_angle = 95.0;
    const pv::BoundarySurface smooth(mesh, blunt);
    BOOST_TEST(smooth.count(pv::BoundaryRole::Surface) == 218u);
    BOOST_TEST(smooth.feature_edges() == 0u);
}

BOOST_AUTO_TEST_CASE(moved_boundary_vertices_project_back_where_they_may_be) {
    const auto mesh = bundled_cube();
    const pv::BoundarySurface surface(mesh);
    const double d = surface.bounding_box_diagonal();
    BOOST_TEST(d > 0.0);
    int checked[4] = {0, 0, 0, 0};
    for (pv::VertexId v = 0; v < mesh.num_vertices(); ++v) {
        const pv::Vec3 p = at(mesh, v);
        // Moved by a tenth of an element off its place, in a direction off every face and edge.
        const pv::Vec3 moved{p[0] + 0.021 * d, p[1] - 0.013 * d, p[2] + 0.017 * d};
        const pv::Vec3 q = surface.project(v, moved);
        const auto role = surface.role(v);
        ++checked[static_cast<int>(role)];
        BOOST_TEST_CONTEXT("vertex " << v << ", role " << static_cast<int>(role)) {
            if (role == pv::BoundaryRole::Interior) {
                BOOST_TEST((q == moved));
                continue;
            }
            if (role == pv::BoundaryRole::Corner) {
                BOOST_TEST((q == p));
                continue;
            }
            // On the cube's boundary: each coordinate within [min, max] and at least one (two on a
            // curve) at a face of the box, the same face(s) as the vertex's own.
            int on_faces = 0, same = 0;
            for (int c = 0; c < 3; ++c) {
                const bool q_at = std::abs(q[c] - 0.0) < 1e-9 * d || std::abs(q[c] - 1.0) < 1e-9 * d;
                const bool p_at = std::abs(p[c] - 0.0) < 1e-12 || std::abs(p[c] - 1.0) < 1e-12;
                on_faces += q_at;
                same += q_at && p_at && std::abs(q[c] - p[c]) < 1e-9 * d;
            }
            const int expected = role == pv::BoundaryRole::Curve ? 2 : 1;
            BOOST_TEST(on_faces >= expected);
            BOOST_TEST(same >= expected);
        }
    }
    BOOST_TEST(checked[0] == 125);
    BOOST_TEST(checked[3] == 8);
}

// Moves along the surface: a face vertex keeps the part of a move within its face's plane, an edge
// vertex the part along its edge, a corner none. A face vertex projects onto its own face even
// where another face of the boundary is nearer: it never cuts across a crease.
BOOST_AUTO_TEST_CASE(moves_stay_on_the_vertex_own_face_edge_or_corner) {
    const auto mesh = bundled_cube();
    const pv::BoundarySurface surface(mesh);
    const pv::Vec3 move{0.1, 0.2, 0.3};
    int checked[4] = {0, 0, 0, 0};
    for (pv::VertexId v = 0; v < mesh.num_vertices(); ++v) {
        const pv::Vec3 p = at(mesh, v);
        const auto role = surface.role(v);
        const pv::Vec3 t = surface.tangent(v, move);
        BOOST_TEST_CONTEXT("vertex " << v) {
            for (int c = 0; c < 3; ++c) {
                const bool at_face = std::abs(p[c]) < 1e-12 || std::abs(p[c] - 1.0) < 1e-12;
                const double expected = role == pv::BoundaryRole::Corner || (at_face && role != pv::BoundaryRole::Interior)
                                            ? 0.0
                                            : move[c];
                BOOST_TEST(t[c] == expected, boost::test_tools::tolerance(1e-12));
            }
            // A face vertex at x = 0 taken to a point just inside the face y = 0: the nearest
            // boundary point is on y = 0, but the vertex's own face is x = 0.
            if (role == pv::BoundaryRole::Surface && std::abs(p[0]) < 1e-12) {
                const pv::Vec3 q = surface.project(v, {0.3, 0.001, p[2]});
                BOOST_TEST(std::abs(q[0]) < 1e-12);
                BOOST_TEST(q[1] == 0.001, boost::test_tools::tolerance(1e-9));
            }
        }
        ++checked[static_cast<int>(role)];
    }
    BOOST_TEST(checked[static_cast<int>(pv::BoundaryRole::Surface)] == 150);
    // Distances to the input's boundary: zero on it, the depth inside.
    BOOST_TEST(surface.distance({0.5, 0.5, 0.0}) == 0.0, boost::test_tools::tolerance(1e-12));
    BOOST_TEST(surface.distance({0.5, 0.4, 0.3}) == 0.3, boost::test_tools::tolerance(1e-12));
}

// A planar triangle mesh: its boundary is a curve, with corners where it turns sharply.
BOOST_AUTO_TEST_CASE(a_square_of_triangles_has_four_corners) {
    // 3 x 3 vertices on the unit square, 8 triangles.
    std::vector<double> xyz;
    for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) xyz.insert(xyz.end(), {0.5 * i, 0.5 * j, 0.0});
    std::vector<pv::VertexId> tris;
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) {
            const int a = 3 * j + i, b = a + 1, c = a + 3, d = a + 4;
            tris.insert(tris.end(), {a, b, d, a, d, c});
        }
    const pv::Mesh mesh(pv::ElementKind::Triangle, xyz, tris);
    const pv::BoundarySurface surface(mesh);
    BOOST_TEST(surface.count(pv::BoundaryRole::Corner) == 4u);
    BOOST_TEST(surface.count(pv::BoundaryRole::Curve) == 4u);
    BOOST_TEST(surface.count(pv::BoundaryRole::Interior) == 1u);
    BOOST_TEST(surface.boundary_faces() == 8u);
    BOOST_TEST(surface.freedom(4) == 2);
    BOOST_TEST(surface.freedom(1) == 1);
    BOOST_TEST(surface.freedom(0) == 0);
    // The midpoint of the bottom side, moved up and right, comes back to the side.
    const auto q = surface.project(1, {0.6, 0.2, 0.0});
    BOOST_TEST(q[0] == 0.6, boost::test_tools::tolerance(1e-12));
    BOOST_TEST(q[1] == 0.0, boost::test_tools::tolerance(1e-12));
}

BOOST_AUTO_TEST_CASE(a_round_surface_has_no_creases_and_bad_options_are_refused) {
    const auto mesh = pv::read_mesh(pv::test::shared_data("mesquite/tets/flat-tet-sphere.vtk")).mesh;
    const pv::BoundarySurface surface(mesh);
    BOOST_TEST_MESSAGE("flat-tet-sphere: " << surface.count(pv::BoundaryRole::Surface) << " surface, "
                                           << surface.count(pv::BoundaryRole::Curve) << " curve, "
                                           << surface.count(pv::BoundaryRole::Corner) << " corner vertices");
    BOOST_TEST(surface.count(pv::BoundaryRole::Surface) > 0u);
    for (double bad : {0.0, 180.0, -5.0, std::nan("")}) {
        pv::SurfaceOptions options;
        options.feature_angle = bad;
        BOOST_CHECK_THROW(pv::BoundarySurface(mesh, options), pv::OptionError);
    }
}

// What makes a distributed run slide as the serial one: the surface does not depend on how the
// vertices are numbered nor on which corner each element lists first. The tire (curved, with
// creases) renumbered backwards, each tet's corners turned (0 1 2 3 -> 0 2 3 1, the same
// orientation): every role, tangent and projection is the same, bit for bit.
BOOST_AUTO_TEST_CASE(the_surface_is_the_same_whatever_the_numbering) {
    const auto mesh = pv::read_mesh(pv::test::shared_data("mesquite/tets/tire.vtk")).mesh;
    const pv::VertexId n = mesh.num_vertices();
    auto renamed = [n](pv::VertexId v) { return n - 1 - v; };
    std::vector<double> xyz(mesh.coordinates().size());
    for (pv::VertexId v = 0; v < n; ++v)
        for (int c = 0; c < 3; ++c) xyz[3 * renamed(v) + c] = mesh.coordinates()[3 * v + c];
    std::vector<pv::VertexId> corners;
    for (pv::ElementId e = 0; e < mesh.num_elements(); ++e) {
        const auto k = mesh.element(e);
        for (int i : {0, 2, 3, 1}) corners.push_back(renamed(k[i]));
    }
    const pv::Mesh other(pv::ElementKind::Tetrahedron, std::move(xyz), std::move(corners));
    const pv::BoundarySurface surface(mesh), same(other);
    BOOST_TEST(same.count(pv::BoundaryRole::Curve) == surface.count(pv::BoundaryRole::Curve));
    const double h = 0.01 * surface.bounding_box_diagonal();
    for (pv::VertexId v = 0; v < n; ++v) {
        const pv::VertexId w = renamed(v);
        BOOST_TEST((same.role(w) == surface.role(v)), "vertex " << v);
        const pv::Vec3 p = at(mesh, v), moved = {p[0] + h, p[1] - 0.5 * h, p[2] + 0.25 * h};
        BOOST_TEST((same.project(w, moved) == surface.project(v, moved)), "vertex " << v);
        BOOST_TEST((same.tangent(w, {1.0, 2.0, 3.0}) == surface.tangent(v, {1.0, 2.0, 3.0})), "vertex " << v);
    }
}

// A surface mesh's triangles that the input turned over (a vertex slid past its neighbour turns
// two over): seen, given the surface's normal, against which they are inverted, and no crease
// of their own. A tetrahedron's faces and a poorer torus's slivers are not turned over.
BOOST_AUTO_TEST_CASE(a_surface_knows_what_its_input_turned_over) {
    const pv::Mesh tangled = pv::test::tangled_torus(32, 16);
    const pv::BoundarySurface surface(tangled);
    BOOST_TEST(surface.turned_over() == 8u);
    BOOST_TEST(surface.feature_edges() == 0u);
    BOOST_TEST(surface.count(pv::BoundaryRole::Surface) == static_cast<std::size_t>(tangled.num_vertices()));
    int against = 0;
    for (pv::ElementId e = 0; e < tangled.num_elements(); ++e) {
        const auto c = tangled.element(e);
        const pv::Vec3 a = at(tangled, c[0]), b = at(tangled, c[1]), d = at(tangled, c[2]);
        const pv::Vec3 u{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w{d[0] - a[0], d[1] - a[1], d[2] - a[2]};
        const pv::Vec3 own{u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
        const pv::Vec3 n = surface.element_normals()[static_cast<std::size_t>(e)];
        against += own[0] * n[0] + own[1] * n[1] + own[2] * n[2] < 0.0;
    }
    BOOST_TEST(against == 8);
    BOOST_TEST(pv::BoundarySurface(pv::test::torus(32, 16, 0.35)).turned_over() == 0u);
    const pv::Mesh tetrahedron(pv::ElementKind::Triangle, {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1},
                               {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3});
    BOOST_TEST(pv::BoundarySurface(tetrahedron).turned_over() == 0u);
}

BOOST_AUTO_TEST_SUITE_END()
