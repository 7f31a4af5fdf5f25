#pragma once
// Splitting a mesh's vertices among processes, and what such a split costs in communication.
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "paloverde/mesh/mesh.hpp"

namespace paloverde {

// METIS k-way partition of the vertex graph (one graph edge per mesh edge): the edge cut is
// minimized, with METIS_OPTION_MINCONN so that each part has few neighbouring parts, and a fixed
// seed so that the same mesh always splits the same way. Returns the part of each vertex.
// Throws OptionError when parts < 1 or parts > the number of vertices.
std::vector<int> partition_vertices(const Mesh& mesh, int parts);

// Greedy edge coloring of the process graph in breadth-first order from part 0: each edge gets
// the smallest color not yet used at either end. `edges` lists each pair (a < b) once; returns
// one color per edge.
std::vector<int> color_process_graph(int parts, std::span<const std::pair<int, int>> edges);

// The communication a partition implies, as the paper's Table 2 counts it.
struct PartitionStatistics {
    int parts = 0;
    std::int64_t ghost_copies = 0;       // ghost vertices summed over the parts: values received per exchange
    std::int64_t shared_vertices = 0;    // owned vertices that some other part holds as a ghost
    std::int64_t process_edges = 0;      // pairs of parts that exchange: messages per exchange, each way
    int colors = 0;                      // of the greedy edge coloring: the exchange's rounds
    int max_neighbours = 0;              // most partners of one part
    std::int64_t largest_part_elements = 0;  // elements (cells) held, owned and ghost, by the largest part
};
// A mesh with cells is split into whole cells, as DistributedMesh splits it.
PartitionStatistics partition_statistics(const Mesh& mesh, std::span<const int> part, int parts);

}  // namespace paloverde
