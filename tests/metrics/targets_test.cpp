// Targets (metrics/targets.hpp): each factor from each source, the metrics rating an element that
// equals its target 1, the maps' gradients, scaling, and the errors for bad input.
#include <boost/test/unit_test.hpp>
#include <cmath>
#include <cstring>
#include <numbers>
#include <random>
#include <vector>

#include "paloverde/core/error.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/boundary_surface.hpp"
#include "paloverde/mesh/cell_types.hpp"
#include "paloverde/metrics/quality_metric.hpp"
#include "paloverde/metrics/targets.hpp"
#include "support/cell_meshes.hpp"
#include "support/surface_meshes.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;

namespace {

std::vector<double> rate(const std::string& name, const pv::Mesh& mesh, std::span<const double> xyz) {
    auto metric = pv::make_metric(name);
    metric->prepare(mesh);
    std::vector<double> q(static_cast<std::size_t>(mesh.num_elements()));
    metric->evaluate(mesh, xyz, 0, mesh.num_elements(), q.data());
    return q;
}
std::vector<double> rate(const std::string& name, const pv::Mesh& mesh) { return rate(name, mesh, mesh.coordinates()); }

void check_all_near(const std::vector<double>& q, double value, double tolerance = 1e-12) {
    for (std::size_t e = 0; e < q.size(); ++e) BOOST_TEST(std::abs(q[e] - value) <= tolerance, "element " << e << ": " << q[e]);
}

// The regular tetrahedron of edge `edge`, turned by `angle` about z, as a one-element mesh.
pv::Mesh regular_tet(double edge = 1.0, double angle = 0.0) {
    const double c = std::cos(angle), s = std::sin(angle);
    std::vector<double> xyz;
    for (const auto& p : pv::ideal_cell(pv::CellType::Tetrahedron)) {
        xyz.push_back(edge * (c * p[0] - s * p[1]));
        xyz.push_back(edge * (s * p[0] + c * p[1]));
        xyz.push_back(edge * p[2]);
    }
    return pv::Mesh(pv::ElementKind::Tetrahedron, std::move(xyz), {0, 1, 2, 3});
}

// A box of a x b x c as one hexahedron.
pv::Mesh box(double a, double b, double c) {
    std::vector<double> xyz{0, 0, 0, a, 0, 0, a, b, 0, 0, b, 0, 0, 0, c, a, 0, c, a, b, c, 0, b, c};
    const pv::CellType types[] = {pv::CellType::Hexahedron};
    return pv::Mesh::from_cells(std::move(xyz), types, {0, 1, 2, 3, 4, 5, 6, 7});
}

// A few tetrahedra of random shapes and sizes, positively oriented.
pv::Mesh random_tets(int count, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::vector<double> xyz;
    std::vector<pv::VertexId> corners;
    for (int t = 0; t < count; ++t) {
        double p[4][3];
        for (auto& point : p)
            for (double& x : point) x = u(rng) * (1.0 + t);
        const double d = (p[1][0] - p[0][0]) * ((p[2][1] - p[0][1]) * (p[3][2] - p[0][2]) - (p[2][2] - p[0][2]) * (p[3][1] - p[0][1])) -
                         (p[1][1] - p[0][1]) * ((p[2][0] - p[0][0]) * (p[3][2] - p[0][2]) - (p[2][2] - p[0][2]) * (p[3][0] - p[0][0])) +
                         (p[1][2] - p[0][2]) * ((p[2][0] - p[0][0]) * (p[3][1] - p[0][1]) - (p[2][1] - p[0][1]) * (p[3][0] - p[0][0]));
        if (d < 0) std::swap(p[2], p[3]);
        for (const auto& point : p) xyz.insert(xyz.end(), point, point + 3);
        for (int i = 0; i < 4; ++i) corners.push_back(static_cast<pv::VertexId>(4 * t + i));
    }
    return pv::Mesh(pv::ElementKind::Tetrahedron, std::move(xyz), std::move(corners));
}

// Surface meshes as the solvers rate them: each element about its normal of the input surface.
pv::Mesh with_surface_normals(pv::Mesh mesh) {
    mesh.set_surface_normals(pv::BoundarySurface(mesh).normals_of(mesh));
    return mesh;
}
pv::Mesh perturbed_torus() { return with_surface_normals(pv::test::torus(24, 12, 0.3)); }
pv::Mesh sphere_of_quadrilaterals() {
    return with_surface_normals(pv::read_mesh(pv::test::shared_data("mesquite/hexes/sph-10-zsquare.vtk")).mesh);
}

// Every element's gradient of `name` at xyz against central differences.
void check_gradients(const pv::Mesh& mesh, std::span<const double> xyz, const char* name) {
    auto metric = pv::make_metric(name);
    metric->prepare(mesh);
    const int k = mesh.corners();
    for (pv::ElementId e = 0; e < mesh.num_elements(); ++e) {
        double g[12];
        metric->element_value(mesh, xyz, e, g);
        for (int i = 0; i < k; ++i)
            for (int d = 0; d < 3; ++d) {
                const auto at = 3 * static_cast<std::size_t>(mesh.element(e)[i]) + d;
                const double h = 1e-7;
                std::vector<double> plus(xyz.begin(), xyz.end()), minus = plus;
                plus[at] += h, minus[at] -= h;
                const double fd = (metric->element_value(mesh, plus, e) - metric->element_value(mesh, minus, e)) / (2 * h);
                BOOST_TEST(std::abs(fd - g[3 * i + d]) <= 1e-5 * (1.0 + std::abs(fd)),
                           name << " element " << e << " corner " << i << ": " << g[3 * i + d] << " vs " << fd);
            }
    }
}

}  // namespace

BOOST_AUTO_TEST_SUITE(targets)

BOOST_AUTO_TEST_CASE(an_element_that_keeps_everything_rates_one_in_every_metric) {
    pv::Mesh tets = random_tets(20, 7);
    pv::set_targets(tets, pv::TargetOptions::from("all"));
    for (const char* metric : {"mean_ratio", "aspect_ratio", "inverse_condition", "shape_size", "shape_size_orient"})
        check_all_near(rate(metric, tets), 1.0, 1e-10);

    pv::Mesh hex = box(3.0, 1.0, 0.01);
    pv::set_targets(hex, pv::TargetOptions::from("all"));
    for (const char* metric : {"mean_ratio", "shape_size", "shape_size_orient"}) check_all_near(rate(metric, hex), 1.0, 1e-10);
}

BOOST_AUTO_TEST_CASE(a_stretched_box_keeps_its_aspect_and_its_angles_are_what_is_rated) {
    pv::Mesh hex = box(10.0, 1.0, 0.1);
    BOOST_TEST(rate("mean_ratio", hex)[0] < 0.5);  // against the cube
    pv::set_targets(hex, pv::TargetOptions::from("aspect"));
    check_all_near(rate("mean_ratio", hex), 1.0, 1e-12);
    // Sheared, it is no longer its target: the angles count, the stretch does not.
    std::vector<double> sheared(hex.coordinates().begin(), hex.coordinates().end());
    for (int v : {4, 5, 6, 7}) sheared[3 * v] += 0.05;
    for (double q : rate("mean_ratio", hex, sheared)) BOOST_TEST(q < 1.0 - 1e-6);
}

BOOST_AUTO_TEST_CASE(size_is_kept_only_when_asked) {
    pv::Mesh small = regular_tet(0.5);
    pv::set_targets(small, pv::TargetOptions::from("size"));
    check_all_near(rate("shape_size", small), 1.0);
    // Twice the edges: eight times the volume, tau = 8, 2 tau / (1 + tau^2) = 16 / 65.
    std::vector<double> doubled(small.coordinates().begin(), small.coordinates().end());
    for (double& x : doubled) x *= 2.0;
    check_all_near(rate("shape_size", small, doubled), 16.0 / 65.0, 1e-12);

    // Ideal size: the mesh's mean, so two regular tets of different sizes both miss it.
    pv::Mesh two = random_tets(2, 3);
    pv::set_targets(two, pv::TargetOptions::from("skew,aspect"));
    const auto q = rate("shape_size", two);
    BOOST_TEST(q[0] < 1.0);
    BOOST_TEST(q[1] < 1.0);
}

BOOST_AUTO_TEST_CASE(orientation_is_rated_only_where_it_is_kept) {
    pv::Mesh turned = regular_tet(1.0, 0.5);
    pv::set_targets(turned, pv::TargetOptions::from("size,orientation"));
    check_all_near(rate("shape_size_orient", turned), 1.0, 1e-12);
    // Ideal orientation: the regular tet as cell_types holds it; turned by 0.5 rad it is not.
    pv::set_targets(turned, pv::TargetOptions::from("size"));
    BOOST_TEST(rate("shape_size_orient", turned)[0] < 0.99);
    check_all_near(rate("shape_size", turned), 1.0, 1e-12);
}

BOOST_AUTO_TEST_CASE(a_reference_mesh_gives_the_targets_of_a_moved_mesh) {
    const pv::Mesh reference = random_tets(10, 11);
    pv::Mesh moved = reference;
    std::vector<double> xyz(moved.coordinates().begin(), moved.coordinates().end());
    for (std::size_t i = 0; i < xyz.size(); ++i) moved.coordinates()[i] += 0.05 * std::sin(static_cast<double>(i));
    pv::TargetOptions options;
    options.size = options.orientation = options.aspect = options.skew = pv::TargetSource::Reference;
    pv::set_targets(moved, options, &reference);
    // At the reference's positions every element is its target.
    check_all_near(rate("shape_size_orient", moved, xyz), 1.0, 1e-10);
    for (double q : rate("shape_size_orient", moved)) BOOST_TEST(q < 1.0);

    // Other connectivity, other counts: refused, naming what differs.
    const pv::Mesh other = random_tets(9, 11);
    BOOST_CHECK_EXCEPTION(pv::set_targets(moved, options, &other), pv::MeshError, [](const pv::MeshError& e) {
        return std::string(e.what()).find("connectivity") != std::string::npos;
    });
    std::vector<double> same(reference.coordinates().begin(), reference.coordinates().end());
    std::vector<pv::VertexId> swapped(reference.connectivity().begin(), reference.connectivity().end());
    std::swap(swapped[4], swapped[8]);
    const pv::Mesh rewired(pv::ElementKind::Tetrahedron, same, swapped);
    BOOST_CHECK_EXCEPTION(pv::set_targets(moved, options, &rewired), pv::MeshError, [](const pv::MeshError& e) {
        return std::string(e.what()).find("element 1") != std::string::npos;
    });
    BOOST_CHECK_THROW(pv::set_targets(moved, options), pv::OptionError);  // no reference given
}

BOOST_AUTO_TEST_CASE(a_degenerate_or_inverted_input_element_falls_back_to_the_ideal) {
    // A flat tetrahedron: its corner gives no factor; the ideal element stands in, no NaN.
    pv::Mesh flat(pv::ElementKind::Tetrahedron, {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0}, {0, 1, 2, 3});
    pv::set_targets(flat, pv::TargetOptions::from("all"));
    for (const auto& row : flat.target_maps()[0])
        for (double x : row) BOOST_TEST(std::isfinite(x));
    // An inverted one keeps its size and shape (its mirror's), not its orientation.
    pv::Mesh inverted = regular_tet();
    std::swap(inverted.coordinates()[6], inverted.coordinates()[9]);
    std::swap(inverted.coordinates()[7], inverted.coordinates()[10]);
    std::swap(inverted.coordinates()[8], inverted.coordinates()[11]);
    pv::set_targets(inverted, pv::TargetOptions::from("all"));
    BOOST_TEST(rate("mean_ratio", inverted)[0] <= 0.0);
    // With the aspect kept and the skew ideal a simplex is rated in its neighbourhood's metric;
    // the flat tetrahedron alone has none (every simplex around it is degenerate): it is rated
    // against the regular tetrahedron, as with no targets.
    pv::set_targets(flat, pv::TargetOptions::from("aspect"));
    BOOST_TEST(std::isfinite(rate("mean_ratio", flat)[0]));
    BOOST_TEST(rate("mean_ratio", flat)[0] == 0.0);
    // Three quadrilaterals around a triangle, every corner of which lies at one point (a Mesquite
    // test mesh): the degenerate triangle's vertices have no metric; its aspect is ideal.
    pv::Mesh hybrid = pv::read_mesh(pv::test::shared_data("mesquite/mixed/hybrid_3quad_1tri_tangled.vtk")).mesh;
    pv::set_targets(hybrid, pv::TargetOptions::from("aspect"));
    BOOST_TEST(hybrid.has_targets());
}

BOOST_AUTO_TEST_CASE(triangles_and_quadrilaterals_take_targets_in_their_plane) {
    // A 4 x 1 rectangle: its corners keep their aspect.
    std::vector<double> xyz{0, 0, 0, 4, 0, 0, 4, 1, 0, 0, 1, 0};
    const pv::CellType quad[] = {pv::CellType::Quadrilateral};
    pv::Mesh rectangle = pv::Mesh::from_cells(xyz, quad, {0, 1, 2, 3});
    BOOST_TEST(rate("mean_ratio", rectangle)[0] < 0.9);
    pv::set_targets(rectangle, pv::TargetOptions::from("aspect"));
    check_all_near(rate("mean_ratio", rectangle), 1.0, 1e-12);

    pv::Mesh triangles(pv::ElementKind::Triangle, {0, 0, 0, 3, 0, 0, 0.5, 0.2, 0, 3, 1, 0}, {0, 1, 2, 1, 3, 2});
    pv::set_targets(triangles, pv::TargetOptions::from("all"));
    for (const char* metric : {"mean_ratio", "shape_size", "shape_size_orient"}) check_all_near(rate(metric, triangles), 1.0, 1e-10);
}

BOOST_AUTO_TEST_CASE(a_simplex_takes_the_stretch_of_its_neighbourhood) {
    // One tetrahedron is its own neighbourhood: with its aspect kept, it is its own target.
    pv::Mesh one = random_tets(1, 3);
    BOOST_TEST(rate("mean_ratio", one)[0] < 0.9);
    pv::set_targets(one, pv::TargetOptions::from("aspect"));
    check_all_near(rate("mean_ratio", one), 1.0, 1e-10);

    // Cubes cut into tetrahedra, each far from regular, then sheared and squashed tenfold along z
    // by F: the vertices' metrics are the cut cubes' mapped by F (F^-T M F^-1, at determinant 1),
    // so a layer's intended stretch is what the targets hold, whatever the cut.
    const double f[3][3] = {{1.0, 0.0, 0.3}, {0.0, 1.0, -0.2}, {0.0, 0.0, 0.1}};
    const double f_inverse[3][3] = {{1.0, 0.0, -3.0}, {0.0, 1.0, 2.0}, {0.0, 0.0, 10.0}};
    pv::Mesh cubes = pv::test::cube_grid(4, pv::test::Fill::Tetrahedra);
    pv::Mesh squashed = cubes;
    for (std::size_t v = 0; v < squashed.coordinates().size(); v += 3)
        for (int i = 0; i < 3; ++i) {
            double sum = 0.0;
            for (int k = 0; k < 3; ++k) sum += f[i][k] * cubes.coordinates()[v + k];
            squashed.coordinates()[v + i] = sum;
        }
    const auto aspect = pv::TargetOptions::from("aspect");
    const auto metric = pv::vertex_metrics(cubes, aspect, nullptr), squashed_metric = pv::vertex_metrics(squashed, aspect, nullptr);
    BOOST_TEST(metric.size() == static_cast<std::size_t>(pv::Mesh::kMetricValues * cubes.num_vertices()));
    const int index[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {1, 2}, {0, 2}};
    const double scale = std::cbrt(0.1 * 0.1);  // det(F)^(2/3)
    double largest = 0.0;
    for (std::size_t v = 0; v < static_cast<std::size_t>(cubes.num_vertices()); ++v) {
        double m[3][3];
        for (int k = 0; k < 6; ++k) m[index[k][0]][index[k][1]] = m[index[k][1]][index[k][0]] = metric[6 * v + k];
        for (int k = 0; k < 6; ++k) {
            const auto [i, j] = index[k];
            double mapped = 0.0;  // (F^-T M F^-1)[i][j]
            for (int p = 0; p < 3; ++p)
                for (int q = 0; q < 3; ++q) mapped += f_inverse[p][i] * m[p][q] * f_inverse[q][j];
            largest = std::max(largest, std::abs(scale * mapped - squashed_metric[6 * v + k]) / (1.0 + std::abs(mapped)));
        }
    }
    BOOST_TEST(largest < 1e-12, "largest difference " << largest);

    const auto ideal = rate("mean_ratio", squashed);
    pv::set_targets(squashed, aspect);
    const auto kept = rate("mean_ratio", squashed);
    BOOST_TEST(*std::min_element(kept.begin(), kept.end()) > *std::min_element(ideal.begin(), ideal.end()));
    // Cells keep their own corners' aspect; keeping the skew too keeps each simplex's own.
    BOOST_TEST(pv::vertex_metrics(box(1, 2, 3), aspect, nullptr) == std::vector<double>(6 * 8, 0.0));
    BOOST_TEST(pv::vertex_metrics(cubes, pv::TargetOptions::from("aspect,skew"), nullptr).empty());
}

BOOST_AUTO_TEST_CASE(gradients_through_targets_match_finite_differences) {
    pv::Mesh tets = random_tets(6, 5);
    pv::set_targets(tets, pv::TargetOptions::from("size,aspect"));
    std::vector<double> xyz(tets.coordinates().begin(), tets.coordinates().end());
    std::mt19937 rng(2);
    std::normal_distribution<double> jitter(0.0, 0.1);
    for (double& x : xyz) x += jitter(rng);
    for (const char* name : {"shape_size", "mean_ratio", "shape_size_orient"}) {
        auto metric = pv::make_metric(name);
        metric->prepare(tets);
        for (pv::ElementId e = 0; e < tets.num_elements(); ++e) {
            double g[12];
            metric->element_value(tets, xyz, e, g);
            for (int i = 0; i < 4; ++i)
                for (int d = 0; d < 3; ++d) {
                    const auto at = 3 * static_cast<std::size_t>(tets.element(e)[i]) + d;
                    const double h = 1e-6 * (1.0 + e);
                    std::vector<double> plus = xyz, minus = xyz;
                    plus[at] += h, minus[at] -= h;
                    const double fd = (metric->element_value(tets, plus, e) - metric->element_value(tets, minus, e)) / (2 * h);
                    BOOST_TEST(std::abs(fd - g[3 * i + d]) <= 1e-5 * (1.0 + std::abs(fd)),
                               name << " element " << e << " corner " << i << ": " << g[3 * i + d] << " vs " << fd);
                }
        }
    }
}

BOOST_AUTO_TEST_CASE(a_size_field_sizes_each_element_by_its_vertices_edge_lengths) {
    const pv::TargetOptions field = [] {
        pv::TargetOptions o;
        o.size = pv::TargetSource::Field;
        return o;
    }();
    // A regular tet of edge 0.5 whose vertices ask for edges of 0.5 rates 1; asking for 1 at every
    // vertex is the doubled tet of the test above, and so is a mean of 1 from unequal lengths.
    pv::Mesh tet = regular_tet(0.5);
    tet.set_target_edge_lengths({0.5, 0.5, 0.5, 0.5});
    pv::set_targets(tet, field);
    check_all_near(rate("shape_size", tet), 1.0, 1e-12);
    tet.set_target_edge_lengths({1.0, 1.0, 1.0, 1.0});
    pv::set_targets(tet, field);
    check_all_near(rate("shape_size", tet), 16.0 / 65.0, 1e-12);
    tet.set_target_edge_lengths({0.5, 1.5, 1.0, 1.0});
    pv::set_targets(tet, field);
    check_all_near(rate("shape_size", tet), 16.0 / 65.0, 1e-12);
    // A box of 2 x 1 x 1 asking for edges of 1 with its aspect kept: the unit cube stretched to
    // the box's aspect has its volume, so it rates 1; asking for 2 misses by eight times the volume.
    pv::Mesh cell = box(2.0, 1.0, 1.0);
    pv::TargetOptions stretched = pv::TargetOptions::from("aspect");
    stretched.size = pv::TargetSource::Field;
    cell.set_target_edge_lengths(std::vector<double>(8, std::cbrt(2.0)));
    pv::set_targets(cell, stretched);
    check_all_near(rate("shape_size", cell), 1.0, 1e-12);
    cell.set_target_edge_lengths(std::vector<double>(8, 2.0 * std::cbrt(2.0)));
    pv::set_targets(cell, stretched);
    check_all_near(rate("shape_size", cell), 16.0 / 65.0, 1e-12);
    // Lengths scale with the mesh.
    tet.scale(3);
    BOOST_TEST(tet.target_edge_lengths()[1] == 12.0);
}

BOOST_AUTO_TEST_CASE(a_size_field_that_is_missing_or_not_a_length_is_refused) {
    pv::Mesh tet = regular_tet();
    pv::TargetOptions field;
    field.size = pv::TargetSource::Field;
    BOOST_CHECK_THROW(pv::set_targets(tet, field), pv::OptionError);  // no lengths given
    BOOST_CHECK_THROW(tet.set_target_edge_lengths({1.0, 1.0, 1.0}), pv::MeshError);
    BOOST_CHECK_EXCEPTION(tet.set_target_edge_lengths({1.0, 1.0, -2.0, 1.0}), pv::MeshError, [](const pv::MeshError& e) {
        return std::string(e.what()).find("vertex 2") != std::string::npos;
    });
    BOOST_CHECK_THROW(tet.set_target_edge_lengths({1.0, std::nan(""), 1.0, 1.0}), pv::MeshError);
    tet.set_target_edge_lengths({1.0, 1.0, 1.0, 1.0});
    pv::TargetOptions skew_from_field;
    skew_from_field.skew = pv::TargetSource::Field;
    BOOST_CHECK_THROW(pv::set_targets(tet, skew_from_field), pv::OptionError);
}

// A metric field (docs/targets.md): every element becomes the ideal element in the mean of its
// vertices' metrics, sized, stretched and turned by it.
pv::TargetOptions from_metric() {
    pv::TargetOptions o;
    o.size = o.aspect = o.orientation = pv::TargetSource::Metric;
    return o;
}
std::vector<double> uniform_metric(const pv::Mesh& mesh, std::array<double, 6> m) {
    std::vector<double> out;
    for (pv::VertexId v = 0; v < mesh.num_vertices(); ++v) out.insert(out.end(), m.begin(), m.end());
    return out;
}

// The batch passes (blocks of tetrahedra, their corners carried by their targets together) and
// the listed call a local smoother rates a star with give the one-element calls' values and
// gradients bit for bit, with targets from a reference, kept from the mesh, or from a metric
// field; on a range off the multiples of the block size.
BOOST_AUTO_TEST_CASE(batch_passes_with_targets_equal_the_one_element_calls) {
    pv::Mesh reference = random_tets(200, 5);
    for (int setup = 0; setup < 3; ++setup) {
        pv::Mesh mesh = reference;
        for (std::size_t i = 0; i < mesh.coordinates().size(); ++i)
            mesh.coordinates()[i] += 0.3 * std::sin(0.7 * static_cast<double>(i));
        if (setup == 0) {
            pv::TargetOptions options;
            options.size = options.aspect = options.skew = pv::TargetSource::Reference;
            pv::set_targets(mesh, options, &reference);
        } else if (setup == 1) {
            pv::set_targets(mesh, pv::TargetOptions::from("aspect"));
        } else {
            std::vector<double> field;
            for (pv::VertexId v = 0; v < mesh.num_vertices(); ++v) {
                const double a = 1.0 + 0.1 * (v % 7);
                field.insert(field.end(), {a, 1.0, 0.5 * a, 0.1, 0.0, 0.05});
            }
            mesh.set_target_metrics(field);
            pv::set_targets(mesh, from_metric());
        }
        const std::span<const double> xyz = mesh.coordinates();
        const pv::ElementId first = 3, last = mesh.num_elements() - 2;
        for (const char* name : {"shape_size", "shape_size_orient", "mean_ratio"}) {
            auto metric = pv::make_metric(name);
            metric->prepare(mesh);
            std::vector<double> quality(static_cast<std::size_t>(last - first));
            metric->evaluate(mesh, xyz, first, last, quality.data());
            const std::vector<double> weight(quality.size(), 1.0);
            std::vector<double> batch(xyz.size(), 0.0), single(xyz.size(), 0.0);
            pv::QualityMetric::GradientTarget target;
            target.weight = weight.data();
            target.gradient = batch.data();
            metric->accumulate_gradient(mesh, xyz, first, last, target);
            // A star's call: every third element, listed.
            std::vector<pv::ElementId> listed;
            for (pv::ElementId e = first; e < last; e += 3) listed.push_back(e);
            std::vector<double> listed_quality(listed.size()), listed_values(listed.size()), listed_gradient(12 * listed.size());
            metric->element_values(mesh, xyz, listed, listed_quality.data(), listed_gradient.data());
            metric->element_values(mesh, xyz, listed, listed_values.data(), nullptr);
            std::size_t mismatches = 0;
            for (pv::ElementId e = first; e < last; ++e) {
                double g[12];
                const double q = metric->element_value(mesh, xyz, e, g);
                mismatches += std::memcmp(&q, &quality[e - first], sizeof q) != 0;
                for (int i = 0; i < 4; ++i)
                    for (int d = 0; d < 3; ++d) single[3 * static_cast<std::size_t>(mesh.element(e)[i]) + d] += g[3 * i + d];
                if ((e - first) % 3 == 0) {
                    const std::size_t at = static_cast<std::size_t>(e - first) / 3;
                    mismatches += std::memcmp(&q, &listed_quality[at], sizeof q) != 0;
                    mismatches += std::memcmp(&q, &listed_values[at], sizeof q) != 0;
                    mismatches += std::memcmp(g, &listed_gradient[12 * at], sizeof g) != 0;
                }
            }
            BOOST_TEST_CONTEXT("targets " << setup << ", " << name) {
                BOOST_TEST(mismatches == 0u);
                BOOST_TEST(std::memcmp(batch.data(), single.data(), batch.size() * sizeof(double)) == 0);
            }
        }
    }
}

BOOST_AUTO_TEST_CASE(an_element_ideal_in_its_metric_rates_one) {
    BOOST_TEST(from_metric().metric("mean_ratio") == "shape_size");
    // The regular tetrahedron of edge 1 mapped by F: ideal in M = (F F^T)^-1, whatever its turn.
    const double f[3][3] = {{2.0, 0.3, 0.0}, {0.0, 0.5, 0.1}, {0.2, 0.0, 0.7}};
    pv::Mesh tet = regular_tet(1.0, 0.4);
    for (std::size_t v = 0; v < 12; v += 3) {
        const double x[3] = {tet.coordinates()[v], tet.coordinates()[v + 1], tet.coordinates()[v + 2]};
        for (int i = 0; i < 3; ++i) tet.coordinates()[v + i] = f[i][0] * x[0] + f[i][1] * x[1] + f[i][2] * x[2];
    }
    double ff[3][3] = {}, m[3][3];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            for (int k = 0; k < 3; ++k) ff[i][j] += f[i][k] * f[j][k];
    const double det = ff[0][0] * (ff[1][1] * ff[2][2] - ff[1][2] * ff[2][1]) - ff[0][1] * (ff[1][0] * ff[2][2] - ff[1][2] * ff[2][0]) +
                       ff[0][2] * (ff[1][0] * ff[2][1] - ff[1][1] * ff[2][0]);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            const int r0 = (j + 1) % 3, r1 = (j + 2) % 3, c0 = (i + 1) % 3, c1 = (i + 2) % 3;
            m[i][j] = (ff[r0][c0] * ff[r1][c1] - ff[r0][c1] * ff[r1][c0]) / det;
        }
    BOOST_TEST(rate("mean_ratio", tet)[0] < 0.5);
    tet.set_target_metrics(uniform_metric(tet, {m[0][0], m[1][1], m[2][2], m[0][1], m[1][2], m[0][2]}));
    pv::set_targets(tet, from_metric());
    for (const char* metric : {"mean_ratio", "shape_size"}) check_all_near(rate(metric, tet), 1.0, 1e-10);
    // Asking for edges half as long misses the size (not the shape); the metric scales with the mesh.
    tet.set_target_metrics(uniform_metric(tet, {4 * m[0][0], 4 * m[1][1], 4 * m[2][2], 4 * m[0][1], 4 * m[1][2], 4 * m[0][2]}));
    pv::set_targets(tet, from_metric());
    check_all_near(rate("mean_ratio", tet), 1.0, 1e-10);
    BOOST_TEST(rate("shape_size", tet)[0] < 0.9);
    tet.scale(-1);
    BOOST_TEST(tet.target_metrics()[0] == 16 * m[0][0]);

    // A 2 x 1 x 3 box: ideal (a cube's corners) in diag(1/4, 1, 1/9), every corner.
    pv::Mesh cell = box(2, 1, 3);
    cell.set_target_metrics(uniform_metric(cell, {0.25, 1.0, 1.0 / 9.0, 0.0, 0.0, 0.0}));
    pv::set_targets(cell, from_metric());
    for (const char* metric : {"mean_ratio", "shape_size"}) check_all_near(rate(metric, cell), 1.0, 1e-10);

    // Triangles in a tilted plane: the metric is read in the plane (here edges of 2 everywhere).
    const double c = std::cos(0.6), s = std::sin(0.6);
    std::vector<double> xyz;
    for (const auto& p : pv::ideal_cell(pv::CellType::Triangle)) xyz.insert(xyz.end(), {2 * p[0], 2 * c * p[1], 2 * s * p[1]});
    pv::Mesh triangle(pv::ElementKind::Triangle, xyz, {0, 1, 2});
    triangle.set_target_metrics(uniform_metric(triangle, {0.25, 0.25, 0.25, 0.0, 0.0, 0.0}));
    pv::set_targets(triangle, from_metric());
    for (const char* metric : {"mean_ratio", "shape_size"}) check_all_near(rate(metric, triangle), 1.0, 1e-10);
}

BOOST_AUTO_TEST_CASE(a_metric_that_is_missing_or_not_a_metric_is_refused) {
    pv::Mesh tet = regular_tet();
    BOOST_CHECK_THROW(pv::set_targets(tet, from_metric()), pv::OptionError);  // no metrics given
    BOOST_CHECK_THROW(tet.set_target_metrics(std::vector<double>(23, 1.0)), pv::MeshError);
    std::vector<double> metric = uniform_metric(tet, {1, 1, 1, 0, 0, 0});
    metric[6 * 2 + 3] = 2.0;  // xy > sqrt(xx yy): not positive definite
    BOOST_CHECK_EXCEPTION(tet.set_target_metrics(metric), pv::MeshError,
                          [](const pv::MeshError& e) { return std::string(e.what()).find("vertex 2") != std::string::npos; });
    metric[6 * 2 + 3] = std::nan("");
    BOOST_CHECK_THROW(tet.set_target_metrics(metric), pv::MeshError);
    tet.set_target_metrics(uniform_metric(tet, {1, 1, 1, 0, 0, 0}));
    pv::TargetOptions partly = from_metric();
    partly.aspect = pv::TargetSource::Input;  // size, aspect and orientation come together
    BOOST_CHECK_THROW(pv::set_targets(tet, partly), pv::OptionError);
    // In a plane the metric must be positive definite there.
    pv::Mesh triangle(pv::ElementKind::Triangle, {0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 2});
    triangle.set_target_metrics(uniform_metric(triangle, {1, 0, 1, 0, 0, 0}));  // nothing along y
    BOOST_CHECK_EXCEPTION(pv::set_targets(triangle, from_metric()), pv::MeshError,
                          [](const pv::MeshError& e) { return std::string(e.what()).find("element 0") != std::string::npos; });
}

BOOST_AUTO_TEST_CASE(scaling_the_mesh_scales_its_target_sizes_exactly) {
    pv::Mesh tets = random_tets(8, 9);
    pv::set_targets(tets, pv::TargetOptions::from("size"));
    const std::vector<double> volumes(tets.target_volumes().begin(), tets.target_volumes().end());
    std::vector<double> xyz(tets.coordinates().begin(), tets.coordinates().end());
    for (double& x : xyz) x *= 1.1;
    const auto before = rate("shape_size", tets, xyz);
    tets.scale(-5);
    for (std::size_t e = 0; e < volumes.size(); ++e) BOOST_TEST(tets.target_volumes()[e] == std::ldexp(volumes[e], -15));
    // The ratings see the same element at another scale: equal to rounding.
    for (double& x : xyz) x = std::ldexp(x, -5);
    const auto after = rate("shape_size", tets, xyz);
    for (std::size_t e = 0; e < before.size(); ++e) BOOST_TEST(std::abs(before[e] - after[e]) <= 1e-14);
}

BOOST_AUTO_TEST_CASE(bad_factors_and_bad_targets_are_refused_clearly) {
    BOOST_CHECK_EXCEPTION(pv::TargetOptions::from("size,colour"), pv::OptionError, [](const pv::OptionError& e) {
        const std::string what = e.what();
        return what.find("colour") != std::string::npos && what.find("size, orientation, aspect, skew") != std::string::npos;
    });
    pv::Mesh tet = regular_tet();
    pv::CornerMap mirror{};
    mirror[0][0] = mirror[1][1] = 1.0, mirror[2][2] = -1.0;
    BOOST_CHECK_THROW(tet.set_targets({mirror}, {1.0}), pv::MeshError);
    pv::CornerMap identity{};
    identity[0][0] = identity[1][1] = identity[2][2] = 1.0;
    BOOST_CHECK_THROW(tet.set_targets({identity}, {0.0}), pv::MeshError);
    BOOST_CHECK_THROW(tet.set_targets({identity, identity}, {1.0, 1.0}), pv::MeshError);
    // Metric roots: one per element, finite and orientation-preserving.
    BOOST_CHECK_THROW(tet.set_targets({identity}, {1.0}, {identity, identity}), pv::MeshError);
    BOOST_CHECK_EXCEPTION(tet.set_targets({identity}, {1.0}, {mirror}), pv::MeshError,
                          [](const pv::MeshError& e) { return std::string(e.what()).find("element 0") != std::string::npos; });
    pv::CornerMap not_finite = identity;
    not_finite[1][2] = std::nan("");
    BOOST_CHECK_THROW(tet.set_targets({identity}, {1.0}, {not_finite}), pv::MeshError);
    tet.set_targets({identity}, {1.0}, {identity});
    BOOST_TEST(tet.target_metric_roots().size() == 1u);
    tet.set_targets({identity}, {1.0});
    BOOST_TEST(tet.target_metric_roots().empty());
    BOOST_CHECK_THROW(tet.flip_elements(), pv::MeshError);
}

// A surface element's target is taken in its own input plane, where the metrics then rate it: a
// torus of triangles and a sphere of quadrilaterals, every factor kept, rate 1 everywhere, with
// the surface's normals set (as the solvers rate) or not (as a report after the run does).
BOOST_AUTO_TEST_CASE(a_surface_element_against_its_own_target_rates_one) {
    for (pv::Mesh mesh : {perturbed_torus(), sphere_of_quadrilaterals()}) {
        const auto ideal = rate("mean_ratio", mesh);
        BOOST_TEST(*std::min_element(ideal.begin(), ideal.end()) < 0.9);
        pv::set_targets(mesh, pv::TargetOptions::from("all"));
        BOOST_TEST(mesh.target_metric_roots().size() == static_cast<std::size_t>(mesh.num_elements()));
        for (const char* metric : {"mean_ratio", "aspect_ratio", "inverse_condition", "shape_size", "shape_size_orient"})
            BOOST_TEST_CONTEXT(metric << ", " << mesh.num_elements() << " elements") check_all_near(rate(metric, mesh), 1.0, 1e-12);
        mesh.clear_surface_normals();
        check_all_near(rate("shape_size_orient", mesh), 1.0, 1e-12);
    }
    // The shape alone kept (size and orientation ideal) is the shape metrics' 1 too.
    pv::Mesh sphere = sphere_of_quadrilaterals();
    pv::set_targets(sphere, pv::TargetOptions::from("aspect,skew"));
    check_all_near(rate("mean_ratio", sphere), 1.0, 1e-12);
}

// A surface element's kept size is its input area: the target's volume (its regular triangle's at
// the target's size) is the same multiple of it for every element.
BOOST_AUTO_TEST_CASE(a_surface_keeps_the_size_of_its_elements) {
    pv::Mesh torus = perturbed_torus();
    pv::set_targets(torus, pv::TargetOptions::from("size"));
    std::vector<double> area(static_cast<std::size_t>(torus.num_elements()));
    for (pv::ElementId e = 0; e < torus.num_elements(); ++e) {
        const auto c = torus.element(e);
        const pv::Vec3 a = torus.point(c[0]), b = torus.point(c[1]), d = torus.point(c[2]);
        const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
        area[static_cast<std::size_t>(e)] = 0.5 * std::hypot(u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]);
    }
    const double ratio = torus.target_volumes()[0] / area[0];
    for (std::size_t e = 0; e < area.size(); ++e)
        BOOST_TEST(std::abs(torus.target_volumes()[e] - ratio * area[e]) <= 1e-12 * area[e], "element " << e);
}

// Gradients through a surface element's map and root (with the neighbourhood's metric where the
// aspect is kept and the skew ideal) match central differences, the vertices moved off the input.
BOOST_AUTO_TEST_CASE(gradients_through_surface_targets_match_finite_differences) {
    std::mt19937 rng(4);
    std::normal_distribution<double> jitter(0.0, 0.02);
    for (const char* keep : {"size,aspect", "size,aspect,orientation", "all"})
        for (pv::Mesh mesh : {with_surface_normals(pv::test::torus(8, 6, 0.3)), sphere_of_quadrilaterals()}) {
            pv::set_targets(mesh, pv::TargetOptions::from(keep));
            std::vector<double> xyz(mesh.coordinates().begin(), mesh.coordinates().end());
            for (double& x : xyz) x += jitter(rng);
            for (const char* name : {"shape_size", "mean_ratio", "shape_size_orient"}) check_gradients(mesh, xyz, name);
        }
}

// A size field sizes a surface's elements as it sizes a plane's.
BOOST_AUTO_TEST_CASE(a_size_field_sizes_a_surface_s_elements) {
    pv::TargetOptions field = pv::TargetOptions::from("aspect");
    field.size = pv::TargetSource::Field;
    pv::Mesh torus = perturbed_torus();
    pv::Mesh plane(pv::ElementKind::Triangle, {0, 0, 0, 3, 0, 0, 0.5, 0.2, 0}, {0, 1, 2});
    for (pv::Mesh* mesh : {&torus, &plane}) {
        mesh->set_target_edge_lengths(std::vector<double>(static_cast<std::size_t>(mesh->num_vertices()), 0.25));
        pv::set_targets(*mesh, field);
    }
    for (double volume : torus.target_volumes()) BOOST_TEST(std::abs(volume - plane.target_volumes()[0]) <= 1e-15 * volume);
}

// What surfaces do not take yet is refused, saying what they do take.
BOOST_AUTO_TEST_CASE(a_surface_refuses_targets_from_a_reference_or_a_metric_field) {
    pv::Mesh torus = perturbed_torus();
    const pv::Mesh reference = torus;
    BOOST_CHECK_EXCEPTION(pv::set_targets(torus, pv::TargetOptions::from("all", pv::TargetSource::Reference), &reference),
                          pv::OptionError, [](const pv::OptionError& e) {
                              return std::string(e.what()).find("surface") != std::string::npos;
                          });
    std::vector<double> identity;
    for (pv::VertexId v = 0; v < torus.num_vertices(); ++v) identity.insert(identity.end(), {1.0, 1.0, 1.0, 0.0, 0.0, 0.0});
    torus.set_target_metrics(std::move(identity));
    pv::TargetOptions metric;
    metric.size = metric.aspect = metric.orientation = pv::TargetSource::Metric;
    BOOST_CHECK_THROW(pv::set_targets(torus, metric), pv::OptionError);
}

BOOST_AUTO_TEST_SUITE_END()
