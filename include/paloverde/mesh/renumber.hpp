#pragma once
// Renumbering for locality: solvers stream over elements and gather their corners, which is
// 4-5x faster when neighbouring elements have neighbouring vertex ids (reverse Cuthill-McKee).
// The user's numbering is kept for output by mapping back through `old_vertex`.
#include <span>
#include <vector>

#include "paloverde/mesh/mesh.hpp"

namespace paloverde {

struct Renumbering {
    std::vector<VertexId> old_vertex;    // new id -> original id
    std::vector<ElementId> old_element;  // new id -> original id
};

// Vertices in reverse Cuthill-McKee order; elements sorted by `last_group` (elements flagged 1
// go after all others) and then by their smallest new vertex id.
Renumbering locality_order(const Mesh& mesh, std::span<const std::uint8_t> last_group = {});
// The vertex order alone (new id -> original id), for callers that order the elements themselves.
std::vector<VertexId> locality_vertex_order(const Mesh& mesh);

// A copy of the mesh with its vertices and elements in the new order (Mesh::permute: every field
// follows).
Mesh renumbered(const Mesh& mesh, const Renumbering& order);

// The vertex-to-vertex graph (compressed rows, sorted neighbours, no self loops).
struct VertexGraph {
    std::vector<std::int64_t> offsets;
    std::vector<VertexId> neighbours;
};
VertexGraph vertex_graph(const Mesh& mesh);
// With `cell_edges`, a mesh with cells lists only its cells' edges (no face or body diagonal of
// a hexahedron): the neighbours whose distance is the local edge length.
VertexGraph vertex_graph(const Mesh& mesh, bool cell_edges);

// The canonical element order, the same however a mesh is numbered or split: each element's
// position when all are sorted by their sorted vertex keys (`vertex_key` per vertex: canonical or
// global ids).
std::vector<GlobalId> canonical_element_positions(const Mesh& mesh, std::span<const GlobalId> vertex_key);

}  // namespace paloverde
