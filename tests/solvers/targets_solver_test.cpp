// Solvers with targets (metrics/targets.hpp): a graded boundary layer keeps its layer heights while
// its angles are fixed; a mesh of cells whose aspect is kept never loses scaled Jacobian; the
// size-adapt and boundary-layer wrappers run end to end.
#include <boost/test/unit_test.hpp>
#include <cmath>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "paloverde/assess/quality_assessor.hpp"
#include "paloverde/mesh/orientation.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "paloverde/solvers/local_solver.hpp"
#include "paloverde/wrappers.hpp"
#include "support/solver_checks.hpp"

namespace pv = paloverde;

namespace {

constexpr int kColumns = 4, kLayers = 8;

// Heights of the layers of a block graded from the wall z = 0 (first 2e-3, growth 1.5).
std::vector<double> layer_tops() {
    std::vector<double> z{0.0};
    for (int k = 0; k < kLayers; ++k) z.push_back(z.back() + 2e-3 * std::pow(1.5, k));
    return z;
}

pv::VertexId vertex(int i, int j, int k) { return (k * (kColumns + 1) + j) * (kColumns + 1) + i; }

// The block of hexahedra, its interior vertices moved sideways by up to half the thinner of their
// two layers: every layer's angles need fixing, no layer's height does.
pv::Mesh wobbly_block() {
    const auto z = layer_tops();
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-0.5, 0.5);
    std::vector<double> xyz;
    for (int k = 0; k <= kLayers; ++k)
        for (int j = 0; j <= kColumns; ++j)
            for (int i = 0; i <= kColumns; ++i) {
                double x = static_cast<double>(i) / kColumns, y = static_cast<double>(j) / kColumns;
                if (i > 0 && i < kColumns && j > 0 && j < kColumns && k > 0 && k < kLayers) {
                    const double local = std::min(z[k + 1] - z[k], z[k] - z[k - 1]);
                    x += u(rng) * local;
                    y += u(rng) * local;
                }
                xyz.insert(xyz.end(), {x, y, z[k]});
            }
    std::vector<pv::CellType> types;
    std::vector<pv::VertexId> cells;
    for (int k = 0; k < kLayers; ++k)
        for (int j = 0; j < kColumns; ++j)
            for (int i = 0; i < kColumns; ++i) {
                types.push_back(pv::CellType::Hexahedron);
                cells.insert(cells.end(), {vertex(i, j, k), vertex(i + 1, j, k), vertex(i + 1, j + 1, k), vertex(i, j + 1, k),
                                           vertex(i, j, k + 1), vertex(i + 1, j, k + 1), vertex(i + 1, j + 1, k + 1),
                                           vertex(i, j + 1, k + 1)});
            }
    pv::Mesh mesh = pv::Mesh::from_cells(std::move(xyz), types, std::move(cells));
    mesh.fix_boundary();
    return mesh;
}

// The same block with every hexahedron cut into six tetrahedra around its diagonal 0-6.
pv::Mesh wobbly_tetrahedra() {
    const pv::Mesh cells = wobbly_block();
    constexpr int kCut[6][4] = {{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 3, 7, 6}, {0, 7, 4, 6}, {0, 4, 5, 6}, {0, 5, 1, 6}};
    std::vector<pv::VertexId> tets;
    for (pv::ElementId c = 0; c < cells.num_cells(); ++c)
        for (const auto& tet : kCut)
            for (int i : tet) tets.push_back(cells.cell(c)[static_cast<std::size_t>(i)]);
    pv::Mesh mesh(pv::ElementKind::Tetrahedron, std::vector<double>(cells.coordinates().begin(), cells.coordinates().end()),
                  std::move(tets));
    mesh.fix_boundary();
    return mesh;
}

// Per layer, its mean height over the columns.
std::vector<double> mean_heights(const pv::Mesh& mesh) {
    std::vector<double> out;
    for (int k = 0; k < kLayers; ++k) {
        double sum = 0.0;
        for (int j = 0; j <= kColumns; ++j)
            for (int i = 0; i <= kColumns; ++i) sum += mesh.point(vertex(i, j, k + 1))[2] - mesh.point(vertex(i, j, k))[2];
        out.push_back(sum / ((kColumns + 1) * (kColumns + 1)));
    }
    return out;
}

double worst_scaled_jacobian(const pv::Mesh& mesh) {
    return pv::QualityAssessor({"scaled_jacobian"}).assess(mesh).metrics.front().all.min;
}

// Pulled toward the ideal element, the layers lose their heights; with size and aspect kept the
// worst element rises, none inverts and every layer keeps its mean height within 5%. Returns the
// improved mesh, with its targets, and the run's summary.
std::pair<pv::Mesh, pv::Summary> check_the_layers_hold(const pv::Mesh& input) {
    BOOST_TEST_REQUIRE(pv::count_orientations(input).inverted == 0);
    const auto heights = mean_heights(input);
    pv::Mesh ideal = input;
    pv::GlobalSolver().improve(ideal);
    BOOST_TEST(mean_heights(ideal)[0] > 1.2 * heights[0]);

    pv::Mesh kept = input;
    const pv::TargetOptions targets = pv::TargetOptions::from("size,aspect");
    pv::set_targets(kept, targets);
    pv::GlobalSolverOptions options;
    options.shape_metric = targets.metric(options.shape_metric);
    BOOST_TEST(options.shape_metric == "shape_size");
    const auto summary = pv::GlobalSolver(options).improve(kept);
    BOOST_TEST_MESSAGE(summary.brief_report());
    pv::test::check_never_worse(summary);
    BOOST_TEST(summary.worst_after > summary.worst_before);
    BOOST_TEST(summary.after.inverted == 0);
    const auto after = mean_heights(kept);
    for (int k = 0; k < kLayers; ++k) BOOST_TEST(std::abs(after[k] / heights[k] - 1.0) < 0.05, "layer " << k);
    return {std::move(kept), summary};
}

}  // namespace

BOOST_AUTO_TEST_SUITE(targets_solver)

BOOST_AUTO_TEST_CASE(a_boundary_layer_keeps_its_heights_with_size_and_aspect_kept) {
    const pv::Mesh input = wobbly_block();
    const auto [kept, summary] = check_the_layers_hold(input);
    BOOST_TEST(worst_scaled_jacobian(kept) > worst_scaled_jacobian(input) + 0.1);
}

// Cut into tetrahedra, each one far from regular, the layers still hold: a simplex whose aspect is
// kept is rated in its neighbourhood's metric, where the cut cells are what they were. In a metric
// the default polish raises the mean after the max-min (a sideways tilt of a thin element counts
// little there, so the elements away from the worst need it).
BOOST_AUTO_TEST_CASE(a_tetrahedral_boundary_layer_keeps_its_heights_too) {
    const auto [kept, summary] = check_the_layers_hold(wobbly_tetrahedra());
    BOOST_TEST(kept.target_metric_roots().size() == static_cast<std::size_t>(kept.num_elements()));
    BOOST_TEST(summary.message.find("the mean quality rose") != std::string::npos, summary.message);
}

// Slow (tests/CMakeLists.txt): the sanitizers see targets on hexahedra in the cases above, and on
// quadrilaterals in surface_test's a_tangled_torus_of_quadrilaterals_with_targets_is_untangled.
BOOST_AUTO_TEST_CASE(a_mesh_of_cells_with_targets_never_loses_scaled_jacobian, *boost::unit_test::label("slow")) {
    for (const char* name : {"mesquite/hexes/cub_fru.vtk", "mesquite/quads/horse20x10_2_4.vtk"}) {
        BOOST_TEST_CONTEXT(name) {
            pv::Mesh mesh = pv::test::shared_mesh(name);
            const double before = worst_scaled_jacobian(mesh);
            pv::set_targets(mesh, pv::TargetOptions::from("aspect"));
            const auto summary = pv::GlobalSolver().improve(mesh);
            BOOST_TEST_MESSAGE(summary.brief_report());
            BOOST_TEST(worst_scaled_jacobian(mesh) >= before);
            const pv::MetricReport* reported = summary.after.metric("scaled_jacobian");
            BOOST_TEST_REQUIRE(reported != nullptr);
            BOOST_TEST(reported->all.min >= before);
        }
    }
}

BOOST_AUTO_TEST_CASE(the_local_smoother_rates_against_targets_too) {
    pv::Mesh mesh = wobbly_block();
    const double before = worst_scaled_jacobian(mesh);
    pv::set_targets(mesh, pv::TargetOptions::from("size,aspect"));
    pv::LocalSolverOptions options;
    options.metric = "shape_size";
    options.termination.max_iterations = 20;
    const auto summary = pv::LocalSolver(options).improve(mesh);
    pv::test::check_never_worse(summary);
    BOOST_TEST(summary.worst_after > summary.worst_before);
    BOOST_TEST(worst_scaled_jacobian(mesh) >= before);
}

BOOST_AUTO_TEST_CASE(the_target_wrappers_set_their_targets_and_hand_back_the_mesh_without_them) {
    for (int job = 0; job < 2; ++job) {
        pv::Mesh mesh = wobbly_block();
        const auto heights = mean_heights(mesh);
        const double jacobian = worst_scaled_jacobian(mesh);
        const auto result = (job == 0 ? pv::wrappers::size_adapt_shape() : pv::wrappers::boundary_layer_shape()).run(mesh);
        BOOST_TEST_REQUIRE(result.success, result.message);
        BOOST_TEST(!mesh.has_targets());  // the queue's targets were the queue's
        const auto& summary = std::get<pv::Summary>(result.steps[1].outcome);
        BOOST_TEST(summary.quality_metric == (job == 0 ? "shape_size" : "shape_size_orient"));
        pv::test::check_never_worse(summary);
        BOOST_TEST(worst_scaled_jacobian(mesh) >= jacobian);
        if (job == 0) continue;
        // Sizes alone pull these thin cells toward cubes of their volume, which the guard refuses;
        // with aspect and orientation kept the angles are what is fixed.
        BOOST_TEST(summary.worst_after > summary.worst_before, summary.message);
        BOOST_TEST(worst_scaled_jacobian(mesh) > jacobian);
        const auto after = mean_heights(mesh);
        for (int k = 0; k < kLayers; ++k) BOOST_TEST(std::abs(after[k] / heights[k] - 1.0) < 0.05, "layer " << k);
    }
}

BOOST_AUTO_TEST_SUITE_END()
