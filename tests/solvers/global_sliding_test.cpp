// Sliding boundary vertices (boundary: slide, issue 17) in the global solver: every boundary
// vertex ends on the input's boundary (flat faces in their plane, feature edges on the edge,
// corners in place) whatever the workspace's renumbering, the worst element over all elements
// ends no lower than with the boundary fixed, nothing inverts, and what it does not take is
// refused.
#include <boost/test/data/test_case.hpp>
#include <boost/test/unit_test.hpp>
#include <algorithm>
#include <cmath>
#include <vector>

#include "paloverde/core/error.hpp"
#include "paloverde/metrics/quality_metric.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "support/sliding_checks.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;
namespace bdata = boost::unit_test::data;
using Boundary = pv::GlobalSolverOptions::Boundary;
using namespace paloverde::test;  // the sliding checks, shared with the local smoother's tests

namespace {

pv::GlobalSolverOptions global(Boundary boundary) {
    pv::GlobalSolverOptions options;
    options.boundary = boundary;
    options.threads = 1;
    return options;
}

// The smallest dihedral angle of all the mesh's tets, in degrees.
double smallest_dihedral(const pv::Mesh& mesh) {
    std::vector<double> angles(static_cast<std::size_t>(mesh.num_elements()));
    pv::make_metric("min_dihedral_deg")->evaluate(mesh, mesh.coordinates(), 0, mesh.num_elements(), angles.data());
    return *std::min_element(angles.begin(), angles.end());
}

// Curved and faceted meshes, renumbered (the default) or not: every boundary vertex on the
// input's boundary, the worst of all elements no lower than with the boundary fixed on the
// budget the sliding run gives its own boundary-fixed run (half: on the whole budget, the Newton
// finish takes tri_20258's worst triangle, which no boundary vertex touches, higher).
void check_slid_on_the_input_boundary(const char* name, bool renumber) {
    const auto input = shared_mesh(name);
    auto fixed_mesh = input, slide_mesh = input;
    auto fixed_options = global(Boundary::Fixed), slide_options = global(Boundary::Slide);
    fixed_options.renumber = slide_options.renumber = renumber;
    fixed_options.termination.max_iterations = (fixed_options.termination.max_iterations + 1) / 2;
    const auto fixed = pv::GlobalSolver(fixed_options).improve(fixed_mesh);
    const auto slide = pv::GlobalSolver(slide_options).improve(slide_mesh);
    BOOST_TEST_MESSAGE(name << " (renumber " << renumber << "): worst aspect ratio of all elements, fixed "
                            << worst_of_all(fixed, "aspect_ratio") << ", slide " << worst_of_all(slide, "aspect_ratio"));
    check_on_the_input_boundary(input, slide_mesh, slide);
    BOOST_TEST(worst_of_all(slide, "aspect_ratio") >= worst_of_all(fixed, "aspect_ratio"));
    // On tri_20258 the worst triangles lie inside, where no boundary vertex can help them: the
    // sliding phase may end on its start, the best iterate.
    if (input.kind() == pv::ElementKind::Tetrahedron) BOOST_TEST(slide.boundary->moved > 0);
}

// What sliding is for: the smallest dihedral angle over all tets (boundary ones, which a fixed
// boundary cannot improve, included) rises above the boundary-fixed run's.
void check_sliding_raises_the_smallest_dihedral_angle(const char* name) {
    auto fixed_mesh = shared_mesh(name), slide_mesh = fixed_mesh;
    const auto fixed = pv::GlobalSolver(global(Boundary::Fixed)).improve(fixed_mesh);
    const auto slide = pv::GlobalSolver(global(Boundary::Slide)).improve(slide_mesh);
    BOOST_TEST(fixed.valid());
    BOOST_TEST(slide.valid());
    BOOST_TEST_MESSAGE(name << ": smallest dihedral of all tets, fixed " << smallest_dihedral(fixed_mesh) << ", slide "
                            << smallest_dihedral(slide_mesh));
    BOOST_TEST(smallest_dihedral(slide_mesh) > smallest_dihedral(fixed_mesh));
}

// Steepest ascent (variant 0) or a focused shape phase (1) keeps the sliding vertices on the
// boundary too.
void check_variant_slides_on_the_boundary(int variant) {
    const auto input = shared_mesh("mesquite/tets/tire.vtk");
    auto mesh = input;
    auto options = global(Boundary::Slide);
    if (variant == 0) options.direction = pv::GlobalSolverOptions::Direction::SteepestAscent;
    else options.focus_band = 0.3;
    const auto slide = pv::GlobalSolver(options).improve(mesh);
    check_on_the_input_boundary(input, mesh, slide);
    BOOST_TEST(slide.boundary->moved > 0);
}

}  // namespace

BOOST_AUTO_TEST_SUITE(global_sliding)

// The cube's faces are flat and its edges straight: a face vertex keeps the coordinate of its
// face's plane, an edge vertex the two of its edge, a corner all three; the volume stays. Slow
// (tests/CMakeLists.txt): the sanitizers see the global solver slide in the cases below, and
// untangle in global_solver_test.
BOOST_AUTO_TEST_CASE(cube_faces_stay_flat_edges_straight_and_corners_in_place, *boost::unit_test::label("slow")) {
    const auto input = tangled_cube();
    auto fixed_mesh = input, slide_mesh = input;
    const auto fixed = pv::GlobalSolver(global(Boundary::Fixed)).improve(fixed_mesh);
    const auto slide = pv::GlobalSolver(global(Boundary::Slide)).improve(slide_mesh);
    check_cube_slid(input, slide_mesh, fixed, slide);
}

BOOST_DATA_TEST_CASE(boundary_vertices_end_on_the_input_boundary,
                     bdata::make({"stellar/house2.node"}) * bdata::make({true, false}), name, renumber) {
    check_slid_on_the_input_boundary(name, renumber);
}

// Slow (tests/CMakeLists.txt): the sanitizers see house2 slide above, renumbered and not; tire in
// steepest_ascent_slides_on_the_boundary; triangles in morph_test and sliding_boundary_test.
BOOST_TEST_DECORATOR(*boost::unit_test::label("slow"))
BOOST_DATA_TEST_CASE(boundary_vertices_of_larger_meshes_end_on_the_input_boundary,
                     bdata::make({"mesquite/tets/tire.vtk", "mesquite/tets/cube-clip-5.vtk",
                                  "mesquite/tris/tri_20258.vtk"}) *
                         bdata::make({true, false}),
                     name, renumber) {
    check_slid_on_the_input_boundary(name, renumber);
}

BOOST_DATA_TEST_CASE(sliding_raises_the_smallest_dihedral_angle_of_all_tets, bdata::make({"stellar/house2.node"}),
                     name) {
    check_sliding_raises_the_smallest_dihedral_angle(name);
}

// Slow (tests/CMakeLists.txt): the sanitizers see house2, above.
BOOST_AUTO_TEST_CASE(sliding_raises_the_smallest_dihedral_angle_of_cube_clip_5s_tets,
                     *boost::unit_test::label("slow")) {
    check_sliding_raises_the_smallest_dihedral_angle("mesquite/tets/cube-clip-5.vtk");
}

BOOST_AUTO_TEST_CASE(steepest_ascent_slides_on_the_boundary) { check_variant_slides_on_the_boundary(0); }

// Slow (tests/CMakeLists.txt): the sanitizers see a focused shape phase in checkpoint_test's
// global_focused_run_resumed_from_a_checkpoint_ends_as_the_uninterrupted_run, and sliding above.
BOOST_AUTO_TEST_CASE(a_focused_shape_phase_slides_on_the_boundary, *boost::unit_test::label("slow")) {
    check_variant_slides_on_the_boundary(1);
}

// Slow (tests/CMakeLists.txt): the sanitizers see the global solver on two threads in
// global_solver_test's result_does_not_depend_on_the_thread_count, and sliding above.
BOOST_AUTO_TEST_CASE(threads_do_not_change_where_the_boundary_slides, *boost::unit_test::label("slow")) {
    auto one = shared_mesh("mesquite/tets/tire.vtk"), two = one;
    auto options = global(Boundary::Slide);
    pv::GlobalSolver(options).improve(one);
    options.threads = 2;
    pv::GlobalSolver(options).improve(two);
    BOOST_TEST(std::equal(one.coordinates().begin(), one.coordinates().end(), two.coordinates().begin()));
}

// The run with the boundary fixed takes half the budget, the sliding run the rest; a budget spent
// before the boundary could slide says so.
BOOST_AUTO_TEST_CASE(the_fixed_run_takes_half_the_budget_and_a_spent_one_says_so) {
    auto mesh = shared_mesh("mesquite/tets/tire.vtk");
    auto options = global(Boundary::Slide);
    options.termination.max_iterations = 3;
    const auto shared = pv::GlobalSolver(options).improve(mesh);
    BOOST_REQUIRE(shared.boundary.has_value());
    BOOST_TEST(shared.boundary->moved > 0);
    BOOST_TEST(shared.message.find("boundary fixed: stopped after 2 iterations; then sliding") == 0u, shared.message);

    mesh = shared_mesh("mesquite/tets/tire.vtk");
    options.termination.max_iterations = 1;
    const auto spent = pv::GlobalSolver(options).improve(mesh);
    BOOST_REQUIRE(spent.boundary.has_value());
    BOOST_TEST(spent.boundary->moved == 0);
    BOOST_TEST(spent.message.find("the boundary did not slide") != std::string::npos, spent.message);
}

BOOST_AUTO_TEST_CASE(what_sliding_does_not_take_is_refused) {
    auto options = global(Boundary::Slide);
    for (double angle : {0.0, -5.0, 180.0, std::nan("")}) {
        options.surface.feature_angle = angle;
        BOOST_CHECK_THROW(pv::GlobalSolver{options}, pv::OptionError);
    }
    auto newton = global(Boundary::Slide);
    newton.direction = pv::GlobalSolverOptions::Direction::Newton;
    try {
        pv::GlobalSolver{newton};
        BOOST_FAIL("newton directions with a sliding boundary were accepted");
    } catch (const pv::OptionError& e) {
        BOOST_TEST(std::string(e.what()).find("direction newton does not go with boundary: slide") != std::string::npos,
                   e.what());
    }
    newton.boundary = Boundary::Fixed;
    BOOST_CHECK_NO_THROW(pv::GlobalSolver{newton});
}

BOOST_AUTO_TEST_SUITE_END()
