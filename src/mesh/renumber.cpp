#include "paloverde/mesh/renumber.hpp"

#include <algorithm>
#include <array>
#include <numeric>

namespace paloverde {

VertexGraph vertex_graph(const Mesh& mesh) { return vertex_graph(mesh, false); }

VertexGraph vertex_graph(const Mesh& mesh, bool cell_edges) {
    cell_edges = cell_edges && mesh.has_cells();
    const auto n = static_cast<std::size_t>(mesh.num_vertices());
    const auto k = static_cast<std::size_t>(mesh.corners());
    const auto connectivity = mesh.connectivity();
    // Every element's edges, each at its lower end, in passes over the elements in order (rows
    // counted first): reading the elements around each vertex instead would miss the cache at
    // nearly every element. A cell's edges join a corner's vertex to its frame's others
    // (cell_types.hpp).
    auto for_each_edge = [&](auto visit) {
        for (std::size_t at = 0; at < connectivity.size(); at += k) {
            const VertexId* c = connectivity.data() + at;
            for (std::size_t i = 0; i < (cell_edges ? 1 : k); ++i)
                for (std::size_t j = i + 1; j < k; ++j) visit(std::min(c[i], c[j]), std::max(c[i], c[j]));
        }
    };
    std::vector<std::int64_t> row(n + 1, 0);
    for_each_edge([&](VertexId low, VertexId) { ++row[static_cast<std::size_t>(low) + 1]; });
    std::partial_sum(row.begin(), row.end(), row.begin());
    std::vector<VertexId> higher(static_cast<std::size_t>(row[n]));
    {
        std::vector<std::int64_t> next(row.begin(), row.end() - 1);
        for_each_edge([&](VertexId low, VertexId high) { higher[static_cast<std::size_t>(next[static_cast<std::size_t>(low)]++)] = high; });
    }
    // Each row sorted, without repeats, in place: a vertex's higher neighbours. Its lower ones are
    // the vertices in whose rows it appears.
    std::vector<std::int64_t> higher_end(n), lower(n, 0);
    for (std::size_t v = 0; v < n; ++v) {
        const auto first = higher.begin() + row[v];
        std::sort(first, higher.begin() + row[v + 1]);
        const auto last = std::unique(first, higher.begin() + row[v + 1]);
        higher_end[v] = last - higher.begin();
        for (auto w = first; w != last; ++w) ++lower[static_cast<std::size_t>(*w)];
    }
    // Each vertex's list, sorted: its lower neighbours in increasing order, then its higher ones.
    VertexGraph graph;
    graph.offsets.assign(n + 1, 0);
    for (std::size_t v = 0; v < n; ++v) graph.offsets[v + 1] = graph.offsets[v] + lower[v] + (higher_end[v] - row[v]);
    graph.neighbours.resize(static_cast<std::size_t>(graph.offsets[n]));
    std::vector<std::int64_t> next_lower(graph.offsets.begin(), graph.offsets.end() - 1);
    for (std::size_t v = 0; v < n; ++v) {
        const auto first = higher.begin() + row[v], last = higher.begin() + higher_end[v];
        std::copy(first, last, graph.neighbours.begin() + graph.offsets[v] + lower[v]);
        for (auto w = first; w != last; ++w)
            graph.neighbours[static_cast<std::size_t>(next_lower[static_cast<std::size_t>(*w)]++)] = static_cast<VertexId>(v);
    }
    return graph;
}

namespace {

// Breadth-first levels from `start` within its component; returns the visit order.
std::vector<VertexId> bfs(const VertexGraph& g, VertexId start, std::vector<int>& level) {
    std::vector<VertexId> order{start};
    level[start] = 0;
    for (std::size_t head = 0; head < order.size(); ++head) {
        const VertexId v = order[head];
        for (auto i = g.offsets[v]; i < g.offsets[v + 1]; ++i) {
            const VertexId w = g.neighbours[i];
            if (level[w] < 0) {
                level[w] = level[v] + 1;
                order.push_back(w);
            }
        }
    }
    return order;
}

// A vertex far from everything in its component (George-Liu pseudo-peripheral search).
VertexId pseudo_peripheral(const VertexGraph& g, VertexId start) {
    const auto degree = [&](VertexId v) { return g.offsets[v + 1] - g.offsets[v]; };
    std::vector<int> level(g.offsets.size() - 1, -1);
    int eccentricity = -1;
    for (int round = 0; round < 8; ++round) {
        std::fill(level.begin(), level.end(), -1);  // O(n) per round; a handful of rounds
        const auto order = bfs(g, start, level);
        const int depth = level[order.back()];
        if (depth <= eccentricity) break;
        eccentricity = depth;
        VertexId best = order.back();
        for (auto it = order.rbegin(); it != order.rend() && level[*it] == depth; ++it)
            if (degree(*it) < degree(best)) best = *it;
        start = best;
    }
    return start;
}

}  // namespace

Renumbering locality_order(const Mesh& mesh, std::span<const std::uint8_t> last_group) {
    const VertexGraph g = vertex_graph(mesh);
    const VertexId n = mesh.num_vertices();
    const auto degree = [&](VertexId v) { return g.offsets[v + 1] - g.offsets[v]; };
    std::vector<VertexId> order;
    order.reserve(static_cast<std::size_t>(n));
    std::vector<char> placed(static_cast<std::size_t>(n), 0);
    std::vector<VertexId> ranked(static_cast<std::size_t>(n));
    std::iota(ranked.begin(), ranked.end(), VertexId{0});
    std::stable_sort(ranked.begin(), ranked.end(), [&](VertexId a, VertexId b) { return degree(a) < degree(b); });
    std::vector<VertexId> neighbours;
    for (VertexId seed : ranked) {  // one Cuthill-McKee sweep per connected component
        if (placed[seed]) continue;
        const VertexId start = pseudo_peripheral(g, seed);
        std::size_t head = order.size();
        order.push_back(start);
        placed[start] = 1;
        for (; head < order.size(); ++head) {
            const VertexId v = order[head];
            neighbours.clear();
            for (auto i = g.offsets[v]; i < g.offsets[v + 1]; ++i)
                if (!placed[g.neighbours[i]]) neighbours.push_back(g.neighbours[i]);
            std::stable_sort(neighbours.begin(), neighbours.end(),
                             [&](VertexId a, VertexId b) { return degree(a) < degree(b); });
            for (VertexId w : neighbours) {
                placed[w] = 1;
                order.push_back(w);
            }
        }
    }
    std::reverse(order.begin(), order.end());

    Renumbering result;
    result.old_vertex = std::move(order);
    std::vector<VertexId> new_id(static_cast<std::size_t>(n));
    for (VertexId i = 0; i < n; ++i) new_id[result.old_vertex[i]] = i;

    // Elements by (group, lowest new vertex id, old id): a counting sort, as the keys are small.
    const ElementId m = mesh.num_elements();
    std::vector<std::int64_t> key(static_cast<std::size_t>(m));
    std::vector<std::int64_t> first_of(2 * (static_cast<std::size_t>(n) + 1) + 1, 0);
    for (ElementId e = 0; e < m; ++e) {
        VertexId lowest = n;
        for (VertexId v : mesh.element(e)) lowest = std::min(lowest, new_id[v]);
        const std::int64_t group = !last_group.empty() && last_group[e] ? 1 : 0;
        key[e] = group * (static_cast<std::int64_t>(n) + 1) + lowest;
        ++first_of[static_cast<std::size_t>(key[e]) + 1];
    }
    std::partial_sum(first_of.begin(), first_of.end(), first_of.begin());
    result.old_element.resize(static_cast<std::size_t>(m));
    for (ElementId e = 0; e < m; ++e) result.old_element[first_of[static_cast<std::size_t>(key[e])]++] = e;
    return result;
}

Mesh renumbered(const Mesh& mesh, const Renumbering& order) {
    const VertexId n = mesh.num_vertices();
    std::vector<VertexId> new_id(static_cast<std::size_t>(n));
    for (VertexId i = 0; i < n; ++i) new_id[order.old_vertex[i]] = i;
    std::vector<double> xyz(3 * static_cast<std::size_t>(n));
    std::vector<std::uint8_t> freedom(static_cast<std::size_t>(n));
    std::vector<GlobalId> global(static_cast<std::size_t>(n));
    for (VertexId i = 0; i < n; ++i) {
        const VertexId old = order.old_vertex[i];
        for (int c = 0; c < 3; ++c) xyz[3 * i + c] = mesh.coordinates()[3 * static_cast<std::size_t>(old) + c];
        freedom[i] = static_cast<std::uint8_t>(mesh.degrees_of_freedom(old));
        global[i] = mesh.global_ids()[old];
    }
    std::vector<VertexId> connectivity;
    connectivity.reserve(mesh.connectivity().size());
    for (ElementId old : order.old_element)
        for (VertexId v : mesh.element(old)) connectivity.push_back(new_id[v]);
    Mesh out(mesh.kind(), std::move(xyz), std::move(connectivity));
    out.set_degrees_of_freedom(std::move(freedom));
    out.set_global_ids(std::move(global));
    out.set_elements_flipped(mesh.elements_flipped());  // corners keep their order within each element
    out.carry_cells_from(mesh, new_id, order.old_element);
    return out;
}

std::vector<GlobalId> canonical_element_positions(const Mesh& mesh, std::span<const GlobalId> vertex_key) {
    const ElementId m = mesh.num_elements();
    const int k = mesh.corners();
    const auto maps = mesh.corner_maps();
    // Sorted in one array with their keys (an order of ids that looks its keys up would miss the
    // cache at every comparison). Two corners of different cells may share their vertices: their
    // maps tell them apart; no two elements have the same key and map.
    struct Keyed {
        std::array<GlobalId, 4> key;
        std::uint8_t map;
        ElementId element;
        bool operator<(const Keyed& o) const {
            for (int i = 0; i < 4; ++i)
                if (key[i] != o.key[i]) return key[i] < o.key[i];
            return map < o.map;
        }
    };
    std::vector<Keyed> sorted(static_cast<std::size_t>(m));
    for (ElementId e = 0; e < m; ++e) {
        Keyed& entry = sorted[e];
        entry.key.fill(-1);
        for (int i = 0; i < k; ++i) entry.key[i] = vertex_key[mesh.element(e)[i]];
        std::sort(entry.key.begin(), entry.key.begin() + k);
        entry.map = maps.empty() ? 0 : maps[e];
        entry.element = e;
    }
    std::sort(sorted.begin(), sorted.end());
    std::vector<GlobalId> position(static_cast<std::size_t>(m));
    for (ElementId i = 0; i < m; ++i) position[sorted[i].element] = i;
    return position;
}

}  // namespace paloverde
