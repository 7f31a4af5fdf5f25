#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Kernel/global_functions.h>
#include <boost/test/unit_test.hpp>
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "paloverde/assess/quality_assessor.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/metrics/quality_metric.hpp"
#include "paloverde/metrics/targets.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;
using K = CGAL::Exact_predicates_inexact_constructions_kernel;

namespace {
// The smallest dihedral angle of a tet by CGAL's own formula: an independent check.
double cgal_min_dihedral(const pv::Mesh& mesh, pv::ElementId e) {
    const auto c = mesh.element(e);
    K::Point_3 p[4];
    for (int i = 0; i < 4; ++i) {
        const auto x = mesh.point(c[i]);
        p[i] = K::Point_3(x[0], x[1], x[2]);
    }
    double smallest = 180.0;
    // The dihedral angle along edge (i, j) between the faces through k and through l.
    const int edges[6][4] = {{0, 1, 2, 3}, {0, 2, 1, 3}, {0, 3, 1, 2}, {1, 2, 0, 3}, {1, 3, 0, 2}, {2, 3, 0, 1}};
    for (const auto& e4 : edges)
        smallest = std::min(smallest, std::abs(CGAL::to_double(
                                          CGAL::approximate_dihedral_angle(p[e4[0]], p[e4[1]], p[e4[2]], p[e4[3]]))));
    return smallest;
}
}  // namespace

BOOST_AUTO_TEST_SUITE(quality_assessor)

BOOST_AUTO_TEST_CASE(cub_wedge_like_matches_an_independent_check) {
    const auto file = pv::read_mesh(pv::test::shared_data("mesquite/tets/cub_wedge_like.vtk"));
    const auto& mesh = file.mesh;
    const auto report = pv::QualityAssessor().assess(mesh);
    BOOST_TEST(report.vertices == 21156);
    BOOST_TEST(report.elements == 112393);

    double expected_min = 180.0;
    long inverted = 0;
    for (pv::ElementId e = 0; e < mesh.num_elements(); ++e) {
        bool movable = false;
        for (auto v : mesh.element(e)) movable |= !mesh.fixed()[v];
        const auto c = mesh.element(e);
        auto p = [&](int i) {
            const auto x = mesh.point(c[i]);
            return K::Point_3(x[0], x[1], x[2]);
        };
        inverted += CGAL::orientation(p(0), p(1), p(2), p(3)) == CGAL::NEGATIVE;
        if (movable) expected_min = std::min(expected_min, cgal_min_dihedral(mesh, e));
    }
    const auto* dihedral = report.metric("min_dihedral_deg");
    BOOST_REQUIRE(dihedral);
    BOOST_TEST(std::abs(dihedral->movable.min - expected_min) < 0.01);
    BOOST_TEST(std::abs(dihedral->movable.min - 6.10) < 0.01);  // the figure in shared/data/README.md
    BOOST_TEST(report.inverted == inverted);
}

BOOST_AUTO_TEST_CASE(tangled_mesh_counts_its_nine_inverted_tets) {
    const auto file = pv::read_mesh(pv::test::shared_data("mesquite/tets/tet_4_tangled.vtk"));
    const auto report = pv::QualityAssessor().assess(file.mesh);
    BOOST_TEST(report.inverted == 9);
    BOOST_TEST(report.inverted_frozen == 0);
    BOOST_TEST(report.metric("aspect_ratio")->all.min < 0.0);
}

BOOST_AUTO_TEST_CASE(statistics_split_movable_and_frozen_elements) {
    // Two tets: the first has a free vertex, the second only fixed ones.
    pv::Mesh mesh(pv::ElementKind::Tetrahedron, {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1},
                  {0, 1, 2, 3, 1, 4, 2, 3});
    mesh.set_fixed({0, 1, 1, 1, 1});
    const auto report = pv::QualityAssessor({"aspect_ratio", "scaled_volume"}, 4).assess(mesh);
    BOOST_TEST(report.frozen_elements == 1);
    const auto* q = report.metric("aspect_ratio");
    BOOST_TEST(q->movable.count == 1);
    BOOST_TEST(q->frozen.count == 1);
    BOOST_TEST(q->all.count == 2);
    BOOST_TEST(q->all.min == std::min(q->movable.min, q->frozen.min));
    BOOST_TEST(q->all.histogram.size() == 4u);
    BOOST_TEST(q->all.histogram[0] + q->all.histogram[3] == 2);
    // mean and rms of two values
    const double a = q->movable.min, b = q->frozen.min;
    BOOST_TEST(q->all.mean == (a + b) / 2, boost::test_tools::tolerance(1e-14));
    BOOST_TEST(q->all.rms == std::sqrt((a * a + b * b) / 2), boost::test_tools::tolerance(1e-14));
}

BOOST_AUTO_TEST_CASE(triangle_meshes_report_the_minimum_angle_not_the_dihedral) {
    const auto file = pv::read_mesh(pv::test::shared_data("mesquite/tris/tangled_tri.vtk"));
    const auto report = pv::QualityAssessor().assess(file.mesh);
    BOOST_TEST(report.metric("min_angle_deg") != nullptr);
    BOOST_TEST(report.metric("min_dihedral_deg") == nullptr);
    BOOST_TEST(report.inverted > 0);
}

BOOST_AUTO_TEST_CASE(json_has_the_documented_keys) {
    const auto file = pv::read_mesh(pv::test::shared_data("mesquite/tets/tet_4_tangled.vtk"));
    const auto j = nlohmann::json::parse(pv::QualityAssessor().assess(file.mesh).to_json());
    for (const char* key : {"vertices", "elements", "inverted", "metrics"}) BOOST_TEST(j.contains(key));
    for (const char* metric : {"aspect_ratio", "mean_ratio", "min_dihedral_deg"})
        for (const char* stat : {"min", "max", "mean", "rms"}) BOOST_TEST(j["metrics"][metric].contains(stat));
    BOOST_TEST(j["inverted"].get<int>() == 9);
}

// A report taken from another assessor's report of the same mesh is the one assess() makes, for
// tetrahedra, cells (by type) and triangles (whose report has no dihedral angle); it is refused
// where the other did not rate a metric or counted other bins.
BOOST_AUTO_TEST_CASE(a_report_taken_from_a_fuller_one_is_the_report_assessed) {
    const pv::QualityAssessor full;
    const pv::QualityAssessor small({"min_dihedral_deg", "aspect_ratio", "scaled_jacobian"});
    for (const char* file : {"mesquite/tets/tire.vtk", "mesquite/hexes/sph-10-zsquare.vtk",
                             "mesquite/mixed/mixed-hex-pyr-tet.vtk", "mesquite/tris/tri_20258.vtk"}) {
        const auto mesh = pv::read_mesh(pv::test::shared_data(file)).mesh;
        const auto taken = small.taken_from(full.assess(mesh), full);
        BOOST_REQUIRE_MESSAGE(taken.has_value(), file);
        BOOST_TEST(taken->to_json() == small.assess(mesh).to_json(), file);
        BOOST_TEST(taken->metrics.front().name == (mesh.kind() == pv::ElementKind::Tetrahedron && !mesh.has_cells()
                                                       ? "min_dihedral_deg"
                                                       : "aspect_ratio"),
                   file);
    }
    const auto mesh = pv::read_mesh(pv::test::shared_data("mesquite/tets/tire.vtk")).mesh;
    const pv::QualityAssessor shape({"aspect_ratio", "mean_ratio"});
    BOOST_TEST(!pv::QualityAssessor({"shape_size"}).taken_from(full.assess(mesh), full).has_value());
    BOOST_TEST(!shape.taken_from(shape.assess(mesh), pv::QualityAssessor({"aspect_ratio", "mean_ratio"}, 20)).has_value());
    BOOST_TEST(pv::QualityAssessor({"mean_ratio"}).taken_from(shape.assess(mesh), shape).has_value());
}

// The report's scaled Jacobian is the corners' own, the users' measure, whatever targets the
// mesh carries (the report's other metrics rate its elements against them): with targets and
// without, its worst and mean are those of the metric's own evaluate().
BOOST_AUTO_TEST_CASE(the_reported_scaled_jacobian_rates_the_corners_as_they_are_with_targets_too) {
    auto mesh = pv::read_mesh(pv::test::shared_data("mesquite/tets/tire.vtk")).mesh;
    const auto own = [&] {
        std::vector<double> q(static_cast<std::size_t>(mesh.num_elements()));
        auto metric = pv::make_metric("scaled_jacobian");
        metric->set_scale(pv::MetricScale::of(mesh));
        metric->evaluate(mesh, mesh.coordinates(), 0, mesh.num_elements(), q.data());
        return *std::min_element(q.begin(), q.end());
    };
    const pv::QualityAssessor assessor({"shape_size", "scaled_jacobian"});
    const double plain = assessor.assess(mesh).metric("scaled_jacobian")->all.min;
    BOOST_TEST(plain == own());
    pv::set_targets(mesh, pv::TargetOptions::from("all"));
    BOOST_REQUIRE(mesh.has_targets());
    const pv::QualityReport targeted = assessor.assess(mesh);
    BOOST_TEST(targeted.metric("scaled_jacobian")->all.min == plain);
    BOOST_TEST(targeted.metric("shape_size")->all.min > 0.99);  // every element is its own target
}

BOOST_AUTO_TEST_CASE(unknown_metrics_and_bad_bins_are_rejected) {
    BOOST_CHECK_THROW(pv::QualityAssessor({"nope"}), std::exception);
    BOOST_CHECK_THROW(pv::QualityAssessor({"aspect_ratio"}, 0), std::exception);
}

BOOST_AUTO_TEST_SUITE_END()
