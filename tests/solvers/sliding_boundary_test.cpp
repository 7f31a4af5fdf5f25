// Sliding boundary vertices (boundary: slide, issue 17) in the local smoother: every boundary
// vertex ends on the input's boundary (flat faces in their plane, feature edges on the edge,
// corners in place), the worst element over all elements ends no lower than with the boundary
// fixed, nothing inverts, and the threads do not change the result.
#include <boost/test/data/test_case.hpp>
#include <boost/test/unit_test.hpp>
#include <cmath>
#include <utility>

#include "paloverde/core/error.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/boundary_surface.hpp"
#include "paloverde/mesh/orientation.hpp"
#include "paloverde/solvers/local_solver.hpp"
#include "support/sliding_checks.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;
namespace bdata = boost::unit_test::data;
using paloverde::test::check_cube_slid;
using paloverde::test::check_on_the_input_boundary;
using paloverde::test::shared_mesh;
using paloverde::test::tangled_cube;
using paloverde::test::worst_of_all;

namespace {

pv::LocalSolverOptions sliding(int threads = 1) {
    pv::LocalSolverOptions options;
    options.boundary = pv::LocalSolverOptions::Boundary::Slide;
    options.threads = threads;
    return options;
}

// Curved and faceted meshes: every boundary vertex on the input's boundary triangulation (or its
// boundary edges, for triangles), the worst of all elements no lower than with the boundary fixed.
void check_slid_on_the_input_boundary(const char* name) {
    const auto input = shared_mesh(name);
    auto fixed_mesh = input, slide_mesh = input;
    pv::LocalSolverOptions fixed_options = sliding();
    fixed_options.boundary = pv::LocalSolverOptions::Boundary::Fixed;
    const auto fixed = pv::LocalSolver(fixed_options).improve(fixed_mesh);
    const auto slide = pv::LocalSolver(sliding()).improve(slide_mesh);
    BOOST_TEST_MESSAGE(name << ": worst aspect ratio of all elements, fixed " << worst_of_all(fixed, "aspect_ratio")
                            << ", slide " << worst_of_all(slide, "aspect_ratio"));
    check_on_the_input_boundary(input, slide_mesh, slide);
    BOOST_TEST(worst_of_all(slide, "aspect_ratio") >= worst_of_all(fixed, "aspect_ratio"));
    BOOST_TEST(slide.boundary->moved > 0);
}

}  // namespace

BOOST_AUTO_TEST_SUITE(sliding_boundary)

// The cube's faces are flat and its edges straight: a face vertex keeps the coordinate of its
// face's plane, an edge vertex the two of its edge, a corner all three, to 1e-9 of the diagonal;
// the volume stays. Slow (tests/CMakeLists.txt): the sanitizers see the local smoother slide in
// boundary_vertices_end_on_the_input_boundary, and untangle in local_solver_test.
BOOST_AUTO_TEST_CASE(cube_faces_stay_flat_edges_straight_and_corners_in_place, *boost::unit_test::label("slow")) {
    const auto input = tangled_cube();
    auto fixed_mesh = input, slide_mesh = input;
    pv::LocalSolverOptions fixed_options = sliding();
    fixed_options.boundary = pv::LocalSolverOptions::Boundary::Fixed;
    const auto fixed = pv::LocalSolver(fixed_options).improve(fixed_mesh);
    const auto slide = pv::LocalSolver(sliding()).improve(slide_mesh);
    check_cube_slid(input, slide_mesh, fixed, slide);
}

BOOST_DATA_TEST_CASE(boundary_vertices_end_on_the_input_boundary,
                     bdata::make({"mesquite/tets/tire.vtk", "stellar/house2.node", "mesquite/tris/tri_20258.vtk"}),
                     name) {
    check_slid_on_the_input_boundary(name);
}

// Slow (tests/CMakeLists.txt): the sanitizers see the same on the smaller meshes above.
BOOST_AUTO_TEST_CASE(boundary_vertices_of_cube_clip_5_end_on_its_boundary, *boost::unit_test::label("slow")) {
    check_slid_on_the_input_boundary("mesquite/tets/cube-clip-5.vtk");
}

// Slow (tests/CMakeLists.txt): the sanitizers see the tire slide in
// boundary_vertices_end_on_the_input_boundary.
BOOST_AUTO_TEST_CASE(threads_do_not_change_where_the_boundary_slides, *boost::unit_test::label("slow")) {
    auto one = shared_mesh("mesquite/tets/tire.vtk"), two = one;
    pv::LocalSolver(sliding(1)).improve(one);
    pv::LocalSolver(sliding(2)).improve(two);
    BOOST_TEST(std::equal(one.coordinates().begin(), one.coordinates().end(), two.coordinates().begin()));
}

// Past the cube's 90-degree creases (feature angle 95) the cube is one smooth surface: its edge
// vertices may cut across them, and the volume shrinks; at the default angle it does not. Slow
// (tests/CMakeLists.txt): the sanitizers see the creases found, and kept, in
// boundary_vertices_end_on_the_input_boundary.
BOOST_AUTO_TEST_CASE(the_feature_angle_decides_which_creases_stay, *boost::unit_test::label("slow")) {
    auto kept = tangled_cube(), cut = kept;
    auto blunt = sliding();
    blunt.surface.feature_angle = 95.0;
    const auto at_default = pv::LocalSolver(sliding()).improve(kept);
    const auto at_95 = pv::LocalSolver(blunt).improve(cut);
    BOOST_TEST(at_default.boundary->volume_after == at_default.boundary->volume_before,
               boost::test_tools::tolerance(1e-12));
    BOOST_TEST(at_95.boundary->volume_after < at_95.boundary->volume_before * (1.0 - 1e-6));
    BOOST_TEST(at_95.boundary->largest_distance <= 1e-9);  // still on the input's boundary faces
    BOOST_TEST(at_95.boundary->sliding == 218);            // every boundary vertex, corners too
}

// The sweeps with the boundary fixed take half the budget, the sliding ones the rest; a budget
// spent before the boundary could slide says so.
BOOST_AUTO_TEST_CASE(the_fixed_sweeps_take_half_the_budget_and_a_spent_one_says_so) {
    auto mesh = shared_mesh("mesquite/tets/tire.vtk");
    auto options = sliding();
    options.termination.max_iterations = 3;
    const auto shared = pv::LocalSolver(options).improve(mesh);
    BOOST_TEST(shared.boundary->moved > 0);
    BOOST_TEST(shared.message.find("boundary fixed: stopped after 2 sweeps") == 0u, shared.message);

    mesh = shared_mesh("mesquite/tets/tire.vtk");
    options.termination.max_iterations = 1;
    const auto spent = pv::LocalSolver(options).improve(mesh);
    BOOST_TEST(spent.boundary->moved == 0);
    BOOST_TEST(spent.message.find("the boundary did not slide") != std::string::npos, spent.message);
}

BOOST_AUTO_TEST_CASE(bad_feature_angles_are_refused) {
    auto options = sliding();
    for (double angle : {0.0, -5.0, 180.0, std::nan("")}) {
        options.surface.feature_angle = angle;
        BOOST_CHECK_THROW(pv::LocalSolver{options}, pv::OptionError);
    }
}

// Two tets sharing only an edge: four boundary faces meet there, and no surface is defined.
BOOST_AUTO_TEST_CASE(a_non_manifold_boundary_is_refused) {
    pv::Mesh mesh(pv::ElementKind::Tetrahedron,
                  {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, -1, 0.5, 0.5, -2},
                  {0, 1, 2, 3, 1, 0, 4, 5});
    auto options = sliding();
    try {
        pv::LocalSolver(options).improve(mesh);
        BOOST_FAIL("a non-manifold boundary was accepted");
    } catch (const pv::MeshError& e) {
        BOOST_TEST(std::string(e.what()).find("not a manifold surface") != std::string::npos, e.what());
    }
}

BOOST_AUTO_TEST_SUITE_END()
