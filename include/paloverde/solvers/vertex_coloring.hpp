#pragma once
// Colors of the free vertices such that no two free vertices of one element share a color: the
// vertices of one color can then move at the same time (Freitag, Jones & Plassmann), each seeing
// its neighbours standing still.
#include <cstdint>
#include <span>
#include <vector>

#include "paloverde/mesh/mesh.hpp"
#include "paloverde/parallel/mesh_part.hpp"

namespace paloverde {

enum class ColoringOrder {
    Greedy,       // first fit in vertex id order
    SmallestLast  // first fit in smallest-last order: usually fewer colors
};

struct VertexColoring {
    std::vector<int> color;  // per vertex; -1 for fixed vertices
    int count = 0;           // colors used: 0 .. count-1
    // The free vertices of each color, in increasing id order.
    std::vector<std::vector<VertexId>> classes() const;
};

// The whole mesh: first fit in `order`. A part of a distributed mesh (collective): a coloring of
// the whole distributed mesh, `order` aside (Jones & Plassmann: in rounds, each free vertex whose
// uncolored neighbours all have lower priority takes the smallest color its neighbours do not
// have; priorities are a hash of the global id). Every rank learns the colors of its ghosts; the
// colors do not depend on the number of ranks. `count` is global.
VertexColoring color_vertices(MeshPart part, ColoringOrder order = ColoringOrder::SmallestLast);

// Whether every free vertex has a color in [0, count), every fixed vertex -1, and no element
// holds two free vertices of the same color.
bool is_proper_coloring(const Mesh& mesh, const VertexColoring& coloring);

}  // namespace paloverde
