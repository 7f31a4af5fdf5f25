// A program's own metric: written one element at a time (ElementMetric), registered by name in
// the catalogue, and then taken by name like a built-in one. Here the program's metric is the
// built-in aspect ratio rated element by element, so every pass must give the built-in's bits.
// Example 3's metric gets the checks every metric gets.
#include <boost/test/unit_test.hpp>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "paloverde/core/error.hpp"
#include "paloverde/metrics/quality_metric.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "paloverde/solvers/local_solver.hpp"
#include "sized_aspect.hpp"  // examples/: example 3's metric
#include "support/solver_checks.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;

namespace {

class ElementwiseAspect final : public pv::ElementMetric {
public:
    std::string_view name() const override { return "elementwise_aspect"; }
    double value(pv::ElementKind kind, const double* x) const override { return inner_->value(kind, x); }
    double value_and_gradient(pv::ElementKind kind, const double* x, double* g) const override {
        return inner_->value_and_gradient(kind, x, g);
    }

private:
    std::unique_ptr<pv::QualityMetric> inner_ = pv::make_metric("aspect_ratio");
};

// Registered once for the whole program (the catalogue refuses a name twice).
void register_once() {
    static const bool done = [] {
        pv::register_metric({"elementwise_aspect", "the aspect ratio, one element at a time (a test)",
                             [](const pv::MetricOptions&) { return std::make_unique<ElementwiseAspect>(); }});
        return true;
    }();
    (void)done;
}

// Tangled: the solvers untangle it first, then raise the metric.
pv::Mesh perturbed_tire() { return pv::test::perturbed_shared_mesh("mesquite/tets/tire.vtk", 0.5, 3); }

// The coordinates `input` is moved to by a solver with these options.
template <class Solver, class Options>
std::vector<double> improved(const pv::Mesh& input, const Options& options) {
    auto mesh = input;
    const auto summary = Solver(options).improve(mesh);
    BOOST_TEST(summary.success(), summary.message);
    return {mesh.coordinates().begin(), mesh.coordinates().end()};
}

}  // namespace

BOOST_AUTO_TEST_SUITE(element_metric)

BOOST_AUTO_TEST_CASE(a_registered_metric_is_in_the_catalogue_by_name) {
    register_once();
    const auto& names = pv::metric_names();
    BOOST_TEST(std::count(names.begin(), names.end(), "elementwise_aspect") == 1);
    BOOST_TEST(names.size() == pv::metric_catalogue().size());
    BOOST_TEST(pv::make_metric("elementwise_aspect")->name() == "elementwise_aspect");
    const auto factory = [](const pv::MetricOptions&) { return std::make_unique<ElementwiseAspect>(); };
    BOOST_CHECK_THROW(pv::register_metric({"aspect_ratio", "taken", factory}), pv::OptionError);
    BOOST_CHECK_THROW(pv::register_metric({"elementwise_aspect", "taken", factory}), pv::OptionError);
    BOOST_CHECK_THROW(pv::register_metric({"", "no name", factory}), pv::OptionError);
    BOOST_CHECK_THROW(pv::register_metric({"no_factory", "no factory", {}}), pv::OptionError);
    BOOST_CHECK_THROW(pv::make_metric("no_factory"), pv::OptionError);
}

// Batches of every size (the built-in takes SIMD blocks from 16 elements on), with and without
// curvature, and a base: the same bits as the built-in kernel's.
BOOST_AUTO_TEST_CASE(its_batch_passes_give_the_built_in_bits) {
    register_once();
    const auto mesh = perturbed_tire();
    auto mine = pv::make_metric("elementwise_aspect");
    auto theirs = pv::make_metric("aspect_ratio");
    mine->prepare(mesh);
    theirs->prepare(mesh);
    const pv::ElementId m = mesh.num_elements();
    const std::size_t n = static_cast<std::size_t>(mesh.num_vertices());
    for (const auto& [first, last] : std::vector<std::pair<pv::ElementId, pv::ElementId>>{{0, m}, {5, 12}, {100, 137}}) {
        const auto count = static_cast<std::size_t>(last - first);
        std::vector<double> q1(count), q2(count);
        mine->evaluate(mesh, mesh.coordinates(), first, last, q1.data());
        theirs->evaluate(mesh, mesh.coordinates(), first, last, q2.data());
        BOOST_TEST(q1 == q2, boost::test_tools::per_element());
        std::vector<double> weight(count), curvature_weight(count);
        for (std::size_t i = 0; i < count; ++i) weight[i] = 1.0 + 0.01 * static_cast<double>(i % 7), curvature_weight[i] = 0.5;
        for (bool curvature : {false, true}) {
            std::vector<double> g1(3 * n), g2(3 * n), c1(6 * n), c2(6 * n);
            pv::QualityMetric::GradientTarget t1{weight.data(), g1.data(), curvature ? curvature_weight.data() : nullptr,
                                                 curvature ? c1.data() : nullptr, 0};
            auto t2 = t1;
            t2.gradient = g2.data();
            t2.curvature = curvature ? c2.data() : nullptr;
            mine->accumulate_gradient(mesh, mesh.coordinates(), first, last, t1);
            theirs->accumulate_gradient(mesh, mesh.coordinates(), first, last, t2);
            BOOST_TEST(g1 == g2, boost::test_tools::per_element());
            BOOST_TEST(c1 == c2, boost::test_tools::per_element());
        }
    }
}

// Named in the solvers' options, it moves the mesh exactly as the built-in does.
BOOST_AUTO_TEST_CASE(the_solvers_take_it_by_name) {
    register_once();
    const auto input = perturbed_tire();
    pv::GlobalSolverOptions global, global_built_in;
    global.termination.max_iterations = global_built_in.termination.max_iterations = 8;
    global.shape_metric = "elementwise_aspect";
    BOOST_TEST((improved<pv::GlobalSolver>(input, global) == improved<pv::GlobalSolver>(input, global_built_in)));
    pv::LocalSolverOptions local, local_built_in;
    local.termination.max_iterations = local_built_in.termination.max_iterations = 3;
    local.metric = "elementwise_aspect";
    BOOST_TEST((improved<pv::LocalSolver>(input, local) == improved<pv::LocalSolver>(input, local_built_in)));
}

BOOST_AUTO_TEST_SUITE_END()

// Example 3's metric (examples/sized_aspect.hpp), checked as the built-in ones are: 1 for the
// regular tetrahedron of the reference size, below 1 when skewed or resized, below 0 inverted,
// and its gradient against central finite differences.
BOOST_AUTO_TEST_SUITE(example_metric)

BOOST_AUTO_TEST_CASE(sized_aspect_rates_shape_and_size_and_its_gradient_matches_finite_differences) {
    example::SizedAspect metric;
    pv::MetricScale scale;
    scale.reference_volume = pv::test::regular_simplex_volume(pv::ElementKind::Tetrahedron);
    metric.set_scale(scale);
    const auto tet = pv::ElementKind::Tetrahedron;
    auto x = pv::test::regular_simplex(tet);
    BOOST_TEST(metric.value(tet, x.data()) == 1.0, boost::test_tools::tolerance(1e-12));
    auto doubled = x;
    for (double& c : doubled) c *= 2.0;
    BOOST_TEST(metric.value(tet, doubled.data()) == 2.0 / (8.0 + 1.0 / 8.0), boost::test_tools::tolerance(1e-12));
    BOOST_TEST(!metric.supports(pv::ElementKind::Triangle));

    std::mt19937 rng(17);
    std::uniform_real_distribution<double> jitter(-0.3, 0.3);
    int checked = 0;
    for (int trial = 0; trial < 40; ++trial) {
        auto y = x;
        for (double& c : y) c += jitter(rng);
        if (trial >= 20)
            for (std::size_t i = 0; i < y.size(); i += 3) y[i] = -y[i];  // mirrored: inverted
        std::vector<double> g(12);
        const double q = metric.value_and_gradient(tet, y.data(), g.data());
        BOOST_TEST(q == metric.value(tet, y.data()));
        BOOST_TEST((trial >= 20 ? q < 0.0 : (q > 0.0 && q < 1.0)), "trial " << trial << ": " << q);
        double largest = 0.0;
        for (double gi : g) largest = std::max(largest, std::abs(gi));
        for (std::size_t i = 0; i < 12; ++i) {
            auto plus = y, minus = y;
            const double h = 1e-6;
            plus[i] += h;
            minus[i] -= h;
            const double fd = (metric.value(tet, plus.data()) - metric.value(tet, minus.data())) / (2 * h);
            BOOST_TEST(std::abs(g[i] - fd) <= 1e-6 * std::max(1.0, largest), "trial " << trial << ", coordinate " << i
                                                                                   << ": " << g[i] << " vs " << fd);
            ++checked;
        }
    }
    BOOST_TEST(checked == 480);
    // All four corners in one point: 0, and a zero gradient rather than NaN.
    const std::vector<double> point(12, 1.5);
    std::vector<double> g(12, 7.0);
    BOOST_TEST(metric.value_and_gradient(tet, point.data(), g.data()) == 0.0);
    BOOST_TEST(std::all_of(g.begin(), g.end(), [](double gi) { return gi == 0.0; }));
}

BOOST_AUTO_TEST_SUITE_END()
