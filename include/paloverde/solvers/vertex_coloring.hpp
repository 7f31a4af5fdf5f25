#pragma once
// Colors of the free vertices such that no two free vertices of one element share a color: the
// vertices of one color can then move at the same time (Freitag, Jones & Plassmann), each seeing
// its neighbours standing still.
#include <span>
#include <vector>

#include "paloverde/mesh/simplex_mesh.hpp"

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

VertexColoring color_vertices(const SimplexMesh& mesh, ColoringOrder order = ColoringOrder::SmallestLast);

// Whether every free vertex has a color in [0, count), every fixed vertex -1, and no element
// holds two free vertices of the same color.
bool is_proper_coloring(const SimplexMesh& mesh, const VertexColoring& coloring);

}  // namespace paloverde
