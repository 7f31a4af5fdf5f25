#include <boost/test/unit_test.hpp>

#include "paloverde/core/error.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "paloverde/solvers/instruction_queue.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;

BOOST_AUTO_TEST_SUITE(instruction_queue)

BOOST_AUTO_TEST_CASE(assess_untangle_improve_assess) {
    auto mesh = pv::read_mesh(pv::test::shared_data("mesquite/tets/tet_4_tangled.vtk")).mesh;
    pv::GlobalSolverOptions untangle;
    untangle.improve_shape = false;
    pv::InstructionQueue queue;
    queue.assess("before")
        .improve(std::make_unique<pv::GlobalSolver>(untangle))
        .improve(std::make_unique<pv::GlobalSolver>())
        .assess("after", pv::QualityAssessor({"aspect_ratio", "min_dihedral_deg"}));
    BOOST_TEST(queue.size() == 4u);
    const auto result = queue.run(mesh);
    BOOST_TEST(result.success);
    BOOST_REQUIRE(result.steps.size() == 4u);
    const auto& before = std::get<pv::QualityReport>(result.steps[0].outcome);
    const auto& untangled = std::get<pv::Summary>(result.steps[1].outcome);
    const auto& improved = std::get<pv::Summary>(result.steps[2].outcome);
    const auto& after = std::get<pv::QualityReport>(result.steps[3].outcome);
    BOOST_TEST(before.inverted == 9);
    BOOST_TEST(untangled.after.inverted == 0);
    BOOST_TEST(improved.untangle_iterations == 0);  // nothing left to untangle
    BOOST_TEST(improved.worst_after >= untangled.worst_after);
    BOOST_TEST(after.inverted == 0);
    BOOST_TEST(after.metrics.size() == 2u);
    BOOST_TEST(result.report().find("== after") != std::string::npos);
}

BOOST_AUTO_TEST_CASE(a_failing_improver_stops_the_queue_and_says_why) {
    auto mesh = pv::read_mesh(pv::test::shared_data("mesquite/tets/tire.vtk")).mesh;
    mesh.set_fixed(std::vector<std::uint8_t>(mesh.num_vertices(), 1));
    pv::InstructionQueue queue;
    queue.improve(std::make_unique<pv::GlobalSolver>()).assess("never reached");
    const auto result = queue.run(mesh);
    BOOST_TEST(!result.success);
    BOOST_TEST(result.steps.size() == 1u);
    BOOST_TEST(result.message.find("fixed") != std::string::npos);
    BOOST_CHECK_THROW(queue.improve(nullptr), pv::OptionError);
}

BOOST_AUTO_TEST_SUITE_END()
