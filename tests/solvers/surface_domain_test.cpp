// Analytic domains (SurfaceOptions::domain): a surface mesh's vertices, and a tet mesh's sliding
// boundary, stay on a sphere or cylinder exactly rather than on the input's facets; a planar
// mesh's plane is checked and changes nothing; a domain the mesh does not lie on, or one that
// does not go with the mesh, is refused naming what is wrong.
#include <boost/test/data/test_case.hpp>
#include <boost/test/unit_test.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <span>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "paloverde/core/error.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "paloverde/solvers/local_solver.hpp"
#include "support/surface_meshes.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;

namespace {

using pv::Vec3;
using pv::test::sphere;
constexpr double pi = std::numbers::pi;
const Vec3 kCentre{0.3, -0.2, 0.1};
constexpr double kRadius = 2.0;

Vec3 minus(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3 cross(const Vec3& a, const Vec3& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// An open tube of quadrilaterals about the axis through kCentre along (1, 1, 1): `around` x `along`
// cells of radius kRadius / 2 and length 3, made poorer along the tube as the sphere is.
pv::Mesh tube(int around, int along, double amount) {
    std::mt19937 random(5);
    const Vec3 axis{1.0 / std::sqrt(3.0), 1.0 / std::sqrt(3.0), 1.0 / std::sqrt(3.0)};
    const Vec3 u{1.0 / std::sqrt(2.0), -1.0 / std::sqrt(2.0), 0.0}, w = cross(axis, u);
    std::vector<double> xyz;
    for (int k = 0; k <= along; ++k)
        for (int i = 0; i < around; ++i) {
            const bool end = k == 0 || k == along;  // the open edges stay where they are
            const double s = 3.0 * (k + (end ? 0.0 : amount * pv::test::jitter(random))) / along;
            const double phi = 2 * pi * (i + (end ? 0.0 : amount * pv::test::jitter(random))) / around;
            const double c = 0.5 * kRadius * std::cos(phi), d = 0.5 * kRadius * std::sin(phi);
            for (int m = 0; m < 3; ++m) xyz.push_back(kCentre[m] + s * axis[m] + c * u[m] + d * w[m]);
        }
    std::vector<pv::CellType> types;
    std::vector<pv::VertexId> cells;
    auto id = [&](int k, int i) { return static_cast<pv::VertexId>(k * around + i % around); };
    for (int k = 0; k < along; ++k)
        for (int i = 0; i < around; ++i) {
            types.push_back(pv::CellType::Quadrilateral);
            cells.insert(cells.end(), {id(k, i), id(k, i + 1), id(k + 1, i + 1), id(k + 1, i)});
        }
    return pv::Mesh::from_cells(std::move(xyz), types, std::move(cells));
}

pv::SurfaceDomain sphere_domain() {
    pv::SurfaceDomain d;
    d.shape = pv::SurfaceDomain::Shape::Sphere;
    d.point = kCentre;
    d.radius = kRadius;
    return d;
}

// The largest distance of a vertex from the domain, over its radius (or 1 for a plane).
double off_domain(const pv::Mesh& mesh, const pv::SurfaceDomain& domain) {
    double off = 0.0;
    for (pv::VertexId v = 0; v < mesh.num_vertices(); ++v) off = std::max(off, domain.distance(mesh.point(v)));
    return off / (domain.shape == pv::SurfaceDomain::Shape::Plane ? 1.0 : domain.radius);
}

// Elements whose normal points into the domain's centre or axis (all face outward in the input).
int facing_in(const pv::Mesh& mesh, const pv::SurfaceDomain& domain) {
    int count = 0;
    for (pv::ElementId e = 0; e < mesh.num_elements(); ++e) {
        const auto c = mesh.element(e);
        const Vec3 a = mesh.point(c[0]), b = mesh.point(c[1]), d = mesh.point(c[2]);
        const Vec3 centroid{(a[0] + b[0] + d[0]) / 3, (a[1] + b[1] + d[1]) / 3, (a[2] + b[2] + d[2]) / 3};
        count += dot(cross(minus(b, a), minus(d, a)), domain.normal(centroid)) <= 0.0;
    }
    return count;
}

template <class Options>
Options on(const pv::SurfaceDomain& domain) {
    Options options;
    options.threads = 1;
    options.surface.domain = domain;
    return options;
}

pv::Summary improve(const std::string& solver, pv::Mesh& mesh, const pv::SurfaceDomain& domain) {
    if (solver == "global") return pv::GlobalSolver(on<pv::GlobalSolverOptions>(domain)).improve(mesh);
    auto options = on<pv::LocalSolverOptions>(domain);
    options.termination.max_iterations = 40;
    return pv::LocalSolver(options).improve(mesh);
}

// A planar mesh of triangles in the plane z = x / 2 + 1/4, its inner vertices jittered.
pv::Mesh tilted_square() {
    std::vector<double> xyz;
    std::vector<pv::VertexId> triangles;
    std::mt19937 random(3);
    constexpr int k = 8;
    for (int j = 0; j <= k; ++j)
        for (int i = 0; i <= k; ++i) {
            const bool inside = i > 0 && j > 0 && i < k && j < k;
            const double x = (i + (inside ? 0.3 * pv::test::jitter(random) : 0.0)) / k,
                         y = (j + (inside ? 0.3 * pv::test::jitter(random) : 0.0)) / k;
            xyz.insert(xyz.end(), {x, y, 0.5 * x + 0.25});
        }
    for (int j = 0; j < k; ++j)
        for (int i = 0; i < k; ++i) {
            const auto a = static_cast<pv::VertexId>(j * (k + 1) + i);
            triangles.insert(triangles.end(), {a, a + 1, a + k + 2, a, a + k + 2, a + k + 1});
        }
    return pv::Mesh(pv::ElementKind::Triangle, std::move(xyz), std::move(triangles));
}

// FNV-1a over the coordinates' bytes: equal only for the same doubles.
std::uint64_t hash_of(std::span<const double> xyz) {
    std::uint64_t h = 14695981039346656037ull;
    for (double c : xyz) {
        unsigned char bytes[sizeof c];
        std::memcpy(bytes, &c, sizeof c);
        for (unsigned char b : bytes) h = (h ^ b) * 1099511628211ull;
    }
    return h;
}

}  // namespace

BOOST_AUTO_TEST_SUITE(surface_domain)

// A coarse sphere made poorer along itself: on the sphere domain every vertex ends on the sphere
// to rounding, none turns over and the worst triangle rises half way back to the regular mesh's;
// on the mesh's own triangles (no domain) the moved vertices end on the facets, off the sphere.
BOOST_DATA_TEST_CASE(a_sphere_keeps_its_vertices_on_the_sphere, boost::unit_test::data::make({"global", "local"}), solver) {
    const pv::Mesh regular = sphere(16, 10, 0.0, kCentre, kRadius), input = sphere(16, 10, 0.3, kCentre, kRadius);
    const pv::SurfaceDomain domain = sphere_domain();
    BOOST_REQUIRE(off_domain(input, domain) < 1e-15);
    BOOST_REQUIRE(facing_in(input, domain) == 0);
    pv::Mesh mesh = input;
    const pv::Summary summary = improve(solver, mesh, domain);
    BOOST_TEST_MESSAGE(summary.brief_report());
    BOOST_TEST(summary.success());
    BOOST_TEST(off_domain(mesh, domain) < 1e-15);
    BOOST_TEST(facing_in(mesh, domain) == 0);
    pv::Mesh unperturbed = regular;  // its worst, in the solvers' own measure
    const double regular_worst = pv::GlobalSolver(on<pv::GlobalSolverOptions>(domain)).improve(unperturbed).worst_before;
    BOOST_TEST(summary.worst_after >= summary.worst_before + 0.5 * (regular_worst - summary.worst_before));
    BOOST_REQUIRE(summary.boundary.has_value());
    BOOST_TEST(summary.boundary->largest_distance < 1e-15 * kRadius);  // measured against the sphere

    pv::Mesh on_facets = input;
    improve(solver, on_facets, pv::SurfaceDomain{});
    BOOST_TEST(off_domain(on_facets, domain) > 1e-4);
}

// An open tube of quadrilaterals on a cylinder: every vertex ends on the cylinder to rounding,
// its two open rims (fixed, as a reader fixes an outline) exactly where they were, none turned.
BOOST_AUTO_TEST_CASE(a_tube_keeps_its_vertices_on_the_cylinder) {
    pv::Mesh input = tube(24, 12, 0.3);
    std::vector<std::uint8_t> rims(static_cast<std::size_t>(input.num_vertices()), 0);
    std::fill_n(rims.begin(), 24, 1);
    std::fill_n(rims.end() - 24, 24, 1);
    input.set_fixed(rims);  // as a file's reader fixes the outline
    pv::SurfaceDomain domain;
    domain.shape = pv::SurfaceDomain::Shape::Cylinder;
    domain.point = kCentre;
    domain.direction = {2.0, 2.0, 2.0};
    domain.radius = kRadius / 2;
    BOOST_REQUIRE(off_domain(input, domain) < 1e-14);
    pv::Mesh mesh = input;
    const pv::Summary summary = improve("global", mesh, domain);
    BOOST_TEST_MESSAGE(summary.brief_report());
    BOOST_TEST(summary.success());
    BOOST_TEST(summary.worst_after > summary.worst_before + 0.1);
    BOOST_TEST(off_domain(mesh, domain) < 1e-14);
    BOOST_TEST(facing_in(mesh, domain) == 0);
    for (pv::VertexId v = 0; v < 24; ++v) {
        BOOST_TEST(mesh.point(v) == input.point(v));
        BOOST_TEST(mesh.point(input.num_vertices() - 1 - v) == input.point(input.num_vertices() - 1 - v));
    }
}

// A tetrahedral ball whose boundary slides: on the sphere domain its boundary vertices end on the
// sphere; without it they end on the input's boundary triangles.
BOOST_AUTO_TEST_CASE(a_tet_ball_slides_on_its_sphere) {
    const pv::Mesh input = pv::read_mesh(pv::test::shared_data("mesquite/tets/flat-tet-sphere.vtk")).mesh;
    pv::SurfaceDomain domain;
    domain.shape = pv::SurfaceDomain::Shape::Sphere;
    domain.radius = 5.0;
    auto options = on<pv::LocalSolverOptions>(domain);
    options.boundary = pv::LocalSolverOptions::Boundary::Slide;
    options.termination.max_iterations = 6;
    pv::Mesh mesh = input;
    const pv::Summary summary = pv::LocalSolver(options).improve(mesh);
    BOOST_TEST_MESSAGE(summary.brief_report());
    BOOST_TEST(summary.success());
    BOOST_REQUIRE(summary.boundary.has_value());
    BOOST_TEST(summary.boundary->moved > 0);
    double off = 0.0;
    for (pv::VertexId v = 0; v < mesh.num_vertices(); ++v)
        if (std::abs(std::hypot(input.point(v)[0], input.point(v)[1], input.point(v)[2]) - 5.0) < 1e-6)
            off = std::max(off, domain.distance(mesh.point(v)));
    BOOST_TEST(off < 1e-8);  // the file's boundary is on the sphere to 7e-10
}

// A planar mesh in a tilted plane: its plane as the domain changes nothing, bit for bit; another
// plane, a sphere, a domain on a tet mesh whose boundary is fixed, a sphere the surface is not
// on and a domain without a radius are refused, naming the vertex or the field.
BOOST_AUTO_TEST_CASE(domains_that_do_not_fit_are_refused) {
    const pv::Mesh input = tilted_square();
    BOOST_REQUIRE(input.is_planar());
    pv::SurfaceDomain plane;
    plane.shape = pv::SurfaceDomain::Shape::Plane;
    plane.point = {0.0, 0.0, 0.25};
    plane.direction = {-0.5, 0.0, 1.0};
    pv::Mesh free_mesh = input, on_plane = input;
    improve("global", free_mesh, pv::SurfaceDomain{});
    improve("global", on_plane, plane);
    BOOST_TEST(std::vector<double>(on_plane.coordinates().begin(), on_plane.coordinates().end()) ==
                   std::vector<double>(free_mesh.coordinates().begin(), free_mesh.coordinates().end()),
               boost::test_tools::per_element());

    auto refused = [](pv::Mesh mesh, const pv::SurfaceDomain& domain, const std::string& words) {
        try {
            improve("global", mesh, domain);
        } catch (const pv::Error& e) {
            BOOST_TEST(std::string(e.what()).find(words) != std::string::npos, e.what());
            return;
        }
        BOOST_ERROR("no error: expected one saying '" + words + "'");
    };
    pv::SurfaceDomain other = plane;
    other.point = {0.0, 0.0, 0.5};
    refused(input, other, "off the plane");
    refused(input, sphere_domain(), "sphere is a domain for surface meshes");
    refused(pv::read_mesh(pv::test::shared_data("mesquite/tets/tire.vtk")).mesh, sphere_domain(), "boundary: slide");
    pv::SurfaceDomain larger = sphere_domain();
    larger.radius = 2.5;
    refused(sphere(8, 6, 0.0, kCentre, kRadius), larger, "lies 0.5");
    pv::SurfaceDomain flat = sphere_domain();
    flat.radius = 0.0;
    BOOST_CHECK_THROW(pv::GlobalSolver(on<pv::GlobalSolverOptions>(flat)), pv::OptionError);
}

// Planar meshes do not take the surfaces' path: a planar triangle mesh in a tilted plane and a
// shared planar mesh are smoothed by both solvers to the very coordinates they had before (hashes
// of the results, bit for bit; a change to planar smoothing that is meant updates them). The
// command line's results on these and other planar meshes were compared by hand with those of the
// commit before surface meshes were smoothed (docs/surfaces.md).
BOOST_DATA_TEST_CASE(planar_meshes_are_smoothed_as_before_surfaces,
                     boost::unit_test::data::make({"global", "local"}) * boost::unit_test::data::make({0, 1}), solver, which) {
    pv::Mesh mesh = which == 0 ? tilted_square() : pv::read_mesh(pv::test::shared_data("mesquite/tris/horseshoe.vtk")).mesh;
    BOOST_REQUIRE(mesh.is_planar());
    improve(solver, mesh, pv::SurfaceDomain{});
    const std::uint64_t expected[2][2] = {{10177187697036529528ull, 773925202846960635ull},
                                          {13550463711065524843ull, 13608774603244712129ull}};
    BOOST_TEST(hash_of(mesh.coordinates()) == expected[std::string(solver) == "global" ? 0 : 1][which]);
}

BOOST_AUTO_TEST_SUITE_END()
