#include <boost/test/unit_test.hpp>
#include <string>
#include <vector>

#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/orientation.hpp"
#include "paloverde/wrappers.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;

namespace {
pv::Mesh tangled() { return pv::read_mesh(pv::test::shared_data("mesquite/tets/tet_4_tangled.vtk")).mesh; }
const pv::QualityReport& report(const pv::QueueResult& r, std::size_t i) { return std::get<pv::QualityReport>(r.steps[i].outcome); }
}  // namespace

BOOST_AUTO_TEST_SUITE(wrappers)

BOOST_AUTO_TEST_CASE(untangle_then_improve_leaves_a_valid_better_mesh) {
    auto mesh = tangled();
    const auto result = pv::wrappers::untangle_then_improve().run(mesh);
    BOOST_TEST(result.success);
    BOOST_REQUIRE(result.steps.size() == 4u);
    BOOST_TEST(report(result, 0).inverted == 9);
    BOOST_TEST(report(result, 3).inverted == 0);
    const auto& untangled = std::get<pv::Summary>(result.steps[1].outcome);
    const auto& improved = std::get<pv::Summary>(result.steps[2].outcome);
    BOOST_TEST(improved.worst_after >= untangled.worst_after);
}

BOOST_AUTO_TEST_CASE(untangle_only_stops_once_valid) {
    auto mesh = tangled();
    const auto result = pv::wrappers::untangle().run(mesh);
    BOOST_TEST(result.success);
    const auto& s = std::get<pv::Summary>(result.steps[1].outcome);
    BOOST_TEST(s.after.inverted == 0);
    BOOST_TEST(s.iterations == s.untangle_iterations);  // no shape iterations
}

BOOST_AUTO_TEST_CASE(shape_improvers_refuse_a_tangled_mesh_and_improve_a_valid_one) {
    auto mesh = tangled();
    const auto refused = pv::wrappers::shape_improvement().run(mesh);
    BOOST_TEST(!refused.success);  // tangled, and untangling is not its job
    auto valid = pv::read_mesh(pv::test::shared_data("mesquite/tets/tire.vtk")).mesh;
    for (auto queue : {pv::wrappers::shape_improvement(), pv::wrappers::local_shape_improvement(), pv::wrappers::laplace()}) {
        auto copy = valid;
        const auto result = queue.run(copy);
        BOOST_TEST(result.success);
        BOOST_TEST(report(result, 2).inverted == 0);
        BOOST_TEST(report(result, 2).metric("aspect_ratio")->movable.min >= report(result, 0).metric("aspect_ratio")->movable.min);
    }
}

BOOST_AUTO_TEST_CASE(queues_label_their_steps_and_tell_an_observer) {
    auto mesh = tangled();
    auto queue = pv::wrappers::untangle_then_improve();
    std::vector<std::string> seen;
    queue.observe([&](std::string_view label, const pv::IterationRecord&) {
        if (seen.empty() || seen.back() != label) seen.emplace_back(label);
    });
    pv::InstructionQueue longer;
    longer.append(queue).assess("end");
    const auto result = longer.run(mesh);
    BOOST_REQUIRE(result.steps.size() == 5u);
    BOOST_TEST(result.steps[1].label == "untangle");
    BOOST_TEST(result.steps[2].label == "global");
    BOOST_TEST(result.steps[4].label == "end");
    BOOST_TEST((seen == std::vector<std::string>{"untangle", "global"}));
}

BOOST_AUTO_TEST_SUITE_END()
