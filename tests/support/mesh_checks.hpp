#pragma once
// Whether two meshes hold the same data, field by field and bit for bit: for the tests of what
// renumbers a mesh and must give it back as it was.
#include <boost/test/unit_test.hpp>
#include <algorithm>

#include "paloverde/mesh/mesh.hpp"

namespace paloverde::test {

// Every field of a and b (with `coordinates` false, all but the coordinates), the marks too.
inline void check_same_mesh(const Mesh& a, const Mesh& b, bool coordinates = true) {
    auto same = [](auto x, auto y) { return x.size() == y.size() && std::equal(x.begin(), x.end(), y.begin()); };
    if (coordinates) BOOST_TEST(same(a.coordinates(), b.coordinates()));
    BOOST_TEST(a.coordinates().size() == b.coordinates().size());
    BOOST_TEST(same(a.connectivity(), b.connectivity()));
    BOOST_TEST(same(a.vertex_element_offsets(), b.vertex_element_offsets()));
    BOOST_TEST(same(a.vertex_elements(), b.vertex_elements()));
    BOOST_TEST(same(a.fixed(), b.fixed()));
    for (VertexId v = 0; v < a.num_vertices(); ++v) BOOST_TEST(a.degrees_of_freedom(v) == b.degrees_of_freedom(v));
    BOOST_TEST(same(a.global_ids(), b.global_ids()));
    BOOST_TEST(same(a.cell_types(), b.cell_types()));
    BOOST_TEST(same(a.cell_offsets(), b.cell_offsets()));
    BOOST_TEST(same(a.cell_connectivity(), b.cell_connectivity()));
    BOOST_TEST(same(a.element_cells(), b.element_cells()));
    BOOST_TEST(same(a.corner_maps(), b.corner_maps()));
    BOOST_TEST(same(a.target_maps(), b.target_maps()));
    BOOST_TEST(same(a.target_volumes(), b.target_volumes()));
    BOOST_TEST(same(a.target_metric_roots(), b.target_metric_roots()));
    BOOST_TEST(same(a.reference_coordinates(), b.reference_coordinates()));
    BOOST_TEST(same(a.target_edge_lengths(), b.target_edge_lengths()));
    BOOST_TEST(same(a.target_metrics(), b.target_metrics()));
    BOOST_TEST(same(a.surface_normals(), b.surface_normals()));
    BOOST_TEST((a.is_planar() == b.is_planar() && a.plane_normal() == b.plane_normal()));
    BOOST_TEST((a.elements_flipped() == b.elements_flipped() && a.locality_ordered() == b.locality_ordered()));
}

}  // namespace paloverde::test
