#pragma once
// What the tests of sliding boundary vertices (boundary: slide) share, for every solver that
// slides: the meshes and the checks that the boundary stayed where it may be.
#include <boost/test/unit_test.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <string>
#include <utility>

#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/boundary_surface.hpp"
#include "paloverde/mesh/orientation.hpp"
#include "paloverde/solvers/summary.hpp"
#include "support/solver_checks.hpp"

namespace paloverde::test {

// The smallest quality of a metric over every element, boundary ones too.
inline double worst_of_all(const Summary& summary, const std::string& metric) { return summary.after.metric(metric)->all.min; }

#ifdef PALOVERDE_SOURCE_DIR
// The bundled example: a 6 x 6 x 6 cube of tets, tangled inside. Untangling keeps the boundary;
// the shape phase then slides it.
inline Mesh tangled_cube() {
    return read_mesh(std::filesystem::path(PALOVERDE_SOURCE_DIR) / "examples/data/tangled_cube.vtk").mesh;
}
#endif

// The run `slide` left `improved` valid, no worse than `input`, with every boundary vertex on the
// input's boundary triangulation to 1e-9 of the bounding-box diagonal, corners where they were,
// and the mesh's fixed flags its own again.
inline void check_on_the_input_boundary(const Mesh& input, const Mesh& improved, const Summary& slide) {
    const BoundarySurface surface(input);
    const double tolerance = 1e-9 * surface.bounding_box_diagonal();
    BOOST_TEST(slide.valid());
    check_never_worse(slide);
    BOOST_TEST(count_orientations(improved).inverted == 0);
    BOOST_TEST(count_orientations(improved).degenerate == 0);
    BOOST_REQUIRE(slide.boundary.has_value());
    BOOST_TEST(slide.boundary->largest_distance <= 1e-9);
    for (VertexId v = 0; v < input.num_vertices(); ++v) {
        if (surface.role(v) == BoundaryRole::Interior) continue;
        BOOST_TEST(surface.distance(improved.point(v)) <= tolerance, "vertex " << v);
        if (surface.role(v) == BoundaryRole::Corner)
            for (int c = 0; c < 3; ++c) BOOST_TEST(improved.point(v)[c] == input.point(v)[c]);
    }
    BOOST_TEST(std::equal(improved.fixed().begin(), improved.fixed().end(), input.fixed().begin()));
}

// An axis-aligned box mesh slid on its boundary: a face vertex keeps the coordinate of its face's
// plane, an edge vertex the two of its edge, a corner all three, to 1e-9 of the diagonal. Returns
// how many boundary vertices moved, by role (BoundaryRole as index).
inline std::array<int, 4> check_box_sides(const Mesh& input, const Mesh& improved) {
    const BoundarySurface surface(input);
    const double tolerance = 1e-9 * surface.bounding_box_diagonal();
    const auto x = improved.coordinates();
    const auto x0 = input.coordinates();
    // The box spans [lo, hi] in each coordinate: a vertex on the boundary has some at lo or hi.
    Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    for (VertexId v = 0; v < input.num_vertices(); ++v)
        for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], x0[3 * v + c]), hi[c] = std::max(hi[c], x0[3 * v + c]);
    std::array<int, 4> moved{};
    for (VertexId v = 0; v < input.num_vertices(); ++v) {
        const auto role = surface.role(v);
        if (role == BoundaryRole::Interior) continue;
        int on_side = 0;
        for (int c = 0; c < 3; ++c) {
            const bool side = std::abs(x0[3 * v + c] - lo[c]) <= tolerance || std::abs(x0[3 * v + c] - hi[c]) <= tolerance;
            if (!side) continue;
            ++on_side;
            BOOST_TEST(std::abs(x[3 * v + c] - x0[3 * v + c]) <= tolerance, "vertex " << v << " left its face");
        }
        BOOST_TEST(on_side == (role == BoundaryRole::Surface ? 1 : role == BoundaryRole::Curve ? 2 : 3));
        bool changed = false;
        for (int c = 0; c < 3; ++c) changed = changed || x[3 * v + c] != x0[3 * v + c];
        moved[static_cast<int>(role)] += changed ? 1 : 0;
    }
    return moved;
}

// The tangled cube slid (`slide`, leaving `improved`) against the boundary-fixed run `fixed`:
// on its boundary, faces flat, edges straight, corners in place, the volume kept, the worst
// element of all no lower; face and edge vertices moved.
inline void check_cube_slid(const Mesh& input, const Mesh& improved, const Summary& fixed,
                            const Summary& slide) {
    check_on_the_input_boundary(input, improved, slide);
    BOOST_TEST(slide.boundary->sliding == 210);  // 150 on the faces, 60 on the edges
    BOOST_TEST(std::abs(slide.boundary->volume_after - slide.boundary->volume_before) <= 1e-12 * slide.boundary->volume_before);
    BOOST_TEST(worst_of_all(slide, "aspect_ratio") >= worst_of_all(fixed, "aspect_ratio"));
    const auto moved = check_box_sides(input, improved);
    BOOST_TEST(moved[static_cast<int>(BoundaryRole::Surface)] > 0);
    BOOST_TEST(moved[static_cast<int>(BoundaryRole::Curve)] > 0);
    BOOST_TEST(moved[static_cast<int>(BoundaryRole::Corner)] == 0);
}

}  // namespace paloverde::test
