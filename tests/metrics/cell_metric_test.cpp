// Cells rated by their corners (cell_types.hpp): the ideal cell scores the ideal value at every
// corner, gradients through the corner maps match finite differences, the rating is invariant
// under motions and scaling, and a mirrored cell is inverted at every corner.
#include <boost/test/data/test_case.hpp>
#include <boost/test/unit_test.hpp>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "paloverde/assess/quality_assessor.hpp"
#include "paloverde/mesh/cell_types.hpp"
#include "paloverde/mesh/orientation.hpp"
#include "paloverde/metrics/quality_metric.hpp"
#include "support/cell_meshes.hpp"

namespace pv = paloverde;
namespace bdata = boost::unit_test::data;

namespace {

const std::vector<pv::CellType> kCells{pv::CellType::Quadrilateral, pv::CellType::Hexahedron, pv::CellType::Wedge,
                                       pv::CellType::Pyramid};

// One cell of `type` at the given corner positions (its ideal shape when empty).
pv::Mesh one_cell(pv::CellType type, std::vector<double> xyz = {}) {
    if (xyz.empty())
        for (const auto& p : pv::ideal_cell(type)) xyz.insert(xyz.end(), p.begin(), p.end());
    std::vector<pv::VertexId> cell(static_cast<std::size_t>(pv::cell_info(type).corners));
    for (std::size_t i = 0; i < cell.size(); ++i) cell[i] = static_cast<pv::VertexId>(i);
    const pv::CellType types[] = {type};
    return pv::Mesh::from_cells(std::move(xyz), types, std::move(cell));
}

std::vector<double> ideal_coordinates(pv::CellType type) {
    std::vector<double> xyz;
    for (const auto& p : pv::ideal_cell(type)) xyz.insert(xyz.end(), p.begin(), p.end());
    return xyz;
}

// Metrics with a gradient that mean something on cells.
std::vector<std::string> metrics_for_cells() {
    std::vector<std::string> out;
    for (const auto& name : pv::metric_names()) {
        auto m = pv::make_metric(name);
        if (m->supports_cells() && m->has_gradient()) out.push_back(name);
    }
    return out;
}

std::vector<double> rate(const pv::QualityMetric& metric, const pv::Mesh& mesh, std::span<const double> xyz) {
    std::vector<double> q(static_cast<std::size_t>(mesh.num_elements()));
    metric.evaluate(mesh, xyz, 0, mesh.num_elements(), q.data());
    return q;
}

}  // namespace

BOOST_AUTO_TEST_SUITE(cell_metrics)

BOOST_AUTO_TEST_CASE(corner_maps_carry_the_ideal_corner_to_the_regular_simplex) {
    BOOST_TEST(pv::corner_map_count() == 1 + 4 + 8 + 6 + 4);
    for (pv::CellType type : kCells) {
        const auto mesh = one_cell(type);
        BOOST_TEST(mesh.has_cells());
        BOOST_TEST(mesh.num_cells() == 1);
        BOOST_TEST(mesh.num_elements() == static_cast<pv::ElementId>(pv::cell_info(type).frames.size()));
        BOOST_TEST(pv::count_orientations(mesh).inverted == 0);
        for (std::uint8_t id : mesh.corner_maps()) BOOST_TEST((pv::corner_map_cell(id) == type));
    }
}

BOOST_DATA_TEST_CASE(the_ideal_cell_scores_the_ideal_value, bdata::make(metrics_for_cells()), name) {
    for (pv::CellType type : kCells) {
        BOOST_TEST_CONTEXT(name << " on a " << pv::cell_info(type).name) {
            const auto mesh = one_cell(type);
            auto metric = pv::make_metric(name);
            metric->prepare(mesh);
            for (double q : rate(*metric, mesh, mesh.coordinates()))
                BOOST_TEST(q == metric->ideal_value(), boost::test_tools::tolerance(1e-12));
        }
    }
}

BOOST_DATA_TEST_CASE(gradients_through_corner_maps_match_finite_differences, bdata::make(metrics_for_cells()), name) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> jitter(-0.15, 0.15);
    for (pv::CellType type : kCells) {
        for (int trial = 0; trial < 5; ++trial) {
            std::vector<double> xyz = ideal_coordinates(type);
            for (std::size_t i = 0; i < xyz.size(); ++i)
                if (pv::cell_info(type).dimension == 3 || i % 3 != 2) xyz[i] += jitter(rng);
            const auto mesh = one_cell(type, xyz);
            auto metric = pv::make_metric(name);
            metric->prepare(mesh);
            const pv::ElementId m = mesh.num_elements();
            // The weighted sum of all corners' qualities, its gradient by accumulate_gradient.
            std::vector<double> weight(static_cast<std::size_t>(m));
            for (pv::ElementId e = 0; e < m; ++e) weight[e] = 1.0 + 0.25 * e;
            std::vector<double> gradient(xyz.size(), 0.0);
            pv::QualityMetric::GradientTarget target;
            target.weight = weight.data();
            target.gradient = gradient.data();
            metric->accumulate_gradient(mesh, xyz, 0, m, target);
            auto total = [&](const std::vector<double>& x) {
                const auto q = rate(*metric, mesh, x);
                double sum = 0.0;
                for (pv::ElementId e = 0; e < m; ++e) sum += weight[e] * q[e];
                return sum;
            };
            BOOST_TEST_CONTEXT(name << " on a " << pv::cell_info(type).name << ", trial " << trial) {
                for (std::size_t i = 0; i < xyz.size(); ++i) {
                    if (pv::cell_info(type).dimension == 2 && i % 3 == 2) continue;  // out of the plane
                    const double h = 1e-6;
                    auto plus = xyz, minus = xyz;
                    plus[i] += h, minus[i] -= h;
                    const double fd = (total(plus) - total(minus)) / (2 * h);
                    BOOST_TEST(std::abs(gradient[i] - fd) <= 1e-5 * std::max(1.0, std::abs(fd)));
                }
                // The one-element call agrees with the batch passes, value and gradient.
                std::vector<double> g(12);
                const auto q = rate(*metric, mesh, xyz);
                for (pv::ElementId e = 0; e < m; ++e) {
                    BOOST_TEST(metric->element_value(mesh, xyz, e) == q[e]);
                    BOOST_TEST(metric->element_value(mesh, xyz, e, g.data()) == q[e], boost::test_tools::tolerance(1e-14));
                }
            }
        }
    }
}

// Whole batches go through the vectorized tetrahedron blocks, one element at a time through the
// scalar kernels: a cell's corners are mapped in both, to the same bits.
BOOST_DATA_TEST_CASE(blocks_and_single_corners_rate_cells_alike, bdata::make(metrics_for_cells()), name) {
    auto mesh = pv::test::cube_grid(3, pv::test::Fill::Mixed);
    std::vector<double> xyz(mesh.coordinates().begin(), mesh.coordinates().end());
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> jitter(-0.05, 0.05);
    for (double& x : xyz) x += jitter(rng);
    auto metric = pv::make_metric(name);
    metric->prepare(mesh);
    const auto q = rate(*metric, mesh, xyz);
    const pv::ElementId m = mesh.num_elements();
    std::vector<double> weight(static_cast<std::size_t>(m), 1.0), batch(xyz.size(), 0.0), single(xyz.size(), 0.0);
    pv::QualityMetric::GradientTarget target;
    target.weight = weight.data();
    target.gradient = batch.data();
    metric->accumulate_gradient(mesh, xyz, 0, m, target);
    target.gradient = single.data();
    bool same = true;
    for (pv::ElementId e = 0; e < m; ++e) {
        same = same && metric->element_value(mesh, xyz, e) == q[e];
        metric->accumulate_gradient(mesh, xyz, e, e + 1, target);
    }
    BOOST_TEST(same);
    BOOST_TEST(batch == single);
}

// A metric that rates orientation (shape_size_orient) is moved and scaled but not turned.
BOOST_DATA_TEST_CASE(cells_rate_the_same_after_motion_and_scaling, bdata::make(metrics_for_cells()), name) {
    const double turn = pv::make_metric(name)->rotation_invariant() ? 0.7 : 0.0;
    const double c = std::cos(turn), s = std::sin(turn);
    for (pv::CellType type : kCells) {
        std::vector<double> xyz = ideal_coordinates(type);
        xyz[3] += 0.2, xyz[4] -= 0.1;  // a distorted cell
        std::vector<double> moved(xyz.size());
        for (std::size_t i = 0; i < xyz.size(); i += 3) {
            const double x = xyz[i], y = xyz[i + 1], z = xyz[i + 2];
            moved[i] = 3.0 * (c * x - s * y) + 5.0;
            moved[i + 1] = 3.0 * (s * x + c * y) - 2.0;
            moved[i + 2] = 3.0 * z + (pv::cell_info(type).dimension == 3 ? 1.0 : 0.0);
        }
        const auto a = one_cell(type, xyz), b = one_cell(type, moved);
        auto ma = pv::make_metric(name), mb = pv::make_metric(name);
        ma->prepare(a);
        mb->prepare(b);
        const auto qa = rate(*ma, a, a.coordinates()), qb = rate(*mb, b, b.coordinates());
        BOOST_TEST_CONTEXT(name << " on a " << pv::cell_info(type).name) {
            for (std::size_t e = 0; e < qa.size(); ++e) BOOST_TEST(qa[e] == qb[e], boost::test_tools::tolerance(1e-10));
        }
    }
}

// (A planar mesh's cells are oriented by its own normal, so one mirrored quadrilateral alone is
// valid: the quadrilateral grid below inverts a few among many.)
BOOST_AUTO_TEST_CASE(a_mirrored_cell_is_inverted_at_every_corner) {
    for (pv::CellType type : kCells) {
        if (pv::cell_info(type).dimension == 2) continue;
        BOOST_TEST_CONTEXT(pv::cell_info(type).name) {
            std::vector<double> xyz = ideal_coordinates(type);
            for (std::size_t i = 0; i < xyz.size(); i += 3) xyz[i] = -xyz[i];  // reflect x
            const auto mesh = one_cell(type, xyz);
            BOOST_TEST(pv::count_orientations(mesh).inverted == 1);  // one cell, every corner
            auto metric = pv::make_metric("aspect_ratio");
            metric->prepare(mesh);
            for (double q : rate(*metric, mesh, mesh.coordinates())) BOOST_TEST(q < 0.0);
            // Flipping it (as auto orientation does for a mirrored file) makes every corner ideal.
            auto flipped = mesh;
            flipped.flip_elements();
            BOOST_TEST(pv::count_orientations(flipped).inverted == 0);
            for (double q : rate(*metric, flipped, flipped.coordinates()))
                BOOST_TEST(q == 1.0, boost::test_tools::tolerance(1e-12));
            flipped.flip_elements();  // an involution
            BOOST_TEST((std::vector<pv::VertexId>(flipped.connectivity().begin(), flipped.connectivity().end()) ==
                        std::vector<pv::VertexId>(mesh.connectivity().begin(), mesh.connectivity().end())));
        }
    }
}

// The target metrics on a unit cube: every corner maps to the unit regular tetrahedron (volume
// sqrt(2) / 12) in the regular tetrahedron's own orientation, so with that reference volume they
// rate 1; the cube grown by 10% or turned by 10 degrees rates less.
BOOST_AUTO_TEST_CASE(target_metrics_rate_the_unit_cube_one_at_every_corner) {
    const std::vector<double> cube = ideal_coordinates(pv::CellType::Hexahedron);
    const double c = std::cos(std::numbers::pi / 18), s = std::sin(std::numbers::pi / 18);
    std::vector<double> grown = cube, turned = cube;
    for (std::size_t i = 0; i < cube.size(); i += 3) {
        for (int d = 0; d < 3; ++d) grown[i + d] = 1.1 * cube[i + d];
        turned[i] = c * cube[i] - s * cube[i + 1];
        turned[i + 1] = s * cube[i] + c * cube[i + 1];
    }
    for (const char* name : {"shape_size", "shape_size_orient"}) {
        BOOST_TEST_CONTEXT(name) {
            auto metric = pv::make_metric(name);
            pv::MetricScale scale;
            scale.reference_volume = std::sqrt(2.0) / 12.0;
            metric->set_scale(scale);
            const auto mesh = one_cell(pv::CellType::Hexahedron, cube);
            BOOST_TEST(mesh.num_elements() == 8);
            for (double q : rate(*metric, mesh, cube)) BOOST_TEST(q == 1.0, boost::test_tools::tolerance(1e-12));
            for (double q : rate(*metric, mesh, grown)) BOOST_TEST(q < 0.999);
            for (double q : rate(*metric, mesh, turned)) {
                if (metric->rotation_invariant()) BOOST_TEST(q == 1.0, boost::test_tools::tolerance(1e-12));
                else BOOST_TEST(q < 0.999);
            }
        }
    }
}

BOOST_AUTO_TEST_CASE(the_assessor_reports_cells_and_types) {
    auto mesh = pv::test::cube_grid(3, pv::test::Fill::Mixed);
    BOOST_TEST_REQUIRE(mesh.has_cells());
    const auto ideal = pv::QualityAssessor().assess(mesh);
    BOOST_TEST(ideal.elements == mesh.num_cells());
    BOOST_TEST(ideal.inverted == 0);
    BOOST_TEST(ideal.by_type.size() == 3u);
    BOOST_TEST(!ideal.metric("min_dihedral_deg"));  // degrees of a corner mean nothing for a cell
    // Push the centre vertex of the grid through a face: the cells around it invert.
    std::vector<double> xyz(mesh.coordinates().begin(), mesh.coordinates().end());
    pv::VertexId inner = -1;
    for (pv::VertexId v = 0; v < mesh.num_vertices(); ++v)
        if (!mesh.fixed()[v] && inner < 0) inner = v;
    BOOST_TEST_REQUIRE(inner >= 0);
    xyz[3 * inner] += 0.9;
    const auto bad = pv::QualityAssessor().assess(mesh, xyz);
    BOOST_TEST(bad.inverted > 0);
    BOOST_TEST(bad.inverted == pv::count_orientations(mesh, xyz).inverted);  // cells, not corners
    BOOST_TEST(bad.metric("aspect_ratio")->all.min < 0.0);
    long inverted_by_type = 0;
    for (const auto& t : bad.by_type) inverted_by_type += t.inverted;
    BOOST_TEST(inverted_by_type == bad.inverted);

    // Quadrilaterals: an interior vertex pushed past its neighbour folds the cells around it.
    const auto quads = pv::test::quad_grid(4);
    std::vector<double> folded(quads.coordinates().begin(), quads.coordinates().end());
    const pv::VertexId middle = 2 * 5 + 2;
    BOOST_TEST_REQUIRE(!quads.fixed()[middle]);
    folded[3 * middle] += 0.4;
    const auto q = pv::QualityAssessor().assess(quads, folded);
    BOOST_TEST(q.elements == 16);
    BOOST_TEST(q.inverted > 0);
    BOOST_TEST(q.inverted <= 4);
    BOOST_TEST(q.by_type.size() == 1u);
    BOOST_TEST(q.by_type[0].type == "quadrilateral");
}

BOOST_AUTO_TEST_SUITE_END()
