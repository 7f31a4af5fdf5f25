// The orientation convention of an input, told by the total signed volume: mirrored copies of
// tangled shared meshes, a tangle where most elements are inverted, a total of zero, triangles.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <boost/test/unit_test.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <utility>
#include <vector>

#include "paloverde/mesh/orientation.hpp"
#include "support/solver_checks.hpp"

namespace pv = paloverde;
using pv::test::mirrored;
using pv::ElementKind;
using pv::OrientationMode;
using pv::VertexId;

namespace {

// A flat slab [0,1]^2 x [0,0.1] whose boundary is triangulated (the top face finely, n x n
// squares) and coned to one interior vertex; that vertex then moved above the top face, which
// inverts the 2 n^2 tets on the top face: most of them, while the total volume stays the slab's.
pv::Mesh slab_with_its_centre_above(int n) {
    const double h = 0.1;
    std::vector<double> xyz = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};  // bottom corners 0..3
    auto top = [&](int i, int j) { return static_cast<VertexId>(4 + j * (n + 1) + i); };
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) xyz.insert(xyz.end(), {double(i) / n, double(j) / n, h});
    const auto centre = static_cast<VertexId>(xyz.size() / 3);
    xyz.insert(xyz.end(), {0.5, 0.5, h / 2});
    std::vector<std::array<VertexId, 3>> faces = {{0, 1, 2}, {0, 2, 3}};
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            faces.push_back({top(i, j), top(i + 1, j), top(i + 1, j + 1)});
            faces.push_back({top(i, j), top(i + 1, j + 1), top(i, j + 1)});
        }
    // Each side: its two bottom corners and the top points above them, as a fan from corner a.
    auto side = [&](VertexId a, VertexId b, auto above) {
        faces.push_back({a, b, above(n)});
        for (int s = 0; s < n; ++s) faces.push_back({a, above(s + 1), above(s)});
    };
    side(0, 1, [&](int s) { return top(s, 0); });
    side(1, 2, [&](int s) { return top(n, s); });
    side(3, 2, [&](int s) { return top(s, n); });
    side(0, 3, [&](int s) { return top(0, s); });
    std::vector<VertexId> tets;
    for (const auto& f : faces) tets.insert(tets.end(), {f[0], f[1], f[2], centre});
    pv::Mesh mesh(ElementKind::Tetrahedron, xyz, tets);
    for (pv::ElementId e = 0; e < mesh.num_elements(); ++e)
        if (pv::element_orientation(mesh, mesh.coordinates(), e) < 0) std::swap(tets[4 * e + 1], tets[4 * e + 2]);
    xyz[3 * static_cast<std::size_t>(centre) + 2] = 2 * h;
    return pv::Mesh(ElementKind::Tetrahedron, std::move(xyz), std::move(tets));
}

}  // namespace

BOOST_AUTO_TEST_SUITE(orientation)

// A tangled mesh (interior vertices moved by up to an edge length) and its mirror: the mirror is
// flipped back to the very same elements, with the same inverted count, at any scale.
BOOST_AUTO_TEST_CASE(a_mirrored_tangled_mesh_is_flipped_back) {
    const auto tangled = pv::test::perturbed_shared_mesh("mesquite/tets/tire.vtk", 0.3, 1);
    const auto counts = pv::count_orientations(tangled);
    for (const double scale : {1.0, 1e-300, 1e300}) {
        BOOST_TEST_CONTEXT("scale " << scale) {
            auto mirror = mirrored(tangled, 2, 3, scale);
            // Read as it is, every element's orientation is reversed.
            BOOST_TEST(pv::count_orientations(mirror).inverted ==
                       tangled.num_elements() - counts.inverted - counts.degenerate);
            const auto d = pv::orient(mirror, OrientationMode::Auto);
            BOOST_TEST(d.flipped);
            BOOST_TEST(d.sign == -1);
            BOOST_TEST(d.share < -0.5);
            BOOST_TEST(mirror.elements_flipped());
            BOOST_TEST(std::equal(mirror.connectivity().begin(), mirror.connectivity().end(),
                                  tangled.connectivity().begin(), tangled.connectivity().end()));
            BOOST_TEST(pv::count_orientations(mirror).inverted == counts.inverted);
        }
    }
    // Corners 1 and 2 swapped (as several tools write tets): flipped too, the same count.
    auto other = mirrored(tangled, 1, 2);
    BOOST_TEST(pv::orient(other, OrientationMode::Auto).flipped);
    BOOST_TEST(pv::count_orientations(other).inverted == counts.inverted);
    // The original is kept as it is.
    auto same = tangled;
    const auto kept = pv::orient(same, OrientationMode::Auto);
    BOOST_TEST(!kept.flipped);
    BOOST_TEST(kept.sign == 1);
    BOOST_TEST(!same.elements_flipped());
}

BOOST_AUTO_TEST_CASE(forced_modes_do_what_they_say) {
    const auto valid = pv::test::shared_mesh("mesquite/tets/tire.vtk");
    auto as_is = mirrored(valid, 2, 3);
    const auto d = pv::orient(as_is, OrientationMode::AsIs);
    BOOST_TEST(!d.flipped);
    BOOST_TEST(d.sign == -1);  // still measured and reported
    BOOST_TEST(pv::count_orientations(as_is).inverted == valid.num_elements());
    auto flipped = valid;
    BOOST_TEST(pv::orient(flipped, OrientationMode::Flipped).flipped);
    BOOST_TEST(flipped.elements_flipped());
    BOOST_TEST(pv::count_orientations(flipped).inverted == valid.num_elements());
}

// Where a majority count would call the file mirrored, the total volume does not.
BOOST_AUTO_TEST_CASE(the_total_decides_where_most_elements_are_inverted) {
    auto slab = slab_with_its_centre_above(4);
    const auto inverted = pv::count_orientations(slab).inverted;
    BOOST_TEST(inverted == 32);
    BOOST_TEST(2 * inverted > slab.num_elements());
    auto mirror = mirrored(slab, 2, 3);
    const auto d = pv::orient(slab, OrientationMode::Auto);
    BOOST_TEST(!d.flipped);
    BOOST_TEST(d.sign == 1);
    BOOST_TEST(pv::orient(mirror, OrientationMode::Auto).flipped);
    BOOST_TEST(pv::count_orientations(mirror).inverted == 32);
}

// A total of zero (a tet and its mirror image) says nothing: the file's order is kept.
BOOST_AUTO_TEST_CASE(a_zero_total_keeps_the_files_order) {
    pv::Mesh pair(ElementKind::Tetrahedron, {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1},
                  {0, 1, 2, 3, 0, 1, 2, 4});
    BOOST_TEST(pv::count_orientations(pair).inverted == 1);
    const auto d = pv::orient(pair, OrientationMode::Auto);
    BOOST_TEST(d.sign == 0);
    BOOST_TEST(!d.flipped);
    BOOST_TEST(d.describe(ElementKind::Tetrahedron).find("cannot be told") != std::string::npos);
    BOOST_TEST(pv::orient(pair, OrientationMode::Flipped).flipped);
}

// A planar triangle mesh is oriented about its own area-weighted normal, which turns with a
// mirror: auto keeps it, and the inverted count is the same either way. A curved surface has no
// orientation at all.
BOOST_AUTO_TEST_CASE(triangles_follow_their_plane_normal) {
    const auto tangled = pv::test::perturbed_shared_mesh("mesquite/tris/tri_20258.vtk", 0.3, 2);
    BOOST_TEST_REQUIRE(tangled.is_planar());
    auto mirror = mirrored(tangled, 1, 2);
    const auto d = pv::orient(mirror, OrientationMode::Auto);
    BOOST_TEST(!d.flipped);
    BOOST_TEST(d.sign == 1);
    BOOST_TEST(pv::count_orientations(mirror).inverted == pv::count_orientations(tangled).inverted);
    BOOST_TEST(mirror.plane_normal()[2] == -tangled.plane_normal()[2]);
    pv::Mesh bent(ElementKind::Triangle, {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, 1, 2, 0, 3, 1});
    BOOST_TEST_REQUIRE(!bent.is_planar());
    const auto none = pv::orient(bent, OrientationMode::Auto);
    BOOST_TEST(!none.oriented);
    BOOST_TEST(!none.flipped);
}

// The floating-point filter in front of the exact predicate answers only where it is sure: tets
// flat to within an ulp or two, and tets far from unit scale (where products underflow or
// overflow), get the exact predicate's sign.
BOOST_AUTO_TEST_CASE(element_orientation_is_the_exact_sign_near_flat_and_far_from_unit_scale_one_by_one_or_in_blocks) {
    using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
    // Coordinates on a grid of 2^-20 and plane weights in eighths: corner 3 lies exactly on the
    // plane of the others until nudged.
    std::mt19937_64 random(7);
    std::uniform_int_distribution<int> grid(-(1 << 20), 1 << 20), eighths(-8, 8);
    auto unit = [&](auto& random) { return std::ldexp(grid(random), -20); };
    std::vector<double> xyz;
    std::vector<VertexId> tets;
    for (int t = 0; t < 2000; ++t) {
        // Corner 3 on the plane of the others, then nudged by an ulp or a few, or not at all.
        double p[4][3];
        for (int i = 0; i < 3; ++i)
            for (double& c : p[i]) c = unit(random);
        const double a = eighths(random) / 8.0, b = eighths(random) / 8.0;
        for (int c = 0; c < 3; ++c) p[3][c] = p[0][c] + a * (p[1][c] - p[0][c]) + b * (p[2][c] - p[0][c]);
        for (int nudge = t % 5; nudge > 0; --nudge) p[3][2] = std::nextafter(p[3][2], nudge % 2 ? 2.0 : -2.0);
        const double scale = std::ldexp(1.0, (t % 7 - 3) * 300);  // 2^-900 .. 2^900
        for (const auto& corner : p)
            for (double c : corner) xyz.push_back(c * scale);
        for (int i = 0; i < 4; ++i) tets.push_back(static_cast<VertexId>(4 * t + i));
    }
    const pv::Mesh mesh(ElementKind::Tetrahedron, xyz, tets);
    auto point = [&](VertexId v) { return Kernel::Point_3(xyz[3 * v], xyz[3 * v + 1], xyz[3 * v + 2]); };
    int flat = 0;
    for (pv::ElementId e = 0; e < mesh.num_elements(); ++e) {
        const auto c = mesh.element(e);
        const int exact = static_cast<int>(CGAL::orientation(point(c[0]), point(c[1]), point(c[2]), point(c[3])));
        flat += exact == 0;
        BOOST_TEST(pv::element_orientation(mesh, mesh.coordinates(), e) == exact, "tet " << e);
    }
    BOOST_TEST(flat > 0);  // some stayed exactly flat: the filter had to pass them on
    // The blocks of element_orientations, over ranges that start and end inside a block.
    for (const auto& [first, last] : {std::pair<pv::ElementId, pv::ElementId>{0, 2000}, {3, 1000}, {77, 78}, {1999, 2000}}) {
        std::vector<std::int8_t> batch(static_cast<std::size_t>(last - first), 9);
        pv::element_orientations(mesh, mesh.coordinates(), first, last, batch.data());
        for (pv::ElementId e = first; e < last; ++e)
            BOOST_TEST(batch[static_cast<std::size_t>(e - first)] == pv::element_orientation(mesh, mesh.coordinates(), e),
                       "tet " << e << " of " << first << ".." << last);
    }
}

BOOST_AUTO_TEST_SUITE_END()
