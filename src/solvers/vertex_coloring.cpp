#include "paloverde/solvers/vertex_coloring.hpp"

#include <algorithm>

#include "paloverde/mesh/renumber.hpp"

namespace paloverde {

std::vector<std::vector<VertexId>> VertexColoring::classes() const {
    std::vector<std::vector<VertexId>> out(static_cast<std::size_t>(count));
    for (VertexId v = 0; v < static_cast<VertexId>(color.size()); ++v)
        if (color[v] >= 0) out[static_cast<std::size_t>(color[v])].push_back(v);
    return out;
}

namespace {

// Smallest-last (Matula & Beck): repeatedly remove a vertex of least remaining degree; coloring
// in the reverse of that order gives each vertex at most its degree-at-removal colors to avoid.
std::vector<VertexId> smallest_last(const VertexGraph& graph, std::span<const std::uint8_t> fixed) {
    const auto n = static_cast<VertexId>(fixed.size());
    std::vector<int> degree(static_cast<std::size_t>(n), 0);
    int max_degree = 0;
    for (VertexId v = 0; v < n; ++v) {
        if (fixed[v]) continue;
        for (auto i = graph.offsets[v]; i < graph.offsets[v + 1]; ++i) degree[v] += !fixed[graph.neighbours[i]];
        max_degree = std::max(max_degree, degree[v]);
    }
    // Buckets by degree as doubly linked lists, so each removal costs O(degree).
    std::vector<VertexId> head(static_cast<std::size_t>(max_degree) + 1, -1), next(n, -1), prev(n, -1);
    auto unlink = [&](VertexId v) {
        if (prev[v] >= 0) next[prev[v]] = next[v];
        else head[degree[v]] = next[v];
        if (next[v] >= 0) prev[next[v]] = prev[v];
    };
    auto link = [&](VertexId v) {
        prev[v] = -1;
        next[v] = head[degree[v]];
        if (next[v] >= 0) prev[next[v]] = v;
        head[degree[v]] = v;
    };
    // Inserting in decreasing id order leaves the lowest id first in each bucket: deterministic.
    for (VertexId v = n - 1; v >= 0; --v)
        if (!fixed[v]) link(v);
    std::vector<std::uint8_t> removed(static_cast<std::size_t>(n), 0);
    std::vector<VertexId> order;
    int low = 0;
    while (true) {
        while (low <= max_degree && head[low] < 0) ++low;
        if (low > max_degree) break;
        const VertexId v = head[low];
        unlink(v);
        removed[v] = 1;
        order.push_back(v);
        for (auto i = graph.offsets[v]; i < graph.offsets[v + 1]; ++i) {
            const VertexId w = graph.neighbours[i];
            if (fixed[w] || removed[w]) continue;
            unlink(w);
            --degree[w];
            link(w);
        }
        low = std::max(0, low - 1);
    }
    std::reverse(order.begin(), order.end());
    return order;
}

}  // namespace

VertexColoring color_vertices(const SimplexMesh& mesh, ColoringOrder order) {
    const VertexId n = mesh.num_vertices();
    const auto fixed = mesh.fixed();
    VertexColoring result;
    result.color.assign(static_cast<std::size_t>(n), -1);
    // In a simplex mesh two vertices share an element exactly when they share an edge.
    const VertexGraph graph = vertex_graph(mesh);
    std::vector<VertexId> sequence;
    if (order == ColoringOrder::SmallestLast) {
        sequence = smallest_last(graph, fixed);
    } else {
        for (VertexId v = 0; v < n; ++v)
            if (!fixed[v]) sequence.push_back(v);
    }
    std::vector<VertexId> taken;  // taken[c] == v: color c is used by a neighbour of v
    for (VertexId v : sequence) {
        for (auto i = graph.offsets[v]; i < graph.offsets[v + 1]; ++i) {
            const int c = result.color[graph.neighbours[i]];
            if (c < 0) continue;
            if (static_cast<std::size_t>(c) >= taken.size()) taken.resize(static_cast<std::size_t>(c) + 1, -1);
            taken[c] = v;
        }
        int c = 0;
        while (static_cast<std::size_t>(c) < taken.size() && taken[c] == v) ++c;
        result.color[v] = c;
        result.count = std::max(result.count, c + 1);
    }
    return result;
}

bool is_proper_coloring(const SimplexMesh& mesh, const VertexColoring& coloring) {
    if (coloring.color.size() != static_cast<std::size_t>(mesh.num_vertices())) return false;
    for (VertexId v = 0; v < mesh.num_vertices(); ++v) {
        const int c = coloring.color[v];
        if (mesh.fixed()[v] ? c != -1 : (c < 0 || c >= coloring.count)) return false;
    }
    for (ElementId e = 0; e < mesh.num_elements(); ++e) {
        const auto element = mesh.element(e);
        for (std::size_t i = 0; i < element.size(); ++i)
            for (std::size_t j = i + 1; j < element.size(); ++j) {
                const int a = coloring.color[element[i]], b = coloring.color[element[j]];
                if (a >= 0 && a == b) return false;
            }
    }
    return true;
}

}  // namespace paloverde
