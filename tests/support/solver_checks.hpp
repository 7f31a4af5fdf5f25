#pragma once
// What the solver tests share: the meshes they start from and the checks every solver passes.
#include <boost/test/unit_test.hpp>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "paloverde/core/error.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/orientation.hpp"
#include "paloverde/mesh/perturb.hpp"
#include "paloverde/solvers/summary.hpp"
#include "support/test_support.hpp"

namespace paloverde::test {

inline Mesh shared_mesh(const std::string& name, OrientationMode orientation = OrientationMode::Auto) {
    ReadOptions read;
    read.orientation = orientation;
    return read_mesh(shared_data(name), read).mesh;
}

// The same mesh with corners i and j of every element swapped, as a tool with the other
// orientation convention would write it (not marked flipped: what such a file holds), its
// coordinates times `scale`.
inline Mesh mirrored(const Mesh& mesh, int i = 2, int j = 3, double scale = 1.0) {
    std::vector<VertexId> connectivity(mesh.connectivity().begin(), mesh.connectivity().end());
    const auto k = static_cast<std::size_t>(mesh.corners());
    for (std::size_t first = 0; first < connectivity.size(); first += k)
        std::swap(connectivity[first + static_cast<std::size_t>(i)], connectivity[first + static_cast<std::size_t>(j)]);
    std::vector<double> xyz(mesh.coordinates().begin(), mesh.coordinates().end());
    for (double& x : xyz) x *= scale;
    Mesh out(mesh.kind(), std::move(xyz), std::move(connectivity));
    out.set_fixed(std::vector<std::uint8_t>(mesh.fixed().begin(), mesh.fixed().end()));
    return out;
}

// A shared mesh with `fraction` of its interior vertices moved by up to `amount` local edge
// lengths; requires that it came out tangled.
inline Mesh perturbed_shared_mesh(const std::string& name, double fraction, int seed, double amount = 1.0) {
    auto mesh = shared_mesh(name);
    PerturbOptions perturb;
    perturb.amount = amount;
    perturb.fraction = fraction;
    perturb.seed = static_cast<std::uint64_t>(seed);
    paloverde::perturb(mesh, perturb);
    BOOST_TEST_REQUIRE(count_orientations(mesh).inverted > 0);
    return mesh;
}

// Two tets: the second inverted with every vertex fixed, the first with a free, badly placed
// vertex that can still be improved.
inline Mesh frozen_inverted_tet() {
    Mesh mesh(ElementKind::Tetrahedron, {0, 0, 0, 1, 0, 0, 0, 1, 0, 0.1, 0.1, 0.05, 0, 0, 1},
              {0, 1, 2, 3, 0, 2, 1, 4});
    mesh.set_fixed({1, 1, 1, 0, 1});
    return mesh;
}

// Within a phase: the count of non-positive elements never rises; at an equal count the best
// worst quality never falls; every accepted global step raised its objective. Overall: no more
// inverted elements than the input, and no lower worst quality for a valid input.
inline void check_never_worse(const Summary& summary) {
    BOOST_TEST(summary.after.inverted <= summary.before.inverted);
    if (summary.before.inverted == 0) BOOST_TEST(summary.worst_after >= summary.worst_before);
    const auto& h = summary.history;
    for (std::size_t i = 1; i < h.size(); ++i) {
        if (h[i].phase != h[i - 1].phase) continue;
        BOOST_TEST(h[i].inverted <= h[i - 1].inverted);
        if (h[i].inverted == h[i - 1].inverted) BOOST_TEST(h[i].best_worst_quality >= h[i - 1].best_worst_quality);
        if (h[i].step > 0.0) BOOST_TEST(h[i].gain > 0.0);
    }
}

// Fixed vertices are exactly where they were.
inline void check_fixed_unchanged(const Mesh& mesh, const std::vector<double>& before) {
    for (VertexId v = 0; v < mesh.num_vertices(); ++v)
        if (mesh.fixed()[v])
            for (int c = 0; c < 3; ++c) BOOST_TEST(mesh.coordinates()[3 * v + c] == before[3 * v + c]);
}

// Constructing a solver from options changed by `change` throws an OptionError naming `word`.
template <class Solver, class Options, class Change>
void check_option_rejected(Change change, const std::string& word) {
    Options options;
    change(options);
    BOOST_CHECK_EXCEPTION(Solver{options}, OptionError, [&](const OptionError& e) {
        return std::string(e.what()).find(word) != std::string::npos;
    });
}

}  // namespace paloverde::test
