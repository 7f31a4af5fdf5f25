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

// A run's report of the input reaches the queue's first solver, whose report of its input is then
// taken from it (a report marked here so that it shows), and the last solver makes the run's report
// of the result with its own: what assessing the result gives. Not through a step that sets
// targets: its solver assesses the input, and no solver reports the result (the queue hands the
// targets back after it).
BOOST_AUTO_TEST_CASE(a_runs_reports_are_shared_with_its_first_and_last_solver) {
    auto mesh = pv::read_mesh(pv::test::shared_data("mesquite/tets/tire.vtk")).mesh;
    const pv::QualityAssessor full;
    const auto coordinates = mesh.coordinates();
    const std::vector<double> given(coordinates.begin(), coordinates.end());
    auto marked = std::make_shared<pv::RunReports>(pv::RunReports{full, full.assess(mesh), std::nullopt});
    for (pv::MetricReport& m : marked->input.metrics)
        if (m.name == "aspect_ratio") m.all.rms = 12345.0;
    const auto rms_before = [](const pv::QueueResult& r, std::size_t step) {
        return std::get<pv::Summary>(r.steps[step].outcome).before.metric("aspect_ratio")->all.rms;
    };
    pv::GlobalSolverOptions brief;
    brief.termination.max_iterations = 2;
    pv::InstructionQueue queue;
    queue.assess("input").improve(std::make_unique<pv::GlobalSolver>(brief)).improve(std::make_unique<pv::GlobalSolver>(brief));
    const auto result = queue.run(mesh, marked);
    BOOST_REQUIRE(result.steps.size() == 3u);
    BOOST_TEST(rms_before(result, 1) == 12345.0);
    BOOST_TEST(rms_before(result, 2) != 12345.0);
    BOOST_REQUIRE(marked->output.has_value());
    BOOST_TEST(marked->output->to_json() == full.assess(mesh).to_json());

    std::copy(given.begin(), given.end(), mesh.coordinates().begin());
    marked->output.reset();
    pv::InstructionQueue targeted;
    targeted.targets({}).improve(std::make_unique<pv::GlobalSolver>(brief));
    const auto after_targets = targeted.run(mesh, marked);
    BOOST_TEST(rms_before(after_targets, 0) != 12345.0);
    BOOST_TEST(!marked->output.has_value());

    // Unmarked, what the solver takes is what it would have assessed.
    std::copy(given.begin(), given.end(), mesh.coordinates().begin());
    pv::InstructionQueue single;
    single.improve(std::make_unique<pv::GlobalSolver>(brief));
    const auto shared = single.run(mesh, std::make_shared<pv::RunReports>(pv::RunReports{full, full.assess(mesh), std::nullopt}));
    std::copy(given.begin(), given.end(), mesh.coordinates().begin());
    const auto alone = single.run(mesh);
    const auto& a = std::get<pv::Summary>(shared.steps[0].outcome);
    const auto& b = std::get<pv::Summary>(alone.steps[0].outcome);
    BOOST_TEST(a.before.to_json() == b.before.to_json());
    BOOST_TEST(a.after.to_json() == b.after.to_json());
}

BOOST_AUTO_TEST_SUITE_END()
