// The block kernels (vectorized: baseline, AVX2 and AVX-512) against the scalar kernels, bit for
// bit, on real meshes and on degenerate elements: the batch passes the solvers use must give
// exactly what the one-element calls give, on every CPU.
// Contraction into FMA off, as in the block kernels' file: cube_roots() relies on it.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("fp-contract=off")
#endif

#include <boost/test/unit_test.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <cstring>
#include <random>
#include <utility>
#include <vector>

#include "metrics/cube_root.hpp"
#include "metrics/evaluate_together.hpp"
#include "metrics/tet_blocks.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/mesh.hpp"
#include "paloverde/metrics/quality_metric.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;
namespace pm = paloverde::metrics;

namespace {

// Same bits; any NaN matches any NaN (operand order may pick a different payload).
bool same(double a, double b) {
    if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
    return std::memcmp(&a, &b, sizeof a) == 0;
}

// Every path this CPU runs.
std::vector<pm::BlockPath> paths() {
    std::vector<pm::BlockPath> out;
    for (pm::BlockPath path : {pm::BlockPath::baseline, pm::BlockPath::avx2, pm::BlockPath::avx512})
        if (pm::block_path_supported(path)) out.push_back(path);
    return out;
}

std::vector<double> corners_of(const pv::Mesh& mesh, pv::ElementId e) {
    std::vector<double> x;
    for (pv::VertexId v : mesh.element(e))
        for (int d = 0; d < 3; ++d) x.push_back(mesh.coordinates()[3 * static_cast<std::size_t>(v) + d]);
    return x;
}

// The untangling energy (outside the catalogue) at a mid-run epsilon, or a catalogue metric.
constexpr double kEpsilon = 0.05, kTheta = 1.0 / 128.0;
std::unique_ptr<pv::QualityMetric> metric_named(const std::string& name) {
    return name == "untangle_energy" ? pv::make_untangle_energy(kEpsilon, kTheta) : pv::make_metric(name);
}

// Rates `elements` (12 doubles each) with the block kernel of `name` on each path and compares
// with the metric's scalar value_and_gradient.
void check_blocks(const std::string& name, const std::vector<std::vector<double>>& elements, double reference_volume) {
    auto metric = metric_named(name);
    pv::MetricScale scale;
    scale.reference_volume = reference_volume;
    metric->set_scale(scale);
    const double alpha = pv::MetricOptions{}.hybrid_sharpness;
    for (pm::BlockPath path : paths()) {
        std::size_t mismatches = 0, first_mismatch = 0;
        for (std::size_t first = 0; first < elements.size(); first += pm::kTetBlock) {
            pm::TetBlock x{}, g{};
            double q[pm::kTetBlock], reference[pm::kTetBlock];
            const std::size_t count = std::min<std::size_t>(pm::kTetBlock, elements.size() - first);
            for (std::size_t j = 0; j < count; ++j)
                for (int k = 0; k < 12; ++k) x.at[k][j] = elements[first + j][k];
            for (double& r : reference) r = reference_volume;
            for (const bool gradient : {false, true}) {
                if (name == "aspect_ratio") pm::tet_aspect_block(path, x, q, gradient ? &g : nullptr);
                else if (name == "shape_size") pm::tet_shape_size_block(path, x, reference, q, gradient ? &g : nullptr);
                else if (name == "mean_ratio") pm::tet_mean_ratio_block(path, x, q, gradient ? &g : nullptr);
                else if (name == "untangle_energy")
                    pm::tet_energy_block(path, x, reference, kEpsilon, kTheta, q, gradient ? &g : nullptr);
                else pm::tet_hybrid_block(path, x, reference, alpha, q, gradient ? &g : nullptr);
                for (std::size_t j = 0; j < count; ++j) {
                    double expected_gradient[12];
                    const double expected = metric->value_and_gradient(pv::ElementKind::Tetrahedron,
                                                                       elements[first + j].data(), expected_gradient);
                    bool equal = same(q[j], expected);
                    for (int k = 0; k < 12 && gradient; ++k) equal = equal && same(g.at[k][j], expected_gradient[k]);
                    if (!equal && mismatches++ == 0) first_mismatch = first + j;
                }
            }
        }
        BOOST_TEST_CONTEXT(name << ", path " << static_cast<int>(path) << ", first mismatch at element "
                                << first_mismatch) {
            BOOST_TEST(mismatches == 0u);
        }
    }
}

// The value-only block kernels of the report's metrics against the metric's scalar value().
void check_value_blocks(const std::vector<std::vector<double>>& elements, double reference_volume) {
    const std::pair<const char*, pm::TetValueMetric> kernels[] = {
        {"inverse_condition", pm::TetValueMetric::inverse_condition},
        {"edge_ratio", pm::TetValueMetric::edge_ratio},       {"scaled_volume", pm::TetValueMetric::scaled_volume},
        {"min_dihedral_deg", pm::TetValueMetric::min_dihedral}, {"scaled_jacobian", pm::TetValueMetric::scaled_jacobian}};
    for (const auto& [name, kernel] : kernels) {
        auto metric = pv::make_metric(name);
        pv::MetricScale scale;
        scale.reference_volume = reference_volume;
        metric->set_scale(scale);
        for (pm::BlockPath path : paths()) {
            std::size_t mismatches = 0, first_mismatch = 0;
            double got = 0.0, wanted = 0.0;
            for (std::size_t first = 0; first < elements.size(); first += pm::kTetBlock) {
                pm::TetBlock x{};
                double q[pm::kTetBlock], reference[pm::kTetBlock];
                const std::size_t count = std::min<std::size_t>(pm::kTetBlock, elements.size() - first);
                for (std::size_t j = 0; j < count; ++j)
                    for (int k = 0; k < 12; ++k) x.at[k][j] = elements[first + j][k];
                for (double& r : reference) r = reference_volume;
                pm::tet_values_block(path, kernel, x, reference, q);
                for (std::size_t j = 0; j < count; ++j) {
                    const double expected = metric->value(pv::ElementKind::Tetrahedron, elements[first + j].data());
                    if (!same(q[j], expected) && mismatches++ == 0)
                        first_mismatch = first + j, got = q[j], wanted = expected;
                }
            }
            BOOST_TEST_CONTEXT(name << ", path " << static_cast<int>(path) << ", first mismatch at element "
                                    << first_mismatch << ": " << got << " for " << wanted) {
                BOOST_TEST(mismatches == 0u);
            }
        }
    }
}

// Random tetrahedra and their inverted (two corners swapped), flattened, needle-like and
// cap-like versions, each also at the scales 1e-100 and 1e100; the regular one and its ties.
std::vector<std::vector<double>> random_and_degenerate_elements() {
    std::mt19937_64 random(16);
    std::uniform_real_distribution<double> coordinate(-1.0, 1.0);
    std::vector<std::vector<double>> base;
    const std::vector<double> regular{0, 0, 0, 1, 0, 0, 0.5, std::sqrt(3.0) / 2, 0, 0.5, std::sqrt(3.0) / 6, std::sqrt(2.0 / 3.0)};
    base.push_back(regular);
    for (int n = 0; n < 2000; ++n) {
        std::vector<double> e(12);
        for (double& v : e) v = coordinate(random);
        base.push_back(e);
        std::vector<double> flat = e;  // the fourth corner in the plane of the others
        const double s = 0.5 + 0.5 * coordinate(random), t = 0.5 * (1.0 - s);
        for (int d = 0; d < 3; ++d) flat[9 + d] = s * e[d] + t * e[3 + d] + (1.0 - s - t) * e[6 + d];
        base.push_back(flat);
        std::vector<double> needle = e, cap = e, repeated = e;
        for (int d = 0; d < 3; ++d) {
            needle[3 + d] = e[d] + 1e-9 * (needle[3 + d] - e[d]);  // one very short edge
            cap[9 + d] = 0.5 * (e[3 + d] + e[6 + d]) + 1e-7 * (e[9 + d] - e[d]);  // the fourth corner nearly on an edge
            repeated[6 + d] = e[3 + d];  // two corners at one point
        }
        for (const auto& v : {needle, cap, repeated}) base.push_back(v);
    }
    std::vector<std::vector<double>> out;
    for (const auto& e : base)
        for (const double scale : {1.0, 1e-100, 1e100}) {
            std::vector<double> scaled = e;
            for (double& v : scaled) v *= scale;
            std::vector<double> inverted = scaled;
            std::swap_ranges(inverted.begin(), inverted.begin() + 3, inverted.begin() + 3);
            out.push_back(scaled);
            out.push_back(inverted);
        }
    out.push_back(std::vector<double>(12, 0.25));  // all corners at one point
    std::vector<double> infinite = regular, nan = regular;
    infinite[3] = INFINITY;
    nan[7] = NAN;
    out.push_back(infinite);
    out.push_back(nan);
    return out;
}

std::vector<std::vector<double>> mesh_elements(const pv::Mesh& mesh) {
    std::vector<std::vector<double>> out;
    for (pv::ElementId e = 0; e < mesh.num_elements(); ++e) out.push_back(corners_of(mesh, e));
    return out;
}

}  // namespace

BOOST_AUTO_TEST_SUITE(block_kernels)

BOOST_AUTO_TEST_CASE(block_cube_roots_equal_std_cbrt) {
    // Positive doubles of every exponent (random bits), values of the sizes the kernels see, and
    // the lanes std::cbrt keeps: zeros, negatives, subnormals, infinities, NaN.
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> unit(0.0, 10.0);
    const double special[] = {0.0, -0.0, -3.0, -1e-300, 4.9e-324, 2.2250738585072014e-308, 2.2250738585072009e-308,
                              1.7976931348623157e308, std::numeric_limits<double>::infinity(),
                              -std::numeric_limits<double>::infinity(), std::nan(""), 1.0, 8.0, 0.125, 27.0};
    long compared = 0, differ = 0;
    for (int block = 0; block < 200000; ++block) {
        alignas(64) double values[16], given[16];
        for (int j = 0; j < 16; ++j) {
            const std::uint64_t bits = rng() >> 1;  // a positive double, any exponent
            std::memcpy(&given[j], &bits, sizeof bits);
            if (block % 2) given[j] = unit(rng);
        }
        if (block < 2)
            for (int j = 0; j < 15; ++j) given[(j + block) % 16] = special[j];
        std::memcpy(values, given, sizeof values);
        pm::cube_roots<16>(values);
        for (int j = 0; j < 16; ++j, ++compared)
            if (!same(values[j], std::cbrt(given[j])) && differ++ == 0)
                BOOST_TEST_MESSAGE("first difference: the cube root of " << given[j] << ", " << values[j] << " against std::cbrt's " << std::cbrt(given[j]));
    }
    BOOST_TEST(compared == 3200000);
    BOOST_TEST(differ == 0);
}

BOOST_AUTO_TEST_CASE(block_kernels_equal_the_scalar_kernels_on_a_real_mesh) {
    const auto mesh = pv::read_mesh(pv::test::shared_data("tetwild/octopus-vol.mesh")).mesh;
    const auto elements = mesh_elements(mesh);
    BOOST_TEST_REQUIRE(elements.size() > 1000u);
    const double reference = pv::MetricScale::of(mesh).reference_volume;
    check_blocks("aspect_ratio", elements, reference);
    check_blocks("untangle_hybrid", elements, reference);
    check_blocks("untangle_energy", elements, reference);
    check_blocks("shape_size", elements, reference);
    check_blocks("mean_ratio", elements, reference);
}

BOOST_AUTO_TEST_CASE(block_kernels_equal_the_scalar_kernels_on_tangled_and_degenerate_elements) {
    auto elements = mesh_elements(pv::read_mesh(pv::test::shared_data("mesquite/tets/tet_4_tangled.vtk")).mesh);
    const std::vector<double> regular{0, 0, 0, 1, 0, 0, 0.5, std::sqrt(3.0) / 2, 0, 0.5, std::sqrt(3.0) / 6, std::sqrt(2.0 / 3.0)};
    std::vector<double> inverted = regular;
    inverted[11] = -inverted[11];
    std::vector<double> flat = regular;
    flat[11] = 0.0;
    const std::vector<double> point(12, 0.25);  // all corners at one point: no edge length
    std::vector<double> tiny = regular, huge = regular, infinite = regular, nan = regular;
    for (double& v : tiny) v *= 1e-300;
    for (double& v : huge) v *= 1e200;
    infinite[3] = INFINITY;
    nan[7] = NAN;
    for (const auto& e : {regular, inverted, flat, point, tiny, huge, infinite, nan}) elements.push_back(e);
    check_blocks("aspect_ratio", elements, 0.1);
    check_blocks("untangle_hybrid", elements, 0.1);
    check_blocks("untangle_energy", elements, 0.1);
    check_blocks("shape_size", elements, 0.1);
    check_blocks("shape_size", elements, 1e-100);  // the size term's quotient beyond the double range
    check_blocks("mean_ratio", elements, 0.1);
}

BOOST_AUTO_TEST_CASE(value_block_kernels_equal_the_scalar_kernels) {
    const auto elements = random_and_degenerate_elements();
    check_value_blocks(elements, 0.1);
    check_value_blocks(elements, 1e-100);  // the scaled volume's quotient beyond the double range
    const auto mesh = pv::read_mesh(pv::test::shared_data("tetwild/octopus-vol.mesh")).mesh;
    check_value_blocks(mesh_elements(mesh), pv::MetricScale::of(mesh).reference_volume);
    // The batch call takes those kernels, on an odd range (blocks off the multiples of 16).
    for (const std::string name :
         {"mean_ratio", "inverse_condition", "edge_ratio", "scaled_volume", "min_dihedral_deg", "scaled_jacobian"}) {
        auto metric = pv::make_metric(name);
        metric->set_scale(pv::MetricScale::of(mesh));
        const pv::ElementId first = 3, last = mesh.num_elements() - 2;
        std::vector<double> quality(static_cast<std::size_t>(last - first));
        metric->evaluate(mesh, mesh.coordinates(), first, last, quality.data());
        std::size_t mismatches = 0;
        for (pv::ElementId e = first; e < last; ++e)
            mismatches += !same(quality[e - first], metric->value(pv::ElementKind::Tetrahedron, corners_of(mesh, e).data()));
        BOOST_TEST_CONTEXT(name) { BOOST_TEST(mismatches == 0u); }
    }
}

// A star's call (the listed elements' values, with and without gradients) against the one-element
// calls.
BOOST_AUTO_TEST_CASE(listed_values_and_gradients_equal_the_one_element_calls) {
    const auto mesh = pv::read_mesh(pv::test::shared_data("tetwild/octopus-vol.mesh")).mesh;
    std::vector<pv::ElementId> listed;
    for (pv::ElementId e = 5; e < mesh.num_elements(); e += 7) listed.push_back(e);
    for (const std::string name : {"aspect_ratio", "mean_ratio", "untangle_hybrid", "shape_size", "inverse_condition"}) {
        auto metric = pv::make_metric(name);
        metric->prepare(mesh);
        std::vector<double> quality(listed.size()), values(listed.size()), gradient(12 * listed.size());
        metric->element_values(mesh, mesh.coordinates(), listed, quality.data(), gradient.data());
        metric->element_values(mesh, mesh.coordinates(), listed, values.data(), nullptr);
        std::size_t mismatches = 0;
        for (std::size_t i = 0; i < listed.size(); ++i) {
            double g[12];
            const double q = metric->element_value(mesh, mesh.coordinates(), listed[i], g);
            mismatches += !same(q, quality[i]) + !same(q, values[i]);
            for (int k = 0; k < 12; ++k) mismatches += !same(g[k], gradient[12 * i + k]);
        }
        BOOST_TEST_CONTEXT(name) { BOOST_TEST(mismatches == 0u); }
    }
}

// The report's pass, one gather per block for all metrics, against each metric's own batch call:
// tetrahedra, cells (whose corners are mapped), triangles (no blocks), with a per-element scale.
BOOST_AUTO_TEST_CASE(metrics_rated_together_equal_each_metric_rated_alone) {
    for (const char* file : {"tetwild/octopus-vol.mesh", "mesquite/mixed/mixed-hex-pyr-tet.vtk",
                             "mesquite/hexes/hex_5_tangled.vtk", "mesquite/tris/bad_circle_tri.vtk"}) {
        const auto mesh = pv::read_mesh(pv::test::shared_data(file)).mesh;
        const pv::ElementId m = mesh.num_elements();
        std::vector<double> local_volume(static_cast<std::size_t>(m));
        for (pv::ElementId e = 0; e < m; ++e) local_volume[e] = 0.001 * (1.0 + e % 13);
        for (const bool per_element_scale : {false, true}) {
            pv::MetricScale scale = pv::MetricScale::of(mesh);
            if (per_element_scale) scale.element_reference_volume = local_volume;
            std::vector<std::unique_ptr<pv::QualityMetric>> metrics;
            for (const auto& name : pv::metric_names())
                if (auto metric = pv::make_metric(name); metric->supports(mesh.kind())) metrics.push_back(std::move(metric));
            metrics.push_back(pv::make_untangle_energy(kEpsilon, kTheta));
            std::vector<const pv::QualityMetric*> rated;
            for (auto& metric : metrics) {
                metric->set_scale(scale);
                rated.push_back(metric.get());
            }
            const pv::ElementId first = m > 40 ? 3 : 0, last = m > 40 ? m - 2 : m;  // blocks off the multiples of 16
            const auto count = static_cast<std::size_t>(last - first);
            std::vector<std::vector<double>> together(metrics.size(), std::vector<double>(count));
            std::vector<double*> out;
            for (auto& q : together) out.push_back(q.data());
            pm::evaluate_together(rated, mesh, mesh.coordinates(), first, last, out);
            for (std::size_t i = 0; i < metrics.size(); ++i) {
                std::vector<double> alone(count);
                metrics[i]->evaluate(mesh, mesh.coordinates(), first, last, alone.data());
                BOOST_TEST_CONTEXT(file << ", " << metrics[i]->name() << (per_element_scale ? ", per-element scale" : "")) {
                    BOOST_TEST(std::memcmp(alone.data(), together[i].data(), count * sizeof(double)) == 0);
                }
            }
        }
    }
}

// The batch calls (which take the block path for tetrahedra) against the one-element calls:
// qualities, and gradient and curvature sums added in the same order.
BOOST_AUTO_TEST_CASE(batch_passes_equal_element_by_element_sums) {
    const auto mesh = pv::read_mesh(pv::test::shared_data("tetwild/octopus-vol.mesh")).mesh;
    const pv::ElementId m = mesh.num_elements();
    const auto n = static_cast<std::size_t>(mesh.num_vertices());
    std::vector<double> weight(static_cast<std::size_t>(m)), curvature_weight(weight.size()),
        local_volume(weight.size());
    for (pv::ElementId e = 0; e < m; ++e) {
        weight[e] = e % 11 == 0 ? 0.0 : 1.0 / (1.0 + e % 7);  // some zero weights, which are skipped
        curvature_weight[e] = e % 5 == 0 ? 0.0 : 0.5 + e % 3;
        local_volume[e] = 0.001 * (1.0 + e % 13);
    }
    for (const std::string name : {"aspect_ratio", "untangle_hybrid", "untangle_energy"}) {
        for (const bool per_element_scale : {false, true}) {
            auto metric = metric_named(name);
            pv::MetricScale scale = pv::MetricScale::of(mesh);
            if (per_element_scale) scale.element_reference_volume = local_volume;
            metric->set_scale(scale);
            // An odd range: blocks start off the element numbering's multiples of the block size.
            const pv::ElementId first = 3, last = m - 2;
            std::vector<double> quality(static_cast<std::size_t>(last - first));
            metric->evaluate(mesh, mesh.coordinates(), first, last, quality.data());
            std::vector<double> gradient(3 * n, 0.0), curvature(6 * n, 0.0);
            pv::QualityMetric::GradientTarget target;
            target.weight = weight.data() + first;
            target.gradient = gradient.data();
            target.curvature_weight = curvature_weight.data() + first;
            target.curvature = curvature.data();
            metric->accumulate_gradient(mesh, mesh.coordinates(), first, last, target);

            std::vector<double> expected_gradient(3 * n, 0.0), expected_curvature(6 * n, 0.0);
            auto one = metric_named(name);
            bool qualities_equal = true;
            for (pv::ElementId e = first; e < last; ++e) {
                pv::MetricScale s = scale;
                if (per_element_scale) s.reference_volume = local_volume[e];
                s.element_reference_volume = {};
                one->set_scale(s);
                const auto x = corners_of(mesh, e);
                double g[12];
                const double q = one->value_and_gradient(pv::ElementKind::Tetrahedron, x.data(), g);
                qualities_equal = qualities_equal && same(q, quality[e - first]);
                const double w = weight[e], cw = curvature_weight[e];
                if (w == 0.0 && cw == 0.0) continue;
                for (int i = 0; i < 4; ++i) {
                    const auto v = static_cast<std::size_t>(mesh.element(e)[i]);
                    const double* gi = g + 3 * i;
                    for (int d = 0; d < 3; ++d) expected_gradient[3 * v + d] += w * gi[d];
                    double* c = &expected_curvature[6 * v];
                    c[0] += cw * gi[0] * gi[0];
                    c[1] += cw * gi[0] * gi[1];
                    c[2] += cw * gi[0] * gi[2];
                    c[3] += cw * gi[1] * gi[1];
                    c[4] += cw * gi[1] * gi[2];
                    c[5] += cw * gi[2] * gi[2];
                }
            }
            BOOST_TEST_CONTEXT(name << (per_element_scale ? ", per-element scale" : "")) {
                BOOST_TEST(qualities_equal);
                BOOST_TEST(std::memcmp(gradient.data(), expected_gradient.data(), gradient.size() * sizeof(double)) == 0);
                BOOST_TEST(std::memcmp(curvature.data(), expected_curvature.data(), curvature.size() * sizeof(double)) == 0);
            }
        }
    }
}

// Target maps (and metric roots) carried over a block's lanes: every path gives the baseline's
// bits, forward and back, whatever the lanes' maps are and wherever they lie (each path lays the
// lanes' entries side by side in its own way).
BOOST_AUTO_TEST_CASE(target_maps_carry_a_block_alike_on_every_path) {
    std::mt19937_64 random(7);
    std::uniform_real_distribution<double> entry(-2.0, 2.0);
    // More maps than lanes, picked out of order: neighbouring lanes' maps are not neighbours.
    std::vector<pv::CornerMap> maps(3 * pm::kTetBlock), roots(maps.size());
    for (auto* list : {&maps, &roots})
        for (pv::CornerMap& map : *list)
            for (auto& row : map)
                for (double& v : row) v = entry(random);
    const pv::CornerMap* map_of[pm::kTetBlock];
    const pv::CornerMap* root_of[pm::kTetBlock];
    for (int j = 0; j < pm::kTetBlock; ++j) {
        map_of[j] = &maps[static_cast<std::size_t>((7 * j + 3) % maps.size())];
        root_of[j] = &roots[static_cast<std::size_t>((5 * j + 11) % roots.size())];
    }
    pm::TetBlock x{}, g{};
    for (int i = 0; i < 12; ++i)
        for (int j = 0; j < pm::kTetBlock; ++j) x.at[i][j] = entry(random), g.at[i][j] = entry(random);
    for (const bool with_roots : {false, true}) {
        const pv::CornerMap* const* r = with_roots ? root_of : nullptr;
        pm::TetBlock x_base = x, g_base = g;
        pm::map_tets(pm::BlockPath::baseline, map_of, r, x_base);
        pm::unmap_tets(pm::BlockPath::baseline, map_of, r, g_base);
        for (pm::BlockPath path : paths()) {
            pm::TetBlock x_path = x, g_path = g;
            pm::map_tets(path, map_of, r, x_path);
            pm::unmap_tets(path, map_of, r, g_path);
            BOOST_TEST_CONTEXT("path " << static_cast<int>(path) << (with_roots ? ", with roots" : "")) {
                BOOST_TEST(std::memcmp(&x_path, &x_base, sizeof x_base) == 0);
                BOOST_TEST(std::memcmp(&g_path, &g_base, sizeof g_base) == 0);
            }
        }
    }
}

BOOST_AUTO_TEST_SUITE_END()

// The listed call (the solvers' re-rating of a few elements around moved vertices) against the
// batch call over the whole range: the same bits, scattered by element id, for lists long enough
// for blocks and too short for them, in any order; tetrahedra, cells and triangles alike.
BOOST_AUTO_TEST_CASE(listed_elements_rate_as_the_batch_call_rates_them) {
    for (const char* file : {"tetwild/octopus-vol.mesh", "mesquite/mixed/mixed-hex-pyr-tet.vtk",
                             "mesquite/tris/bad_circle_tri.vtk"}) {
        const auto mesh = pv::read_mesh(pv::test::shared_data(file)).mesh;
        const pv::ElementId m = mesh.num_elements();
        std::vector<double> local_volume(static_cast<std::size_t>(m));
        for (pv::ElementId e = 0; e < m; ++e) local_volume[e] = 0.001 * (1.0 + e % 13);
        std::vector<pv::ElementId> many, few;
        const pv::ElementId stride = m >= 40 * pm::kTetBlock ? 7 : 1;
        for (pv::ElementId e = m - 1; e >= 0; e -= stride) many.push_back(e);  // scattered, decreasing
        for (pv::ElementId e = 0; e < m && few.size() < 5; e += 3) few.push_back(e);
        BOOST_TEST_REQUIRE(many.size() > static_cast<std::size_t>(pm::kTetBlock + 1), file << ": " << m << " elements");
        std::vector<std::unique_ptr<pv::QualityMetric>> metrics;
        for (const auto& name : pv::metric_names())
            if (auto metric = pv::make_metric(name); metric->supports(mesh.kind())) metrics.push_back(std::move(metric));
        metrics.push_back(pv::make_untangle_energy(kEpsilon, kTheta));
        for (const bool per_element_scale : {false, true})
            for (auto& metric : metrics) {
                pv::MetricScale scale = pv::MetricScale::of(mesh);
                if (per_element_scale) scale.element_reference_volume = local_volume;
                metric->set_scale(scale);
                std::vector<double> whole(static_cast<std::size_t>(m));
                metric->evaluate(mesh, mesh.coordinates(), 0, m, whole.data());
                for (const auto* listed : {&many, &few}) {
                    const double untouched = -12345.0;
                    std::vector<double> quality(static_cast<std::size_t>(m), untouched);
                    metric->evaluate_listed(mesh, mesh.coordinates(), *listed, quality.data());
                    std::size_t mismatches = 0, strays = 0;
                    std::vector<bool> in_list(static_cast<std::size_t>(m), false);
                    for (pv::ElementId e : *listed) {
                        in_list[e] = true;
                        mismatches += !same(quality[e], whole[e]);
                    }
                    for (pv::ElementId e = 0; e < m; ++e) strays += !in_list[e] && quality[e] != untouched;
                    BOOST_TEST_CONTEXT(file << ", " << metric->name() << ", " << listed->size() << " elements"
                                            << (per_element_scale ? ", per-element scale" : "")) {
                        BOOST_TEST(mismatches == 0u);
                        BOOST_TEST(strays == 0u);
                    }
                }
            }
    }
}
