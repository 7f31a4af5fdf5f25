#pragma once
// One rank's part as plain arrays: what rank 0 sends each rank when it splits a mesh, and what a
// piece file holds; DistributedMesh::assemble() moves them into the part's mesh.
#include <cstdint>
#include <vector>

namespace paloverde::parallel {

// The pieces of one rank's part, as rank 0 sends them or a piece file holds them.
struct PartArrays {
    std::vector<double> coordinates;
    std::vector<std::uint8_t> fixed;
    std::vector<std::int64_t> canonical;  // per vertex
    std::vector<std::int32_t> owner;      // per vertex
    std::vector<std::int32_t> connectivity;
    std::vector<std::int64_t> element_order;
};

}  // namespace paloverde::parallel
