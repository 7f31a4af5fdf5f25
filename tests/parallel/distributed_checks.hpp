#pragma once
// What the tests of tests/parallel share: scattering a mesh over MPI_COMM_WORLD, comparing
// coordinates, and the global solver run serially and on the ranks.
#include <boost/test/unit_test.hpp>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <utility>

#include "paloverde/mesh/renumber.hpp"
#include "paloverde/parallel/distributed_mesh.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "support/solver_checks.hpp"
#include "world.hpp"

namespace paloverde::test {

inline DistributedMesh scatter(const Mesh& whole, ExchangeMode mode = ExchangeMode::Colored) {
    DistributeOptions options;
    options.exchange = mode;
    return DistributedMesh::scatter(MPI_COMM_WORLD, rank() == 0 ? &whole : nullptr, options);
}

// A file in a folder of this rank count's own (CTest may run the 2- and 4-rank entries at once).
inline std::filesystem::path scratch(const std::string& name) {
    auto dir = std::filesystem::temp_directory_path() / ("paloverde_pieces_" + std::to_string(ranks()));
    if (rank() == 0) std::filesystem::create_directories(dir);
    MPI_Barrier(MPI_COMM_WORLD);
    return dir / name;
}

// The largest coordinate difference, relative to the mesh's extent.
inline double relative_difference(const Mesh& a, const Mesh& b) {
    double extent = 0.0, difference = 0.0;
    for (std::size_t i = 0; i < a.coordinates().size(); ++i) {
        extent = std::max(extent, std::abs(a.coordinates()[i]));
        difference = std::max(difference, std::abs(a.coordinates()[i] - b.coordinates()[i]));
    }
    return difference / extent;
}

// gather_whole() of `input` scattered over the ranks, after each owner moved its vertices by 0.25
// along x (so that a ghost's stale copy would show). Rank 0 checks that every vertex comes at its
// global id (canonical order) with its owner's coordinates and fixed flag, and gets the whole
// mesh; the other ranks an empty one.
inline Mesh gathered_whole(const Mesh& input) {
    auto part = scatter(input);
    for (VertexId v = 0; v < part.mesh().num_vertices(); ++v)
        if (part.vertex_owner()[v] == rank()) part.mesh().coordinates()[3 * static_cast<std::size_t>(v)] += 0.25;
    Mesh whole = part.gather_whole();
    if (rank() != 0) {
        BOOST_TEST(whole.num_vertices() == 0);
        return whole;
    }
    const auto order = locality_order(input);
    BOOST_REQUIRE(whole.num_vertices() == input.num_vertices());
    long wrong = 0;
    for (VertexId v = 0; v < whole.num_vertices(); ++v) {
        const auto o = static_cast<std::size_t>(order.old_vertex[static_cast<std::size_t>(v)]);
        const auto w = 3 * static_cast<std::size_t>(v);
        wrong += whole.coordinates()[w] != input.coordinates()[3 * o] + 0.25 ||
                 whole.coordinates()[w + 1] != input.coordinates()[3 * o + 1] ||
                 whole.coordinates()[w + 2] != input.coordinates()[3 * o + 2] || whole.fixed()[v] != input.fixed()[o];
    }
    BOOST_TEST(wrong == 0);
    return whole;
}

// The global solver on `input`, serially and on the ranks: the distributed run must take the same
// steps to the same mesh, bit for bit, and never make things worse. Returns both summaries (and
// on rank 0 the distributed run's mesh in `result`, if given).
inline std::pair<Summary, Summary> serial_and_distributed(const Mesh& input, const GlobalSolverOptions& options,
                                                          Mesh* result = nullptr) {
    Mesh serial = input;
    const auto serial_summary = GlobalSolver(options).improve(serial);
    BOOST_TEST_MESSAGE("serial: " << serial_summary.brief_report());
    Mesh gathered = input;
    auto part = scatter(input);
    const auto summary = GlobalSolver(options).improve(part);
    part.gather_coordinates(rank() == 0 ? &gathered : nullptr);
    BOOST_TEST(summary.iterations == serial_summary.iterations);
    BOOST_TEST(summary.untangle_iterations == serial_summary.untangle_iterations);
    BOOST_TEST(summary.after.inverted == serial_summary.after.inverted);
    BOOST_TEST(summary.worst_after == serial_summary.worst_after);
    if (rank() == 0) {
        const double difference = relative_difference(gathered, serial);
        BOOST_TEST_MESSAGE(ranks() << " ranks: " << summary.brief_report() << "; relative difference " << difference);
        BOOST_TEST(difference == 0.0);
    }
    check_never_worse(summary);
    if (result) *result = std::move(gathered);
    return {serial_summary, summary};
}

}  // namespace paloverde::test
