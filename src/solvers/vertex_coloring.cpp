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
std::vector<VertexId> smallest_last(const VertexGraph& graph, const Mesh& mesh) {
    const VertexId n = mesh.num_vertices();
    std::vector<int> degree(static_cast<std::size_t>(n), 0);
    int max_degree = 0;
    for (VertexId v = 0; v < n; ++v) {
        if (!mesh.can_move(v)) continue;
        for (auto i = graph.offsets[v]; i < graph.offsets[v + 1]; ++i) degree[v] += mesh.can_move(graph.neighbours[i]);
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
        if (mesh.can_move(v)) link(v);
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
            if (!mesh.can_move(w) || removed[w]) continue;
            unlink(w);
            --degree[w];
            link(w);
        }
        low = std::max(0, low - 1);
    }
    std::reverse(order.begin(), order.end());
    return order;
}

// The whole mesh: first fit in `order`.
VertexColoring color_whole(const Mesh& mesh, ColoringOrder order) {
    const VertexId n = mesh.num_vertices();
    VertexColoring result;
    result.color.assign(static_cast<std::size_t>(n), -1);
    // In a simplex mesh two vertices share an element exactly when they share an edge.
    const VertexGraph graph = vertex_graph(mesh);
    std::vector<VertexId> sequence;
    if (order == ColoringOrder::SmallestLast) {
        sequence = smallest_last(graph, mesh);
    } else {
        for (VertexId v = 0; v < n; ++v)
            if (mesh.can_move(v)) sequence.push_back(v);
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

// A part: in rounds (Jones & Plassmann), by priorities every rank computes alike.
VertexColoring color_part(const MeshPart& part) {
    const Mesh& mesh = part.mesh();
    const auto ids = mesh.global_ids();
    const Reducer& reducer = part.reducer();
    const VertexId n = mesh.num_vertices();
    // SplitMix64 of the id: a priority that looks random (few rounds) yet is the same on every
    // rank and in every numbering.
    auto priority = [&](VertexId v) {
        std::uint64_t z = static_cast<std::uint64_t>(ids[v]) + 0x9e3779b97f4a7c15ULL;
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
        return std::pair{z ^ (z >> 31), ids[v]};
    };
    const VertexGraph graph = vertex_graph(mesh);
    std::vector<double> color(static_cast<std::size_t>(n), -1.0);  // doubles: they travel through the halo
    std::vector<std::pair<VertexId, int>> chosen;
    std::vector<char> used;
    for (;;) {
        chosen.clear();
        double uncolored = 0.0;
        for (VertexId v = 0; v < n; ++v) {
            if (!mesh.can_move(v) || !part.owns(v) || color[v] >= 0.0) continue;
            uncolored += 1.0;
            bool first = true;
            used.assign(1, 0);
            for (auto i = graph.offsets[v]; i < graph.offsets[v + 1] && first; ++i) {
                const VertexId w = graph.neighbours[i];
                if (!mesh.can_move(w)) continue;
                if (color[w] < 0.0) first = priority(w) < priority(v);
                else {
                    const auto c = static_cast<std::size_t>(color[w]);
                    if (c >= used.size()) used.resize(c + 1, 0);
                    used[c] = 1;
                }
            }
            if (!first) continue;
            int c = 0;
            while (static_cast<std::size_t>(c) < used.size() && used[static_cast<std::size_t>(c)]) ++c;
            chosen.push_back({v, c});
        }
        if (reducer.total(uncolored) == 0.0) break;
        for (const auto& [v, c] : chosen) color[v] = c;
        part.halo().update(color, 1);
    }
    VertexColoring result;
    result.color.resize(static_cast<std::size_t>(n));
    int count = 0;
    for (VertexId v = 0; v < n; ++v) {
        result.color[v] = mesh.can_move(v) ? static_cast<int>(color[v]) : -1;
        count = std::max(count, result.color[v] + 1);
    }
    result.count = static_cast<int>(reducer.max(count));
    return result;
}

}  // namespace

VertexColoring color_vertices(MeshPart part, ColoringOrder order) {
    // The serial orders need the whole mesh.
    return part.whole() ? color_whole(part.mesh(), order) : color_part(part);
}

bool is_proper_coloring(const Mesh& mesh, const VertexColoring& coloring) {
    if (coloring.color.size() != static_cast<std::size_t>(mesh.num_vertices())) return false;
    for (VertexId v = 0; v < mesh.num_vertices(); ++v) {
        const int c = coloring.color[v];
        if (!mesh.can_move(v) ? c != -1 : (c < 0 || c >= coloring.count)) return false;
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
