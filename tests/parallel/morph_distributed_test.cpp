// Morphing on the ranks' parts (solvers/boundary_motion.hpp): the reference coordinates travel
// with a part, the interior is carried along part by part, the steps are decided alike on every
// rank, and the result is the serial mesh bit for bit. Run by CTest on 1, 2 and 4 ranks.
#include <mpi.h>

#include <boost/test/data/test_case.hpp>
#include <boost/test/unit_test.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "paloverde/parallel/distributed_mesh.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "paloverde/solvers/local_solver.hpp"
#include "paloverde/solvers/stop.hpp"
#include "paloverde/assess/quality_assessor.hpp"
#include "distributed_checks.hpp"
#include "support/cell_meshes.hpp"
#include "support/ring_meshes.hpp"

namespace pv = paloverde;
namespace bdata = boost::unit_test::data;
using pv::test::rank;

namespace {

// A unit cube of n^3 cubes (`fill`) whose top face is pressed in: its inner vertices sink by up to
// 0.4 (more than a layer), the layers below left where they were.
pv::Mesh dented(pv::test::Fill fill) {
    pv::Mesh mesh = pv::test::cube_grid(4, fill);
    mesh.fix_boundary();
    mesh.set_reference_coordinates({mesh.coordinates().begin(), mesh.coordinates().end()});
    auto xyz = mesh.coordinates();
    for (std::size_t i = 0; i < xyz.size(); i += 3) {
        const double x = xyz[i], y = xyz[i + 1];
        if (xyz[i + 2] == 1.0 && x > 0.0 && x < 1.0 && y > 0.0 && y < 1.0)
            xyz[i + 2] -= 0.4 * std::sin(M_PI * x) * std::sin(M_PI * y);
    }
    return mesh;
}

struct Case {
    const char* name;
    pv::Mesh (*make)();
    int untangle_iterations;
    bool in_steps;
};
const Case kCases[] = {
    // One run on this budget leaves elements inverted: the motion is followed in steps.
    {"triangles, the inner circle turned 500 degrees, in steps", [] { return pv::test::turned_ring(500.0); }, 5, true},
    {"tetrahedra, the top face pressed in", [] { return dented(pv::test::Fill::Tetrahedra); }, 500, false},
    {"hexahedra, the top face pressed in", [] { return dented(pv::test::Fill::Hexahedra); }, 500, false}};
std::ostream& operator<<(std::ostream& out, const Case& c) { return out << c.name; }

void check_same_mesh(pv::DistributedMesh& part, const pv::Mesh& input, const pv::Mesh& serial) {
    pv::Mesh gathered = input;
    part.gather_coordinates(rank() == 0 ? &gathered : nullptr);
    if (rank() == 0) BOOST_TEST(pv::test::relative_difference(gathered, serial) == 0.0);
}

}  // namespace

BOOST_AUTO_TEST_SUITE(morph_distributed)

BOOST_DATA_TEST_CASE(the_parts_follow_the_motion_as_the_whole_mesh_does, bdata::make(kCases), c) {
    const pv::Mesh input = c.make();
    pv::GlobalSolverOptions options;
    options.termination.max_iterations = 10;
    options.untangle_termination.max_iterations = c.untangle_iterations;

    pv::Mesh serial = input;
    const auto serial_summary = pv::GlobalSolver(options).improve(serial);
    BOOST_TEST_INFO(serial_summary.message);
    BOOST_TEST_REQUIRE(serial_summary.valid());
    if (c.in_steps) BOOST_TEST(serial_summary.message.find("followed in") != std::string::npos);
    BOOST_TEST(serial_summary.before.inverted > 0);

    auto part = pv::test::scatter(input);
    BOOST_TEST(part.mesh().reference_coordinates().size() == part.mesh().coordinates().size());
    const auto summary = pv::GlobalSolver(options).improve(part);
    BOOST_TEST(summary.message == serial_summary.message);
    BOOST_TEST(summary.iterations == serial_summary.iterations);
    BOOST_TEST(summary.worst_after == serial_summary.worst_after);
    BOOST_TEST(summary.after.inverted == serial_summary.after.inverted);
    check_same_mesh(part, input, serial);
}

// The motion in steps of kCases, stopped in a step (three records after the second checkpoint):
// the last checkpoint rank 0 wrote resumes on as many ranks to the uninterrupted run's mesh, bit
// for bit (for the global solver that is the serial mesh, as above).
BOOST_AUTO_TEST_CASE(a_motion_stopped_in_a_step_resumes_on_the_parts_as_if_never_stopped) {
    const pv::Mesh input = pv::test::turned_ring(500.0);
    for (const bool global : {true, false}) {
        BOOST_TEST_CONTEXT((global ? "global" : "local")) {
            // Budgets on which one run does not untangle the motion.
            auto improve = [&](pv::MeshPart part, const pv::CheckpointOptions& checkpoint, pv::IterationObserver observer) {
                auto with = [&]<class Solver>(auto options, int untangle_iterations) {
                    options.untangle_termination.max_iterations = untangle_iterations;
                    options.termination.max_iterations = 10;
                    options.checkpoint = checkpoint;
                    Solver solver(options);
                    solver.set_observer(std::move(observer));
                    return solver.improve(part);
                };
                return global ? with.template operator()<pv::GlobalSolver>(pv::GlobalSolverOptions{}, 5)
                              : with.template operator()<pv::LocalSolver>(pv::LocalSolverOptions{}, 1);
            };
            // The uninterrupted run on as many ranks (the local smoother's coloring depends on the split).
            auto uninterrupted_part = pv::test::scatter(input);
            const pv::Summary uninterrupted = improve(pv::MeshPart(uninterrupted_part), {}, {});
            BOOST_TEST_REQUIRE(uninterrupted.message.find("followed in") != std::string::npos);
            pv::Mesh expected = input;
            uninterrupted_part.gather_coordinates(rank() == 0 ? &expected : nullptr);

            const std::filesystem::path file = pv::test::scratch(std::string("morph_") + (global ? "global" : "local") + ".ckpt");
            if (rank() == 0) std::filesystem::remove(file);
            pv::CheckpointOptions writing;
            writing.file = file.string();
            // Rank 0 watches the file: a stop requested on one rank stops them all at once.
            std::string last;
            int written = 0, records = 0;
            auto watch = [&](const pv::IterationRecord&) {
                if (rank() != 0 || !std::filesystem::exists(file)) return;
                std::ifstream in(file, std::ios::binary);
                std::stringstream bytes;
                bytes << in.rdbuf();
                if (bytes.str() != last) last = bytes.str(), ++written;
                if (written >= 2 && ++records == 3) pv::request_stop();
            };
            pv::clear_stop_request();
            auto stopped_part = pv::test::scatter(input);
            const pv::Summary stopped = improve(pv::MeshPart(stopped_part), writing, watch);
            pv::clear_stop_request();
            BOOST_TEST_REQUIRE(to_string(stopped.reason) == "interrupted");

            pv::CheckpointOptions resuming;
            resuming.resume = file.string();
            auto part = pv::test::scatter(input);
            const pv::Summary resumed = improve(pv::MeshPart(part), resuming, {});
            BOOST_TEST(resumed.message == uninterrupted.message);
            BOOST_TEST(resumed.iterations == uninterrupted.iterations);
            BOOST_TEST(resumed.quality_passes == uninterrupted.quality_passes);
            BOOST_TEST(resumed.history.size() == uninterrupted.history.size());
            BOOST_TEST(resumed.worst_after == uninterrupted.worst_after);
            check_same_mesh(part, input, expected);
            MPI_Barrier(MPI_COMM_WORLD);
            if (rank() == 0) std::filesystem::remove(file), std::filesystem::remove(file.string() + ".run");
        }
    }
}

BOOST_AUTO_TEST_CASE(a_parts_targets_from_its_reference_coordinates_are_the_serial_ones) {
    const pv::Mesh input = dented(pv::test::Fill::Tetrahedra);
    const pv::TargetOptions targets = pv::TargetOptions::from("size,aspect,skew", pv::TargetSource::Reference);
    pv::Mesh serial = input;
    pv::set_targets(pv::MeshPart(serial), targets);
    auto part = pv::test::scatter(input);
    pv::set_targets(pv::MeshPart(part), targets);
    const pv::QualityAssessor assessor({targets.metric("mean_ratio")});
    const auto a = assessor.assess(serial), b = assessor.assess(pv::MeshPart(part));
    BOOST_TEST(a.metrics.front().all.min == b.metrics.front().all.min);
    BOOST_TEST(a.metrics.front().all.mean == b.metrics.front().all.mean);
    // The dent lowered the elements under it against their reference.
    BOOST_TEST(a.metrics.front().all.min < 0.5);
}

BOOST_AUTO_TEST_SUITE_END()
