// Surface meshes in 3D (triangles that do not lie in one plane), smoothed by the global and local
// solvers with every vertex sliding on the input surface: the vertices end on the input's
// triangles, creases and corners stay, nothing turns over, the worst triangle rises, and what is
// not done yet is refused.
#include <boost/test/data/test_case.hpp>
#include <boost/test/unit_test.hpp>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <map>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "paloverde/core/error.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/metrics/targets.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "paloverde/solvers/laplace_solver.hpp"
#include "paloverde/solvers/local_solver.hpp"
#include "support/surface_meshes.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;

namespace {

using pv::Vec3;
using pv::test::jitter;
using pv::test::torus;
Vec3 point(const pv::Mesh& mesh, pv::VertexId v) { return mesh.point(v); }



Vec3 normal_of(const pv::Mesh& mesh, pv::ElementId e) {
    const auto c = mesh.element(e);
    const Vec3 a = point(mesh, c[0]), b = point(mesh, c[1]), d = point(mesh, c[2]);
    const Vec3 u{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w{d[0] - a[0], d[1] - a[1], d[2] - a[2]};
    return {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
}

// The worst triangle's mean ratio, 4 sqrt(3) area / the sum of its squared edges (1: equilateral).
double worst_mean_ratio(const pv::Mesh& mesh) {
    double worst = 1.0;
    for (pv::ElementId e = 0; e < mesh.num_elements(); ++e) {
        const auto c = mesh.element(e);
        double squares = 0.0;
        for (int k = 0; k < 3; ++k) {
            const Vec3 a = point(mesh, c[k]), b = point(mesh, c[(k + 1) % 3]);
            squares += (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]);
        }
        const Vec3 n = normal_of(mesh, e);
        worst = std::min(worst, 2.0 * std::sqrt(3.0) * std::hypot(n[0], n[1], n[2]) / squares);
    }
    return worst;
}

// Triangles whose normal in `out` does not point the way it did in `in`.
int turned_over(const pv::Mesh& in, const pv::Mesh& out) {
    int count = 0;
    for (pv::ElementId e = 0; e < in.num_elements(); ++e) {
        const Vec3 a = normal_of(in, e), b = normal_of(out, e);
        count += a[0] * b[0] + a[1] * b[1] + a[2] * b[2] <= 0.0;
    }
    return count;
}

double diagonal(const pv::Mesh& mesh) {
    Vec3 low = point(mesh, 0), high = low;
    for (pv::VertexId v = 0; v < mesh.num_vertices(); ++v)
        for (int k = 0; k < 3; ++k) {
            low[k] = std::min(low[k], point(mesh, v)[k]);
            high[k] = std::max(high[k], point(mesh, v)[k]);
        }
    return std::hypot(high[0] - low[0], high[1] - low[1], high[2] - low[2]);
}

// The largest distance of a vertex of `out` to the triangles of `in` (its cells cut into
// triangles), over in's diagonal.
double largest_distance(const pv::Mesh& in, const pv::Mesh& out) {
    std::vector<Kernel::Triangle_3> triangles;
    auto at = [](const Vec3& p) { return Kernel::Point_3(p[0], p[1], p[2]); };
    for (pv::ElementId e = 0; e < in.num_cells(); ++e) {
        const auto c = in.cell(e);  // a quadrilateral cut as Paloverde cuts it: from its first corner
        for (std::size_t k = 2; k < c.size(); ++k)
            triangles.emplace_back(at(point(in, c[0])), at(point(in, c[k - 1])), at(point(in, c[k])));
    }
    double largest = 0.0;
    for (pv::VertexId v = 0; v < out.num_vertices(); ++v) {
        double nearest = INFINITY;
        for (const auto& t : triangles) nearest = std::min(nearest, CGAL::squared_distance(at(point(out, v)), t));
        largest = std::max(largest, std::sqrt(nearest));
    }
    return largest / diagonal(in);
}

// The surface of the unit cube, k x k squares a face cut into triangles facing outward. With
// `amount` > 0 the vertices inside a face move in its plane, those on an edge along it, by up to
// that fraction of a square; the corners stay.
pv::Mesh cube_surface(int k, double amount) {
    std::map<std::array<int, 3>, pv::VertexId> ids;
    std::vector<double> xyz;
    std::mt19937 random(3);
    auto id = [&](std::array<int, 3> g) {
        const auto [it, added] = ids.try_emplace(g, static_cast<pv::VertexId>(ids.size()));
        if (added)
            for (int c = 0; c < 3; ++c) {
                const bool on_side = g[c] == 0 || g[c] == k;
                xyz.push_back((g[c] + (on_side ? 0.0 : amount * jitter(random))) / k);
            }
        return it->second;
    };
    std::vector<pv::VertexId> triangles;
    for (int axis = 0; axis < 3; ++axis)
        for (int side : {0, k}) {
            const int a = (axis + 1) % 3, b = (axis + 2) % 3;
            for (int s = 0; s < k; ++s)
                for (int t = 0; t < k; ++t) {
                    auto at = [&](int ds, int dt) {
                        std::array<int, 3> g{};
                        g[axis] = side;
                        g[a] = s + ds;
                        g[b] = t + dt;
                        return id(g);
                    };
                    // (a, b, axis) is right-handed: counterclockwise in (a, b) faces +axis.
                    std::array<pv::VertexId, 4> q{at(0, 0), at(1, 0), at(1, 1), at(0, 1)};
                    if (side == 0) std::swap(q[1], q[3]);
                    triangles.insert(triangles.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
                }
        }
    return pv::Mesh(pv::ElementKind::Triangle, std::move(xyz), std::move(triangles));
}

// The smallest corner scaled Jacobian of a report's cells (-1 without).
double worst_scaled_jacobian(const pv::QualityReport& report) {
    for (const auto& type : report.by_type)
        for (const auto& [metric, value] : type.worst)
            if (metric == "scaled_jacobian") return value;
    return -1.0;
}

// A cube_surface() improved: a face vertex keeps its face's plane, an edge vertex its edge's two
// coordinates, a corner its place, exactly. Returns the edge vertices that slid along their edge.
int check_on_the_cube(const pv::Mesh& input, const pv::Mesh& mesh) {
    int moved_on_edges = 0;
    for (pv::VertexId v = 0; v < mesh.num_vertices(); ++v) {
        const Vec3 p = point(input, v), q = point(mesh, v);
        int sides = 0;
        for (int c = 0; c < 3; ++c)
            if (p[c] == 0.0 || p[c] == 1.0) {
                ++sides;
                BOOST_TEST(q[c] == p[c], "vertex " << v << " left its face");
            }
        if (sides == 2 && q != p) ++moved_on_edges;
        if (sides == 3) BOOST_TEST(q == p, "corner " << v << " moved");
    }
    return moved_on_edges;
}

pv::GlobalSolverOptions one_thread() {
    pv::GlobalSolverOptions options;
    options.threads = 1;
    return options;
}

// The mesh improved by the named solver ("global" or "local") with its default options, on one
// thread.
pv::Summary improve_by(const std::string& solver, pv::Mesh& mesh) {
    if (solver == "global") return pv::GlobalSolver(one_thread()).improve(mesh);
    pv::LocalSolverOptions local;
    local.threads = 1;
    return pv::LocalSolver(local).improve(mesh);
}

// A tangled torus `input` (tests/support/surface_meshes.hpp) improved into `mesh`: the solver saw
// its turned-over elements, untangled them, and kept every vertex on the input's cells.
void check_untangled_on_the_torus(const pv::Mesh& input, const pv::Mesh& mesh, const pv::Summary& summary) {
    BOOST_TEST_MESSAGE(summary.brief_report());
    BOOST_TEST(summary.success());
    BOOST_TEST(summary.before.inverted > 0);  // the solvers see what the input turned over
    BOOST_TEST(summary.after.inverted == 0);
    BOOST_TEST(summary.untangle_iterations > 0);
    BOOST_TEST(pv::test::turned_over_on_torus(mesh) == 0);
    BOOST_TEST(largest_distance(input, mesh) < 1e-9);
    BOOST_REQUIRE(summary.boundary.has_value());
    BOOST_TEST(summary.boundary->largest_distance < 1e-9);
    BOOST_TEST(!mesh.has_surface_normals());
}

}  // namespace

BOOST_AUTO_TEST_SUITE(surface)

// A torus made poorer along itself, smoothed by either solver: every vertex ends on the poorer
// torus's triangles, none turns over, and the worst triangle rises at least half way back to the
// unperturbed mesh's. Its slivers fold their neighbours by more than the feature angle: the
// creases they make must not hold them (BoundarySurface takes a triangle creased on every side,
// and a short crease with a loose end, for a fold on surface meshes). Slow (tests/CMakeLists.txt):
// the sanitizers see both solvers on a torus in
// a_tangled_torus_of_quadrilaterals_with_targets_is_untangled.
BOOST_TEST_DECORATOR(*boost::unit_test::label("slow"))
BOOST_DATA_TEST_CASE(a_torus_is_mended_on_its_own_surface, boost::unit_test::data::make({"global", "local"}), solver) {
    const pv::Mesh regular = torus(32, 16, 0.0), input = torus(32, 16, 0.35);
    pv::Mesh mesh = input;
    pv::LocalSolverOptions local;
    local.threads = 1;
    local.termination.max_iterations = 40;  // its sweeps creep up after the first few
    const pv::Summary summary = std::string(solver) == "global" ? pv::GlobalSolver(one_thread()).improve(mesh)
                                                                : pv::LocalSolver(local).improve(mesh);
    BOOST_TEST_MESSAGE(summary.brief_report());
    BOOST_TEST(summary.success());
    BOOST_TEST(turned_over(input, mesh) == 0);
    BOOST_TEST(largest_distance(input, mesh) < 1e-9);
    const double before = worst_mean_ratio(input), after = worst_mean_ratio(mesh);
    BOOST_TEST(before < 0.6 * worst_mean_ratio(regular));  // the input is poorer
    BOOST_TEST(after >= before + 0.5 * (worst_mean_ratio(regular) - before));
    BOOST_REQUIRE(summary.boundary.has_value());
    BOOST_TEST(summary.boundary->moved > 0);
    BOOST_TEST(summary.boundary->largest_distance < 1e-9);
    BOOST_TEST(!mesh.has_surface_normals());  // the run's own, cleared when it ends
}

// The cube's creases and corners stay (check_on_the_cube); the worst triangle rises.
BOOST_AUTO_TEST_CASE(a_cube_surface_keeps_its_creases_and_corners) {
    constexpr int k = 6;
    const pv::Mesh input = cube_surface(k, 0.4);
    pv::Mesh mesh = input;
    const pv::Summary summary = pv::GlobalSolver(one_thread()).improve(mesh);
    BOOST_TEST_MESSAGE(summary.brief_report());
    BOOST_TEST(summary.success());
    BOOST_TEST(turned_over(input, mesh) == 0);
    BOOST_TEST(worst_mean_ratio(mesh) > worst_mean_ratio(input) + 0.1);
    BOOST_TEST(check_on_the_cube(input, mesh) > 0);  // the edge vertices slid along the creases
}

// An open surface (a saddle): its outline is held by the default fixed flags; the rest slides.
// Its jitter turns one triangle over (seen from above, the saddle being a graph over the plane):
// it is turned back.
BOOST_AUTO_TEST_CASE(an_open_surface_keeps_its_outline) {
    constexpr int k = 12;
    std::mt19937 random(5);
    std::vector<double> xyz;
    for (int i = 0; i <= k; ++i)
        for (int j = 0; j <= k; ++j) {
            const bool outline = i == 0 || j == 0 || i == k || j == k;
            const double x = (i + (outline ? 0.0 : 0.4 * jitter(random))) / k - 0.5;
            const double y = (j + (outline ? 0.0 : 0.4 * jitter(random))) / k - 0.5;
            xyz.insert(xyz.end(), {x, y, x * x - y * y});
        }
    std::vector<pv::VertexId> triangles;
    for (int i = 0; i < k; ++i)
        for (int j = 0; j < k; ++j) {
            const pv::VertexId a = i * (k + 1) + j, b = a + k + 1;
            triangles.insert(triangles.end(), {a, b, b + 1, a, b + 1, a + 1});
        }
    pv::Mesh input(pv::ElementKind::Triangle, std::move(xyz), std::move(triangles));
    std::vector<std::uint8_t> outline(static_cast<std::size_t>(input.num_vertices()));
    for (int i = 0; i <= k; ++i)
        for (int j = 0; j <= k; ++j) outline[static_cast<std::size_t>(i * (k + 1) + j)] = i == 0 || j == 0 || i == k || j == k;
    input.set_fixed(outline);  // as a file's reader fixes it
    pv::Mesh mesh = input;
    const pv::Summary summary = pv::GlobalSolver(one_thread()).improve(mesh);
    BOOST_TEST(summary.success());
    auto facing_down = [](const pv::Mesh& m) {
        int count = 0;
        for (pv::ElementId e = 0; e < m.num_elements(); ++e) count += normal_of(m, e)[2] <= 0.0;
        return count;
    };
    BOOST_TEST(facing_down(input) == 1);
    BOOST_TEST(summary.before.inverted == 1);
    BOOST_TEST(facing_down(mesh) == 0);
    BOOST_TEST(largest_distance(input, mesh) < 1e-9);
    BOOST_TEST(worst_mean_ratio(mesh) > worst_mean_ratio(input));
    for (pv::VertexId v = 0; v < mesh.num_vertices(); ++v)
        if (outline[static_cast<std::size_t>(v)]) BOOST_TEST(point(mesh, v) == point(input, v));
}

// Mesquite's patch of quadrilaterals on a sphere, its outline sliding: every vertex stays on the
// input's quadrilaterals (cut along their first diagonal, which is no crease however much it
// folds), no corner turns over, the worst corner rises and the scaled Jacobian does not fall.
BOOST_AUTO_TEST_CASE(a_sphere_of_quadrilaterals_is_mended_on_itself) {
    const pv::Mesh input = pv::read_mesh(pv::test::shared_data("mesquite/hexes/sph-10-zsquare.vtk")).mesh;
    pv::Mesh mesh = input;
    pv::GlobalSolverOptions options = one_thread();
    options.boundary = pv::GlobalSolverOptions::Boundary::Slide;
    const pv::Summary summary = pv::GlobalSolver(options).improve(mesh);
    BOOST_TEST_MESSAGE(summary.brief_report());
    BOOST_TEST(summary.success());
    BOOST_TEST(summary.worst_after > 2.0 * summary.worst_before);  // 0.399 -> 0.826
    BOOST_TEST(turned_over(input, mesh) == 0);
    BOOST_TEST(largest_distance(input, mesh) < 1e-9);
    BOOST_TEST(worst_scaled_jacobian(summary.after) >= worst_scaled_jacobian(summary.before));
    BOOST_TEST(worst_scaled_jacobian(summary.before) > 0.8);  // the guard reads it
}

// A torus of quadrilaterals with one ring of them cut into triangles (a mixed surface), made
// poorer along itself: every vertex on the input's cells, nothing turned over, the worst corner
// and the minimum scaled Jacobian raised. Slow (tests/CMakeLists.txt): the sanitizers see
// surfaces of triangles and of quadrilaterals in a_cube_surface_keeps_its_creases_and_corners
// and a_sphere_of_quadrilaterals_is_mended_on_itself.
BOOST_AUTO_TEST_CASE(a_mixed_surface_is_mended_on_itself, *boost::unit_test::label("slow")) {
    const pv::Mesh points = torus(24, 12, 0.25);  // its vertices; its cells are made here
    std::vector<pv::CellType> types;
    std::vector<pv::VertexId> cells;
    auto id = [](int i, int j) { return static_cast<pv::VertexId>((i % 24) * 12 + j % 12); };
    for (int i = 0; i < 24; ++i)
        for (int j = 0; j < 12; ++j) {
            if (i == 0) {
                types.insert(types.end(), 2, pv::CellType::Triangle);
                cells.insert(cells.end(), {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j), id(i + 1, j + 1), id(i, j + 1)});
            } else {
                types.push_back(pv::CellType::Quadrilateral);
                cells.insert(cells.end(), {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
            }
        }
    const pv::Mesh input = pv::Mesh::from_cells({points.coordinates().begin(), points.coordinates().end()}, types,
                                                std::move(cells));
    BOOST_REQUIRE(input.has_cells());
    pv::Mesh mesh = input;
    const pv::Summary summary = pv::GlobalSolver(one_thread()).improve(mesh);
    BOOST_TEST_MESSAGE(summary.brief_report());
    BOOST_TEST(summary.success());
    BOOST_TEST(summary.worst_after > summary.worst_before + 0.1);
    BOOST_TEST(turned_over(input, mesh) == 0);
    BOOST_TEST(largest_distance(input, mesh) < 1e-9);
}

// A cylinder of quadrilaterals graded along its axis (rows from a sixth of their width high to
// twice it), made poorer along itself (its rows' mean heights within 9.4% of the unperturbed
// ones). With size and aspect kept, both solvers raise the minimum scaled Jacobian and leave every
// row within 12%; the ideal targets pull the cells toward squares and the thin rows to more than
// twice their height.
BOOST_DATA_TEST_CASE(a_graded_cylinder_keeps_its_rows_with_size_and_aspect_kept, boost::unit_test::data::make({"global", "local"}),
                     solver) {
    const int around = 24, along = 10;
    const double first = 0.045, growth = 1.35;
    const std::vector<double> rings = pv::test::graded_rings(along, first, growth);
    const pv::Mesh input = pv::test::graded_cylinder(around, along, first, growth, 0.3);
    // The largest change of a row's mean height from the unperturbed cylinder's.
    auto largest_row_change = [&](const pv::Mesh& mesh) {
        double largest = 0.0;
        for (int j = 0; j < along; ++j) {
            double sum = 0.0;
            for (int i = 0; i < around; ++i)
                sum += point(mesh, static_cast<pv::VertexId>((j + 1) * around + i))[2] - point(mesh, static_cast<pv::VertexId>(j * around + i))[2];
            const double wanted = rings[static_cast<std::size_t>(j) + 1] - rings[static_cast<std::size_t>(j)];
            largest = std::max(largest, std::abs(sum / around - wanted) / wanted);
        }
        return largest;
    };
    struct Result {
        double row_change, jacobian_before, jacobian_after;
    };
    auto improve = [&](const char* keep) {
        pv::Mesh mesh = input;
        const pv::TargetOptions targets = pv::TargetOptions::from(keep);
        pv::set_targets(mesh, targets);
        pv::Summary summary;
        if (std::string(solver) == "global") {
            pv::GlobalSolverOptions options = one_thread();
            options.shape_metric = targets.metric(options.shape_metric);
            summary = pv::GlobalSolver(options).improve(mesh);
        } else {
            pv::LocalSolverOptions options;
            options.threads = 1;
            options.termination.max_iterations = 40;
            options.metric = targets.metric(options.metric);
            summary = pv::LocalSolver(options).improve(mesh);
        }
        BOOST_TEST_MESSAGE(solver << " --keep '" << keep << "': " << summary.brief_report() << "; rows within "
                                  << largest_row_change(mesh) << "; scaled Jacobian " << worst_scaled_jacobian(summary.before)
                                  << " -> " << worst_scaled_jacobian(summary.after));
        BOOST_TEST(summary.success());
        BOOST_TEST(turned_over(input, mesh) == 0);
        BOOST_TEST(largest_distance(input, mesh) < 1e-9);
        return Result{largest_row_change(mesh), worst_scaled_jacobian(summary.before), worst_scaled_jacobian(summary.after)};
    };
    BOOST_TEST(largest_row_change(input) < 0.1);
    const Result kept = improve("size,aspect"), ideal = improve("");
    BOOST_TEST(kept.row_change < 0.12);
    BOOST_TEST(ideal.row_change > 1.0);
    BOOST_TEST(kept.jacobian_after > kept.jacobian_before + 0.1);
}

// A torus tangled along itself (vertices slid past their neighbours, two triangles turned over
// at each), smoothed by either solver: the turned-over triangles are rated inverted, untangled
// with every vertex sliding on the tangled input's triangles, and then improved. Slow
// (tests/CMakeLists.txt): the sanitizers see a tangled torus untangled by both solvers in
// a_tangled_torus_of_quadrilaterals_with_targets_is_untangled, tangled triangles in
// a_tangle_beside_creases_leaves_them_in_place.
BOOST_TEST_DECORATOR(*boost::unit_test::label("slow"))
BOOST_DATA_TEST_CASE(a_tangled_torus_is_untangled_on_its_surface, boost::unit_test::data::make({"global", "local"}),
                     solver) {
    const pv::Mesh input = pv::test::tangled_torus(32, 16);
    BOOST_TEST(pv::test::turned_over_on_torus(input) == 8);
    pv::Mesh mesh = input;
    const pv::Summary summary = improve_by(solver, mesh);
    BOOST_TEST(summary.before.inverted == 8);
    check_untangled_on_the_torus(input, mesh, summary);
}

// The same on a torus of quadrilaterals: the two cells at each crossed edge fold, and come back.
// Slow (tests/CMakeLists.txt): the sanitizers see it with targets, in the next case.
BOOST_TEST_DECORATOR(*boost::unit_test::label("slow"))
BOOST_DATA_TEST_CASE(a_tangled_torus_of_quadrilaterals_is_untangled, boost::unit_test::data::make({"global", "local"}),
                     solver) {
    const pv::Mesh input = pv::test::tangled_torus(32, 16, true);
    BOOST_REQUIRE(input.has_cells());
    BOOST_TEST(pv::test::turned_over_on_torus(input) > 0);
    pv::Mesh mesh = input;
    check_untangled_on_the_torus(input, mesh, improve_by(solver, mesh));
}

// With the quadrilaterals' aspect kept (the command line's default on a surface of cells), each
// target lies in its element's own input plane: a turned-over cell's is turned to the surface's
// side, so that it too is rated inverted and turned back.
BOOST_DATA_TEST_CASE(a_tangled_torus_of_quadrilaterals_with_targets_is_untangled, boost::unit_test::data::make({"global", "local"}),
                     solver) {
    const pv::Mesh input = pv::test::tangled_torus(32, 16, true);
    pv::Mesh mesh = input;
    pv::set_targets(mesh, pv::TargetOptions::from("aspect"));
    const pv::Summary summary = improve_by(solver, mesh);
    BOOST_TEST(summary.before.inverted > 0);
    check_untangled_on_the_torus(input, mesh, summary);
}

// A vertex inside a face of the cube slid past its neighbour in the face's plane: the tangle is
// undone in that plane while every crease and corner stays exactly where it was.
BOOST_DATA_TEST_CASE(a_tangle_beside_creases_leaves_them_in_place, boost::unit_test::data::make({"global", "local"}),
                     solver) {
    constexpr int k = 6;
    pv::Mesh input = cube_surface(k, 0.0);
    std::vector<double> xyz(input.coordinates().begin(), input.coordinates().end());
    for (pv::VertexId v = 0; v < input.num_vertices(); ++v) {
        double* p = &xyz[3 * static_cast<std::size_t>(v)];
        if (p[0] == 2.0 / k && p[1] == 3.0 / k && p[2] == 1.0) p[0] = 3.5 / k;  // past (3, 3) on the top face
    }
    input = pv::Mesh(pv::ElementKind::Triangle, xyz, {input.connectivity().begin(), input.connectivity().end()});
    auto turned = [](const pv::Mesh& mesh) {  // triangles that face into the cube
        int count = 0;
        for (pv::ElementId e = 0; e < mesh.num_elements(); ++e) {
            const auto c = mesh.element(e);
            Vec3 centre{0, 0, 0};
            for (int i = 0; i < 3; ++i)
                for (int d = 0; d < 3; ++d) centre[d] += point(mesh, c[i])[d] / 3 - 1.0 / 6;
            const Vec3 n = normal_of(mesh, e);
            count += n[0] * centre[0] + n[1] * centre[1] + n[2] * centre[2] <= 0.0;
        }
        return count;
    };
    BOOST_TEST(turned(input) == 2);
    pv::Mesh mesh = input;
    const pv::Summary summary = improve_by(solver, mesh);
    BOOST_TEST_MESSAGE(summary.brief_report());
    BOOST_TEST(summary.success());
    BOOST_TEST(summary.before.inverted == 2);
    BOOST_TEST(turned(mesh) == 0);
    check_on_the_cube(input, mesh);
}

// A tangle that cannot be undone (its vertices fixed, or no untangling budget) is reported: the
// run says so, hands back its mesh with the fewest turned over, on the surface, and the command
// line exits with 1. Slow (tests/CMakeLists.txt): the sanitizers see surface untangling in
// a_tangle_beside_creases_leaves_them_in_place, and a tangle that cannot be undone reported in
// global_solver_test's an_inverted_tet_with_every_vertex_fixed_cannot_be_untangled.
BOOST_AUTO_TEST_CASE(a_tangle_that_cannot_be_undone_is_reported, *boost::unit_test::label("slow")) {
    const pv::Mesh tangled = pv::test::tangled_torus(32, 16);
    std::vector<std::uint8_t> fixed(static_cast<std::size_t>(tangled.num_vertices()), 0);
    for (const auto& [i, j] : pv::test::torus_slides(32, 16))
        for (int di = -1; di <= 2; ++di)
            for (int dj = -2; dj <= 2; ++dj) fixed[static_cast<std::size_t>(((i + di + 32) % 32) * 16 + (j + dj + 16) % 16)] = 1;
    pv::Mesh mesh = tangled;
    mesh.set_fixed(fixed);
    const pv::Summary summary = pv::GlobalSolver(one_thread()).improve(mesh);
    BOOST_TEST_MESSAGE(summary.brief_report());
    BOOST_TEST(!summary.success());
    BOOST_TEST((summary.reason == pv::TerminationReason::CannotUntangle));
    BOOST_TEST(summary.after.inverted == 8);
    BOOST_TEST(largest_distance(tangled, mesh) < 1e-9);

    pv::GlobalSolverOptions short_of_budget = one_thread();
    short_of_budget.untangle_termination.max_iterations = 1;
    pv::Mesh cut_short = tangled;
    const pv::Summary stopped = pv::GlobalSolver(short_of_budget).improve(cut_short);
    BOOST_TEST_MESSAGE(stopped.brief_report());
    BOOST_TEST((stopped.reason == pv::TerminationReason::CannotUntangle));
    BOOST_TEST(stopped.after.inverted > 0);
    BOOST_TEST(stopped.after.inverted <= 8);
    BOOST_TEST(largest_distance(tangled, cut_short) < 1e-9);

    const pv::test::ScratchDir dir("surface_tangle_held");
    const pv::Field flags{"fixed", 1, std::vector<double>(fixed.begin(), fixed.end())};
    pv::write_mesh(dir / "held.vtk", tangled, {}, std::span<const pv::Field>(&flags, 1));
    for (const char* method : {"global", "local"}) {
        const auto result = pv::test::run_cli("improve " + (dir / "held.vtk").string() + " -o " +
                                              (dir / "out.vtk").string() + " --method " + method);
        BOOST_TEST(result.exit_code == 1, result.output);
        BOOST_TEST(std::filesystem::exists(dir / "out.vtk"));
    }
}

// Three triangles on one edge: no surface to slide on. The command line names the file.
BOOST_AUTO_TEST_CASE(a_non_manifold_surface_is_refused) {
    pv::Mesh mesh(pv::ElementKind::Triangle, {0, 0, 0, 1, 0, 0, 0.5, 1, 0, 0.5, -1, 0, 0.5, 0, 1, 0.5, 0.5, 0.6},
                  {0, 1, 2, 1, 0, 3, 0, 1, 4, 0, 5, 1});
    BOOST_CHECK_EXCEPTION(pv::GlobalSolver(one_thread()).improve(mesh), pv::MeshError, [](const pv::MeshError& e) {
        return std::string(e.what()).find("not a manifold") != std::string::npos;
    });
    const pv::test::ScratchDir dir("surface_non_manifold");
    pv::write_mesh(dir / "fins.vtk", mesh);
    const auto result = pv::test::run_cli("improve " + (dir / "fins.vtk").string() + " -o " + (dir / "out.vtk").string());
    BOOST_TEST(result.exit_code != 0);
    BOOST_TEST(result.output.find("fins.vtk") != std::string::npos, result.output);
    BOOST_TEST(result.output.find("non-manifold") != std::string::npos, result.output);
}

// A tetrahedron's surface is all corners: the solvers move nothing; Laplace, which does not slide
// on surfaces, refuses it, and so does the global solver with Newton directions.
BOOST_AUTO_TEST_CASE(what_is_not_done_yet_is_refused) {
    const pv::Mesh input(pv::ElementKind::Triangle, {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3});
    const std::vector<double> before(input.coordinates().begin(), input.coordinates().end());
    pv::Mesh mesh = input;
    pv::GlobalSolver(one_thread()).improve(mesh);
    pv::LocalSolver().improve(mesh);
    const std::vector<double> after(mesh.coordinates().begin(), mesh.coordinates().end());
    BOOST_TEST(after == before, boost::test_tools::per_element());
    BOOST_CHECK_THROW(pv::LaplaceSolver().improve(mesh), pv::MeshError);
    pv::Mesh torus_mesh = torus(8, 6, 0.2);
    pv::GlobalSolverOptions newton = one_thread();
    newton.direction = pv::GlobalSolverOptions::Direction::Newton;
    BOOST_CHECK_THROW(pv::GlobalSolver(newton).improve(torus_mesh), pv::OptionError);
}

BOOST_AUTO_TEST_SUITE_END()
