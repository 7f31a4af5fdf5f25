// Targets travel with a part (metrics/targets.hpp): computed on each rank's part from its own
// elements, the ideal size summed over the whole mesh, they are the serial targets bit for bit, and
// the global solver rating against them ends on the serial mesh. Run by CTest on 1, 2 and 4 ranks.
#include <mpi.h>

#include <boost/test/data/test_case.hpp>
#include <boost/test/unit_test.hpp>
#include <vector>

#include "paloverde/assess/quality_assessor.hpp"
#include "paloverde/parallel/distributed_mesh.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "distributed_checks.hpp"
#include "support/cell_meshes.hpp"
#include "support/surface_meshes.hpp"

namespace pv = paloverde;
namespace bdata = boost::unit_test::data;
using pv::test::Fill;
using pv::test::rank;

namespace {

struct Case {
    const char* name;
    Fill fill;
    const char* keep;
};
const Case kCases[] = {{"hexahedra, aspect kept", Fill::Hexahedra, "aspect"},
                       {"hexahedra, size and aspect kept", Fill::Hexahedra, "size,aspect"},
                       {"tetrahedra, size, aspect and orientation kept", Fill::Tetrahedra, "size,aspect,orientation"},
                       {"wedges, everything but the skew kept", Fill::Wedges, "size,aspect,orientation"}};
std::ostream& operator<<(std::ostream& out, const Case& c) { return out << c.name; }

// A grid stretched along z (the cells ten times wider than tall) and tangled.
pv::Mesh stretched(Fill fill) {
    pv::Mesh mesh = pv::test::cube_grid(5, fill);
    for (std::size_t v = 2; v < mesh.coordinates().size(); v += 3) mesh.coordinates()[v] *= 0.1;
    return pv::test::tangled(std::move(mesh), 3);
}

// `input` with `targets` set serially and on this rank's part: the parts report what the whole
// mesh does, and the global solver ends on the serial mesh, bit for bit.
void check_parts_give_the_serial_answer(const pv::Mesh& input, const pv::TargetOptions& targets, const char* shape_metric,
                                        bool outline_slides = false) {
    pv::GlobalSolverOptions options;
    if (outline_slides) options.boundary = pv::GlobalSolverOptions::Boundary::Slide;
    options.shape_metric = targets.metric(shape_metric);
    options.termination.max_iterations = 15;
    options.untangle_termination.max_iterations = 150;

    pv::Mesh serial = input;
    pv::set_targets(serial, targets);
    auto part = pv::test::scatter(input);
    pv::set_targets(pv::MeshPart(part), targets);
    const pv::QualityAssessor assessor({options.shape_metric});
    const auto whole_report = assessor.assess(serial), part_report = assessor.assess(pv::MeshPart(part));
    const auto& a = whole_report.metrics.front().all;
    const auto& b = part_report.metrics.front().all;
    BOOST_TEST(a.min == b.min);
    BOOST_TEST(a.mean == b.mean);
    BOOST_TEST(a.count == b.count);

    const auto serial_summary = pv::GlobalSolver(options).improve(serial);
    const auto summary = pv::GlobalSolver(options).improve(part);
    pv::Mesh gathered = input;
    part.gather_coordinates(rank() == 0 ? &gathered : nullptr);
    BOOST_TEST(summary.iterations == serial_summary.iterations);
    BOOST_TEST(summary.worst_after == serial_summary.worst_after);
    BOOST_TEST(summary.after.inverted == serial_summary.after.inverted);
    if (rank() == 0) BOOST_TEST(pv::test::relative_difference(gathered, serial) == 0.0);
    pv::test::check_never_worse(summary);
}

}  // namespace

BOOST_AUTO_TEST_SUITE(targets_distributed)

BOOST_DATA_TEST_CASE(the_parts_targets_are_the_serial_ones_and_so_is_the_result, bdata::make(kCases), c) {
    check_parts_give_the_serial_answer(stretched(c.fill), pv::TargetOptions::from(c.keep), "aspect_ratio");
}

// A surface mesh's targets, each element's taken in its own input plane, and the sliding run
// against them: a torus of triangles with size and aspect kept (its neighbourhood's metrics summed
// over each part), a graded cylinder and Mesquite's sphere patch of quadrilaterals.
BOOST_DATA_TEST_CASE(a_surface_s_targets_and_result_are_the_serial_ones, bdata::make({0, 1, 2}), which) {
    if (which == 0) check_parts_give_the_serial_answer(pv::test::torus(32, 16, 0.3), pv::TargetOptions::from("size,aspect"), "aspect_ratio");
    if (which == 1)
        check_parts_give_the_serial_answer(pv::test::graded_cylinder(24, 10, 0.045, 1.35, 0.3),
                                           pv::TargetOptions::from("size,aspect,orientation"), "aspect_ratio");
    if (which == 2)
        check_parts_give_the_serial_answer(pv::test::shared_mesh("mesquite/hexes/sph-10-zsquare.vtk"), pv::TargetOptions::from("aspect"),
                                           "aspect_ratio", true);
}

// The target edge lengths travel with the parts like the coordinates.
BOOST_AUTO_TEST_CASE(sizes_from_a_field_travel_with_the_parts) {
    pv::Mesh input = stretched(Fill::Tetrahedra);
    std::vector<double> lengths;
    for (pv::VertexId v = 0; v < input.num_vertices(); ++v) lengths.push_back(0.1 + 0.2 * input.coordinates()[3 * v]);
    input.set_target_edge_lengths(lengths);
    pv::TargetOptions targets = pv::TargetOptions::from("aspect");
    targets.size = pv::TargetSource::Field;
    check_parts_give_the_serial_answer(input, targets, "mean_ratio");
}

// The target metrics too, on cells.
BOOST_AUTO_TEST_CASE(metrics_from_a_field_travel_with_the_parts) {
    pv::Mesh input = stretched(Fill::Wedges);
    std::vector<double> metrics;
    for (pv::VertexId v = 0; v < input.num_vertices(); ++v) {
        const double x = input.coordinates()[3 * v], h = 0.1 + 0.2 * x;
        metrics.insert(metrics.end(), {1 / (h * h), 1 / (h * h), 100 / (h * h), 0.3 / (h * h), 0.0, 0.0});
    }
    input.set_target_metrics(metrics);
    pv::TargetOptions targets;
    targets.size = targets.aspect = targets.orientation = pv::TargetSource::Metric;
    check_parts_give_the_serial_answer(input, targets, "mean_ratio");
}

BOOST_AUTO_TEST_SUITE_END()
