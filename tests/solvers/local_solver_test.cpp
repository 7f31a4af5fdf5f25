// The local (Freitag-Plassmann) smoother, its vertex coloring, and Laplace / smart Laplace: the
// same never-worse, never-inverts checks as the global solver, and thread-count independence.
#include <boost/test/data/test_case.hpp>
#include <boost/test/unit_test.hpp>

#include "paloverde/core/error.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/orientation.hpp"
#include "paloverde/mesh/perturb.hpp"
#include "paloverde/mesh/renumber.hpp"
#include "paloverde/solvers/laplace_solver.hpp"
#include "paloverde/solvers/local_solver.hpp"
#include "paloverde/solvers/vertex_coloring.hpp"
#include "support/solver_checks.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;
namespace bdata = boost::unit_test::data;
using paloverde::test::check_fixed_unchanged;
using paloverde::test::check_never_worse;
using paloverde::test::shared_mesh;

namespace {


pv::LocalSolverOptions quick_local(int sweeps) {
    pv::LocalSolverOptions options;
    options.termination.max_iterations = sweeps;
    return options;
}

const char* const kValidMeshes[] = {"mesquite/tets/tire.vtk", "stellar/house2.node", "mesquite/tris/tri_20258.vtk"};

}  // namespace

BOOST_AUTO_TEST_SUITE(vertex_coloring)

BOOST_DATA_TEST_CASE(colorings_are_proper, bdata::make({"mesquite/tets/tire.vtk", "mesquite/tris/tri_20258.vtk"}) *
                                               bdata::make({0, 1}),
                     name, order) {
    auto mesh = shared_mesh(name);
    const auto kind = order == 0 ? pv::ColoringOrder::Greedy : pv::ColoringOrder::SmallestLast;
    const auto coloring = pv::color_vertices(mesh, kind);
    BOOST_TEST_MESSAGE(name << (order == 0 ? " greedy: " : " smallest-last: ") << coloring.count << " colors");
    BOOST_TEST(pv::is_proper_coloring(mesh, coloring));
    BOOST_TEST(coloring.count > 1);
    std::size_t colored = 0;
    for (const auto& members : coloring.classes()) colored += members.size();
    BOOST_TEST(colored == static_cast<std::size_t>(mesh.num_free_vertices()));
}

BOOST_AUTO_TEST_CASE(an_improper_coloring_is_detected) {
    auto mesh = shared_mesh("mesquite/tets/tire.vtk");
    auto coloring = pv::color_vertices(mesh);
    pv::VertexId a = -1, b = -1;
    for (pv::ElementId e = 0; e < mesh.num_elements() && b < 0; ++e) {
        a = b = -1;
        for (pv::VertexId v : mesh.element(e))
            if (!mesh.fixed()[v]) (a < 0 ? a : b) = v;
    }
    BOOST_TEST_REQUIRE(b >= 0);
    coloring.color[b] = coloring.color[a];
    BOOST_TEST(!pv::is_proper_coloring(mesh, coloring));
    coloring = pv::color_vertices(mesh);
    for (pv::VertexId v = 0; v < mesh.num_vertices(); ++v)
        if (mesh.fixed()[v]) {
            coloring.color[v] = 0;
            break;
        }
    BOOST_TEST(!pv::is_proper_coloring(mesh, coloring));
}

BOOST_AUTO_TEST_SUITE_END()

BOOST_AUTO_TEST_SUITE(local_solver)

BOOST_DATA_TEST_CASE(improves_valid_shared_meshes_without_making_anything_worse, bdata::make(kValidMeshes), name) {
    auto mesh = shared_mesh(name);
    const std::vector<double> before(mesh.coordinates().begin(), mesh.coordinates().end());
    const auto summary = pv::LocalSolver(quick_local(10)).improve(mesh);
    BOOST_TEST_MESSAGE(name << ": " << summary.brief_report());
    BOOST_TEST(summary.before.inverted == 0);
    BOOST_TEST(summary.after.inverted == 0);
    BOOST_TEST(pv::count_orientations(mesh).inverted == 0);
    BOOST_TEST(summary.worst_after > summary.worst_before);
    BOOST_TEST(summary.success());
    BOOST_TEST(summary.message.find("colors") != std::string::npos);
    check_never_worse(summary);
    check_fixed_unchanged(mesh, before);
    if (mesh.kind() == pv::ElementKind::Triangle) {
        BOOST_TEST(mesh.is_planar());
        const auto coordinates = mesh.coordinates();
        double off_plane = 0.0;
        for (pv::VertexId v = 0; v < mesh.num_vertices(); ++v)
            off_plane = std::max(off_plane, std::abs(coordinates[3 * v + 2] - before[3 * v + 2]));
        if (std::abs(mesh.plane_normal()[2]) == 1.0) BOOST_TEST(off_plane < 1e-12);
    }
}

BOOST_AUTO_TEST_CASE(untangles_the_mesquite_tangled_mesh) {
    auto mesh = shared_mesh("mesquite/tets/tet_4_tangled.vtk");
    const auto summary = pv::LocalSolver().improve(mesh);
    BOOST_TEST_MESSAGE(summary.brief_report());
    BOOST_TEST(summary.before.inverted == 9);
    BOOST_TEST(summary.after.inverted == 0);
    BOOST_TEST(pv::count_orientations(mesh).inverted == 0);
    BOOST_TEST(summary.untangle_iterations > 0);
    BOOST_TEST(summary.success());
    check_never_worse(summary);
}

// Interior vertices moved by up to one local edge length. Local moves, one vertex at a time,
// may not be able to untangle a cluster; what must hold is that nothing gets worse.
BOOST_DATA_TEST_CASE(perturbed_shared_meshes,
                     bdata::make({"mesquite/tets/tire.vtk", "stellar/house2.node", "mesquite/tris/tri_20258.vtk"}) *
                         bdata::make({1, 2, 3}),
                     name, seed) {
    auto mesh = pv::test::perturbed_shared_mesh(name, 0.1, seed);
    const auto tangled = pv::count_orientations(mesh).inverted;
    const std::vector<double> before(mesh.coordinates().begin(), mesh.coordinates().end());
    const auto summary = pv::LocalSolver(quick_local(5)).improve(mesh);
    BOOST_TEST_MESSAGE(name << " seed " << seed << ": " << tangled << " inverted; " << summary.brief_report());
    check_never_worse(summary);
    check_fixed_unchanged(mesh, before);
    BOOST_TEST(pv::count_orientations(mesh).inverted == summary.after.inverted);
    if (summary.after.inverted == 0) {
        BOOST_TEST(summary.success());
    } else {
        BOOST_TEST((summary.reason == pv::TerminationReason::CannotUntangle));
        BOOST_TEST(!summary.success());
    }
}

// Every interior vertex moved by up to 1.5 local edge lengths: the volume sweeps (one linear
// program per vertex) leave such tangles inverted; the energy sweeps free them, and a cluster no
// single position of one vertex can fix is freed by its neighbours' moves.
BOOST_DATA_TEST_CASE(energy_sweeps_untangle_heavy_tangles,
                     bdata::make({"mesquite/tets/tire.vtk", "mesquite/tets/cube-clip-5.vtk", "mesquite/tris/tri_20258.vtk"}),
                     name) {
    const auto input = pv::test::perturbed_shared_mesh(name, 1.0, 7, 1.5);
    const auto tangled = pv::count_orientations(input).inverted;
    const std::vector<double> before(input.coordinates().begin(), input.coordinates().end());
    auto options = quick_local(3);
    options.improve_shape = false;
    auto mesh = input;
    const auto summary = pv::LocalSolver(options).improve(mesh);
    BOOST_TEST_MESSAGE(name << ": " << tangled << " inverted; " << summary.brief_report());
    BOOST_TEST(summary.before.inverted == tangled);
    BOOST_TEST(summary.after.inverted == 0);
    BOOST_TEST(pv::count_orientations(mesh).inverted == 0);
    BOOST_TEST(summary.success());
    BOOST_TEST(std::any_of(summary.history.begin(), summary.history.end(), [](const auto& r) { return r.phase == "untangle"; }));
    check_never_worse(summary);
    check_fixed_unchanged(mesh, before);
    // Within the untangling sweeps the count of inverted elements never rises.
    long last = tangled;
    for (const auto& r : summary.history) {
        BOOST_TEST(r.inverted <= last);
        last = r.inverted;
    }
    // The volume sweeps, kept as an option, do not get there (checked on the smallest mesh).
    if (name == std::string("mesquite/tets/tire.vtk")) {
        options.untangling = pv::LocalSolverOptions::Untangling::Volume;
        auto by_volume = input;
        const auto volume_summary = pv::LocalSolver(options).improve(by_volume);
        BOOST_TEST_MESSAGE("  by volume: " << volume_summary.brief_report());
        BOOST_TEST(volume_summary.after.inverted > 0);
        check_never_worse(volume_summary);
    }
}

// The energy sweeps are scale-free: the same tangle in units 1e4 times smaller or larger is
// untangled in the same number of sweeps.
BOOST_AUTO_TEST_CASE(energy_untangling_does_not_depend_on_the_units) {
    const auto input = pv::test::perturbed_shared_mesh("mesquite/tets/tire.vtk", 1.0, 5, 1.5);
    auto options = quick_local(1);
    options.improve_shape = false;
    auto mesh = input;
    const auto summary = pv::LocalSolver(options).improve(mesh);
    BOOST_TEST_REQUIRE(summary.after.inverted == 0);
    for (double factor : {1e-4, 1e4}) {
        auto scaled = input;
        for (double& x : scaled.coordinates()) x *= factor;
        const auto scaled_summary = pv::LocalSolver(options).improve(scaled);
        BOOST_TEST_MESSAGE("x" << factor << ": " << scaled_summary.brief_report());
        BOOST_TEST(scaled_summary.after.inverted == 0);
        BOOST_TEST(scaled_summary.untangle_iterations == summary.untangle_iterations);
    }
}

// The shape sweeps follow the energy's untangling, and the run as a whole is never worse.
BOOST_AUTO_TEST_CASE(energy_untangling_then_shape_sweeps_raise_the_worst_element) {
    auto mesh = pv::test::perturbed_shared_mesh("mesquite/tets/tire.vtk", 1.0, 11, 1.5);
    const auto summary = pv::LocalSolver(quick_local(5)).improve(mesh);
    BOOST_TEST_MESSAGE(summary.brief_report());
    BOOST_TEST(summary.after.inverted == 0);
    BOOST_TEST(summary.untangle_iterations > 0);
    BOOST_TEST(summary.iterations > summary.untangle_iterations);
    BOOST_TEST(summary.worst_after > 0.0);
    check_never_worse(summary);
}

BOOST_AUTO_TEST_CASE(result_does_not_depend_on_the_thread_count) {
    auto one = shared_mesh("mesquite/tets/cube-clip-5.vtk");
    pv::PerturbOptions perturb;
    perturb.amount = 0.7;
    perturb.fraction = 0.2;
    pv::perturb(one, perturb);
    auto two = one;
    auto options = quick_local(4);
    options.threads = 1;
    const auto s1 = pv::LocalSolver(options).improve(one);
    options.threads = 2;
    const auto s2 = pv::LocalSolver(options).improve(two);
    BOOST_TEST_MESSAGE(s1.brief_report());
    BOOST_TEST(s1.iterations == s2.iterations);
    BOOST_TEST(s1.untangle_iterations > 0);
    BOOST_TEST(std::equal(one.coordinates().begin(), one.coordinates().end(), two.coordinates().begin()));
}

// Vertices of one color share no element, so the order they are visited in cannot matter.
// Renumbering the vertices by (color, reversed id) keeps the greedy coloring's classes (each
// vertex still meets its lower-colored neighbours first) but reverses the order within every
// class; the result must be the same mesh, bit for bit, up to the renumbering.
BOOST_AUTO_TEST_CASE(result_does_not_depend_on_the_order_within_a_color) {
    auto mesh = shared_mesh("mesquite/tets/tire.vtk");
    pv::PerturbOptions perturb;
    perturb.amount = 0.5;
    perturb.fraction = 0.2;
    pv::perturb(mesh, perturb);
    const auto coloring = pv::color_vertices(mesh, pv::ColoringOrder::Greedy);
    pv::Renumbering order;
    for (pv::VertexId v = 0; v < mesh.num_vertices(); ++v) order.old_vertex.push_back(v);
    std::stable_sort(order.old_vertex.begin(), order.old_vertex.end(), [&](pv::VertexId a, pv::VertexId b) {
        return coloring.color[a] != coloring.color[b] ? coloring.color[a] < coloring.color[b] : a > b;
    });
    for (pv::ElementId e = 0; e < mesh.num_elements(); ++e) order.old_element.push_back(e);
    auto reordered = pv::renumbered(mesh, order);
    const auto recolored = pv::color_vertices(reordered, pv::ColoringOrder::Greedy);
    for (pv::VertexId v = 0; v < reordered.num_vertices(); ++v)
        BOOST_TEST_REQUIRE(recolored.color[v] == coloring.color[order.old_vertex[v]]);

    auto options = quick_local(4);
    options.coloring = pv::ColoringOrder::Greedy;
    options.threads = 1;
    const std::vector<double> before(mesh.coordinates().begin(), mesh.coordinates().end());
    const auto s1 = pv::LocalSolver(options).improve(mesh);
    const auto s2 = pv::LocalSolver(options).improve(reordered);
    BOOST_TEST(s1.iterations == s2.iterations);
    BOOST_TEST(!std::equal(before.begin(), before.end(), mesh.coordinates().begin()));  // vertices did move
    for (pv::VertexId v = 0; v < reordered.num_vertices(); ++v)
        for (int c = 0; c < 3; ++c)
            BOOST_TEST_REQUIRE(reordered.coordinates()[3 * v + c] == mesh.coordinates()[3 * order.old_vertex[v] + c]);
}

BOOST_AUTO_TEST_CASE(all_vertices_fixed_means_nothing_to_move) {
    auto mesh = shared_mesh("mesquite/tets/tire.vtk");
    mesh.set_fixed(std::vector<std::uint8_t>(mesh.num_vertices(), 1));
    const auto summary = pv::LocalSolver().improve(mesh);
    BOOST_TEST((summary.reason == pv::TerminationReason::NothingToMove));
    BOOST_TEST(!summary.success());
    pv::Mesh empty;
    BOOST_TEST((pv::LocalSolver().improve(empty).reason == pv::TerminationReason::NothingToMove));
}

BOOST_AUTO_TEST_CASE(an_inverted_tet_with_every_vertex_fixed_cannot_be_untangled) {
    auto mesh = pv::test::frozen_inverted_tet();
    const auto summary = pv::LocalSolver().improve(mesh);
    BOOST_TEST((summary.reason == pv::TerminationReason::CannotUntangle));
    BOOST_TEST(summary.after.inverted == 1);
    BOOST_TEST(summary.worst_after >= summary.worst_before);
}

BOOST_AUTO_TEST_CASE(impossible_options_are_rejected_by_name) {
    auto expect = [](auto change, const std::string& word) {
        pv::test::check_option_rejected<pv::LocalSolver, pv::LocalSolverOptions>(change, word);
    };
    expect([](auto& o) { o.metric = "min_dihedral_deg"; }, "gradient");
    expect([](auto& o) { o.termination.max_iterations = -1; }, "max_iterations");
    expect([](auto& o) { o.threads = -2; }, "threads");
    expect([](auto& o) { o.ascent_steps = 0; }, "ascent_steps");
    expect([](auto& o) { o.active_tolerance = -1.0; }, "active_tolerance");
    expect([](auto& o) { o.improve_below = 0.0; }, "improve_below");
}

BOOST_AUTO_TEST_SUITE_END()

BOOST_AUTO_TEST_SUITE(laplace_solver)

BOOST_DATA_TEST_CASE(smart_laplace_never_makes_anything_worse, bdata::make(kValidMeshes), name) {
    auto mesh = shared_mesh(name);
    const std::vector<double> before(mesh.coordinates().begin(), mesh.coordinates().end());
    pv::LaplaceSolverOptions options;
    options.termination.max_iterations = 10;
    pv::LaplaceSolver solver(options);
    BOOST_TEST(solver.name() == "smart_laplace");
    const auto summary = solver.improve(mesh);
    BOOST_TEST_MESSAGE(name << ": " << summary.brief_report());
    BOOST_TEST(summary.after.inverted == 0);
    BOOST_TEST(summary.worst_after >= summary.worst_before);
    BOOST_TEST(summary.history.back().mean_quality >= 0.0);
    check_never_worse(summary);
    check_fixed_unchanged(mesh, before);
}

// A fan around one free vertex whose neighbours form a polygon with a deep notch from the top:
// their mean lies above the notch's tip, outside the polygon's kernel, so moving there inverts.
pv::Mesh notched_fan() {
    std::vector<double> xyz = {0.5, 0.1, 0,  // 0: free, below the notch's tip
                               0, 0, 0,  1, 0, 0,  1, 1, 0,  0.6, 1, 0,  0.5, 0.2, 0,  0.4, 1, 0,  0, 1, 0};
    std::vector<pv::VertexId> triangles = {0, 1, 2,  0, 2, 3,  0, 3, 4,  0, 4, 5,  0, 5, 6,  0, 6, 7,  0, 7, 1};
    // Orient every triangle counter-clockwise.
    for (std::size_t t = 0; t < triangles.size(); t += 3) {
        const auto* a = &xyz[3 * triangles[t]];
        const auto* b = &xyz[3 * triangles[t + 1]];
        const auto* c = &xyz[3 * triangles[t + 2]];
        if ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) < 0) std::swap(triangles[t + 1], triangles[t + 2]);
    }
    pv::Mesh mesh(pv::ElementKind::Triangle, xyz, triangles);
    mesh.set_fixed({0, 1, 1, 1, 1, 1, 1, 1});
    return mesh;
}

BOOST_AUTO_TEST_CASE(plain_laplace_says_when_it_inverts_and_smart_laplace_does_not_invert) {
    auto mesh = notched_fan();
    BOOST_TEST_REQUIRE(pv::count_orientations(mesh).inverted == 0);
    pv::LaplaceSolverOptions options;
    options.smart = false;
    pv::LaplaceSolver plain(options);
    BOOST_TEST(plain.name() == "laplace");
    auto plain_mesh = mesh;
    const auto summary = plain.improve(plain_mesh);
    BOOST_TEST_MESSAGE(summary.brief_report() << " " << summary.message);
    BOOST_TEST(summary.after.inverted > 0);
    BOOST_TEST(summary.message.find("inverted") != std::string::npos);

    options.smart = true;
    auto smart_mesh = mesh;
    const auto smart = pv::LaplaceSolver(options).improve(smart_mesh);
    BOOST_TEST(smart.after.inverted == 0);
    BOOST_TEST(smart.worst_after >= smart.worst_before);
    BOOST_TEST(smart.message.find("inverted") == std::string::npos);
}

BOOST_AUTO_TEST_CASE(laplace_results_do_not_depend_on_the_thread_count) {
    for (bool smart : {false, true}) {
        auto one = shared_mesh("mesquite/tets/tire.vtk");
        auto two = one;
        pv::LaplaceSolverOptions options;
        options.smart = smart;
        options.termination.max_iterations = 5;
        options.threads = 1;
        pv::LaplaceSolver(options).improve(one);
        options.threads = 2;
        pv::LaplaceSolver(options).improve(two);
        BOOST_TEST(std::equal(one.coordinates().begin(), one.coordinates().end(), two.coordinates().begin()));
    }
}

BOOST_AUTO_TEST_SUITE_END()
