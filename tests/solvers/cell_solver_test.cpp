// Both solvers on meshes of cells (quadrilaterals, hexahedra, wedges, pyramids, a mix): tangled
// grids are untangled with the boundary fixed, valid ones improved, never worse, and the
// reports count cells.
#include <boost/test/data/test_case.hpp>
#include <boost/test/unit_test.hpp>
#include <vector>

#include "paloverde/mesh/orientation.hpp"
#include "paloverde/mesh/perturb.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "paloverde/solvers/local_solver.hpp"
#include "support/cell_meshes.hpp"
#include "support/solver_checks.hpp"

namespace pv = paloverde;
namespace bdata = boost::unit_test::data;
using pv::test::Fill;

namespace {

// 0: quadrilaterals, then each Fill.
const char* const kFillNames[] = {"quadrilaterals", "hexahedra", "wedges", "pyramids", "mixed"};

pv::Mesh grid(int fill) {
    return fill == 0 ? pv::test::quad_grid(12) : pv::test::cube_grid(5, static_cast<Fill>(fill - 1));
}

pv::Mesh tangled_grid(int fill, int seed) {
    auto mesh = pv::test::tangled(grid(fill), seed);
    BOOST_TEST_REQUIRE(pv::count_orientations(mesh).inverted > 0);
    return mesh;
}

pv::Summary improve(int method, pv::Mesh& mesh) {
    if (method == 0) return pv::GlobalSolver().improve(mesh);
    return pv::LocalSolver().improve(mesh);
}

// A tangled grid of `fill` untangled by both solvers, twice: nothing inverted, the boundary fixed.
void check_tangled_grid_untangled(int fill) {
    for (int method : {0, 1})
        for (int seed : {1, 2}) {
            BOOST_TEST_CONTEXT(kFillNames[fill] << ", " << (method == 0 ? "global" : "local") << ", seed " << seed) {
                auto mesh = tangled_grid(fill, seed);
                const std::vector<double> before(mesh.coordinates().begin(), mesh.coordinates().end());
                const auto summary = improve(method, mesh);
                BOOST_TEST_MESSAGE(summary.brief_report());
                BOOST_TEST(summary.before.elements == mesh.num_cells());
                BOOST_TEST(summary.before.inverted > 0);
                BOOST_TEST(summary.after.inverted == 0);
                BOOST_TEST(pv::count_orientations(mesh).inverted == 0);
                BOOST_TEST(summary.success());
                pv::test::check_never_worse(summary);
                pv::test::check_fixed_unchanged(mesh, before);
            }
        }
}

// The global solver's focus rates its cells' corners through their maps as the whole mesh does:
// it reaches the local smoother's worst (a focus that lost the maps stalled at 0.53 against
// 0.93 on the pyramids).
void check_valid_grid_improved(int fill) {
    double worst[2] = {0.0, 0.0};
    for (int method : {0, 1}) {
        BOOST_TEST_CONTEXT(kFillNames[fill] << ", " << (method == 0 ? "global" : "local")) {
            auto mesh = grid(fill);
            pv::PerturbOptions perturb;
            perturb.amount = 0.2;
            pv::perturb(mesh, perturb);
            BOOST_TEST_REQUIRE(pv::count_orientations(mesh).inverted == 0);
            const auto summary = improve(method, mesh);
            BOOST_TEST_MESSAGE(summary.brief_report());
            BOOST_TEST(summary.after.inverted == 0);
            BOOST_TEST(summary.worst_after > summary.worst_before);
            pv::test::check_never_worse(summary);
            worst[method] = summary.worst_after;
        }
    }
    BOOST_TEST(worst[0] >= worst[1] - 1e-3);
}

}  // namespace

BOOST_AUTO_TEST_SUITE(cell_solvers)

BOOST_DATA_TEST_CASE(tangled_grids_of_cells_are_untangled, bdata::make({0, 1}), fill) {
    check_tangled_grid_untangled(fill);
}

// Slow (tests/CMakeLists.txt): the sanitizers see cells untangled in the grids above, and wedges
// and pyramids in the mixed grid of valid_grids_of_cells_improve_and_invert_nothing.
BOOST_TEST_DECORATOR(*boost::unit_test::label("slow"))
BOOST_DATA_TEST_CASE(tangled_grids_of_wedges_pyramids_and_mixed_cells_are_untangled, bdata::make({2, 3, 4}), fill) {
    check_tangled_grid_untangled(fill);
}

BOOST_DATA_TEST_CASE(valid_grids_of_cells_improve_and_invert_nothing, bdata::make({0, 1, 4}), fill) {
    check_valid_grid_improved(fill);
}

// Slow (tests/CMakeLists.txt): the sanitizers see wedges and pyramids in the mixed grid above.
BOOST_TEST_DECORATOR(*boost::unit_test::label("slow"))
BOOST_DATA_TEST_CASE(valid_grids_of_wedges_and_pyramids_improve_and_invert_nothing, bdata::make({2, 3}), fill) {
    check_valid_grid_improved(fill);
}

// Slow (tests/CMakeLists.txt): the sanitizers see the global solver on two threads in
// global_solver_test's result_does_not_depend_on_the_thread_count, and on cells in the cases above.
BOOST_AUTO_TEST_CASE(the_global_solver_gives_the_same_cells_on_one_and_two_threads, *boost::unit_test::label("slow")) {
    std::vector<double> result[2];
    for (int threads : {1, 2}) {
        auto mesh = tangled_grid(4, 3);
        pv::GlobalSolverOptions options;
        options.threads = threads;
        pv::GlobalSolver(options).improve(mesh);
        result[threads - 1].assign(mesh.coordinates().begin(), mesh.coordinates().end());
    }
    BOOST_TEST(result[0] == result[1]);
}

BOOST_AUTO_TEST_SUITE_END()
