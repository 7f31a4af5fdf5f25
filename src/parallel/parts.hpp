#pragma once
// One rank's part as plain arrays: what rank 0 sends each rank when it splits a mesh, and what a
// piece file holds; DistributedMesh::assemble() moves them into the part's mesh.
#include <cstdint>
#include <span>
#include <vector>

#include "paloverde/mesh/mesh.hpp"

namespace paloverde::parallel {

// The pieces of one rank's part, as rank 0 sends them or a piece file holds them. A mesh with
// cells sends its cells (connectivity stays empty): the part's elements are their corners, in
// from_cells order, and element_order holds each corner's canonical position.
struct PartArrays {
    std::vector<double> coordinates;
    std::vector<std::uint8_t> fixed;
    std::vector<std::int64_t> canonical;  // per vertex
    std::vector<std::int32_t> owner;      // per vertex
    std::vector<std::int32_t> connectivity;
    std::vector<std::int64_t> element_order;
    std::vector<std::uint8_t> cell_types;  // CellType
    std::vector<std::int32_t> cell_connectivity;
    std::vector<std::int64_t> cell_order;
    std::vector<double> reference;  // the reference coordinates (morphing), 3 per vertex; empty: none
    std::vector<double> edge_lengths;  // the target edge lengths (a size field), 1 per vertex; empty: none
    std::vector<double> metrics;       // the target metrics (a metric field), 6 per vertex; empty: none
};

// The part's mesh from its arrays (moved out of them), with its fixed flags and global ids.
Mesh part_mesh(PartArrays& arrays, ElementKind kind);
// Per cell of a part's mesh (per element without cells): counted by `rank`, the owner of its
// vertex with the smallest canonical id (the first in local order: vertices are sorted by it).
std::vector<std::uint8_t> counted_cells(const Mesh& mesh, std::span<const std::int32_t> owner, int rank);
// Per element: its cell's flag.
std::vector<std::uint8_t> per_element(const Mesh& mesh, std::span<const std::uint8_t> per_cell);

// Canonical keys, `width` values each, flat: an element's sorted global ids padded with -1 to 4
// (and its corner map, for a mesh with cells: corners of two cells may share their vertices); a
// cell's sorted global ids padded with -1 to 8, then its type. Sorted keys give the canonical
// order, the same however the mesh is numbered or split.
constexpr int kCellKeyWidth = kMaxCellCorners + 1;
void append_element_key(const Mesh& mesh, ElementId e, int width, std::vector<std::int64_t>& keys);
void append_cell_key(CellType type, std::span<const VertexId> cell, std::span<const GlobalId> ids,
                     std::vector<std::int64_t>& keys);
// Each key's position among the distinct keys in sorted order (copies of one element or cell,
// held by several parts, share it); `distinct` is set to their number.
std::vector<std::int64_t> key_positions(const std::vector<std::int64_t>& keys, int width, std::int64_t& distinct);

}  // namespace paloverde::parallel
