#include "paloverde/mesh/renumber.hpp"

#include <algorithm>
#include <array>
#include <functional>
#include <numeric>

#include "core/prefetch.hpp"

namespace paloverde {

namespace {
// Sorts for the short ranges a vertex's neighbours make (about fourteen in a tetrahedral mesh):
// each value goes to its rank (how many come before it), so no branch depends on the values,
// where insertion sort mispredicted at nearly every step (building a large mesh's vertex graph
// took nearly twice as long with it), and nothing is allocated, as std::stable_sort does at every
// call.
constexpr std::ptrdiff_t kShort = 32;

// Writes n distinct values to `out` in increasing order (n <= kShort).
template <class T>
void place_by_rank(const T* values, std::ptrdiff_t n, T* out) {
    for (std::ptrdiff_t i = 0; i < n; ++i) {
        std::ptrdiff_t rank = 0;
        for (std::ptrdiff_t j = 0; j < n; ++j) rank += values[j] < values[i];
        out[rank] = values[i];
    }
}

// Distinct values, increasing.
template <class T>
void sort_distinct_short(T* first, T* last) {
    const std::ptrdiff_t n = last - first;
    if (n > kShort) {
        std::sort(first, last);
        return;
    }
    T copy[kShort];
    std::copy(first, last, copy);
    place_by_rank(copy, n, first);
}

// Stable, by increasing key(value).
template <class T, class Key>
void stable_sort_short_by(T* first, T* last, Key key) {
    const std::ptrdiff_t n = last - first;
    if (n > kShort) {
        std::stable_sort(first, last, [&](const T& a, const T& b) { return key(a) < key(b); });
        return;
    }
    T copy[kShort];
    decltype(key(*first)) keys[kShort];
    for (std::ptrdiff_t i = 0; i < n; ++i) copy[i] = first[i], keys[i] = key(first[i]);
    for (std::ptrdiff_t i = 0; i < n; ++i) {
        std::ptrdiff_t rank = 0;  // those with a smaller key, and those before it with its own
        for (std::ptrdiff_t j = 0; j < i; ++j) rank += keys[j] <= keys[i];
        for (std::ptrdiff_t j = i + 1; j < n; ++j) rank += keys[j] < keys[i];
        first[rank] = copy[i];
    }
}
}  // namespace

VertexGraph vertex_graph(const Mesh& mesh) { return vertex_graph(mesh, false); }

VertexGraph vertex_graph(const Mesh& mesh, bool cell_edges) {
    cell_edges = cell_edges && mesh.has_cells();
    const auto n = static_cast<std::size_t>(mesh.num_vertices());
    const auto k = static_cast<std::size_t>(mesh.corners());
    const VertexId* corners = mesh.connectivity().data();
    const auto first_around = mesh.vertex_element_offsets();
    const auto around = mesh.vertex_elements();
    // Each vertex's row from the elements around it, rows written in order. In a mesh in file
    // order those elements lie scattered: their corners are asked for a few elements ahead, so
    // the loads overlap (scattering every element's edges into rows instead wrote to a cache line
    // of its own at nearly every edge). A cell's edges join a corner's vertex to its frame's
    // others (cell_types.hpp). Repeats (an edge lies in about five tetrahedra) are dropped by a
    // mark per vertex, then the row is sorted.
    VertexGraph graph;
    graph.offsets.assign(n + 1, 0);
    graph.neighbours.reserve(around.size());
    std::vector<VertexId> last_row(n, -1);  // the row that last took each vertex
    std::int64_t most_around = 0;
    for (std::size_t v = 0; v < n; ++v) most_around = std::max(most_around, first_around[v + 1] - first_around[v]);
    // One row's neighbours, gathered without branching on the ids (whether a corner is new to
    // the row mispredicts often): each is written at the row's end, which moves on only for a new
    // one.
    std::vector<VertexId> row(k * static_cast<std::size_t>(most_around) + 1);
    const auto ahead = static_cast<std::size_t>(detail::kPrefetchAroundAhead);
    for (std::size_t v = 0; v < n; ++v) {
        const auto vertex = static_cast<VertexId>(v);
        last_row[v] = vertex;  // never its own neighbour
        std::size_t length = 0;
        auto take = [&](VertexId w) {
            row[length] = w;
            length += last_row[static_cast<std::size_t>(w)] != vertex;
            last_row[static_cast<std::size_t>(w)] = vertex;
        };
        const auto end = static_cast<std::size_t>(first_around[v + 1]);
        for (auto i = static_cast<std::size_t>(first_around[v]); i < end; ++i) {
            if (i + ahead < around.size()) __builtin_prefetch(corners + k * static_cast<std::size_t>(around[i + ahead]));
            const VertexId* c = corners + k * static_cast<std::size_t>(around[i]);
            if (!cell_edges) {
                for (std::size_t j = 0; j < k; ++j) take(c[j]);
            } else if (c[0] == vertex) {
                for (std::size_t j = 1; j < k; ++j) take(c[j]);
            } else {
                take(c[0]);  // v is one of the frame's other corners
            }
        }
        sort_distinct_short(row.data(), row.data() + length);
        graph.neighbours.insert(graph.neighbours.end(), row.data(), row.data() + length);
        graph.offsets[v + 1] = static_cast<std::int64_t>(graph.neighbours.size());
    }
    return graph;
}

namespace {

// In a sweep over a queue of vertices (breadth-first), the rows of the vertices a few places
// ahead are asked for: in a mesh in file order they lie scattered, and the loads then overlap
// (the sweeps take about 40% less on a large mesh). Always inlined: GCC drops a call to a function
// that only prefetches, as it sees no effect.
[[gnu::always_inline]] inline void prefetch_rows_ahead(const VertexGraph& g, const std::vector<VertexId>& queue,
                                                       std::size_t head) {
    const auto ahead = static_cast<std::size_t>(detail::kPrefetchAhead);
    if (head + 2 * ahead < queue.size()) __builtin_prefetch(&g.offsets[queue[head + 2 * ahead]]);
    if (head + ahead < queue.size()) __builtin_prefetch(g.neighbours.data() + g.offsets[queue[head + ahead]]);
}

// Breadth-first levels from `start` within its component, into `order` (the visit order).
void bfs(const VertexGraph& g, VertexId start, std::vector<int>& level, std::vector<VertexId>& order) {
    order.assign(1, start);
    level[start] = 0;
    for (std::size_t head = 0; head < order.size(); ++head) {
        prefetch_rows_ahead(g, order, head);
        const VertexId v = order[head];
        for (auto i = g.offsets[v]; i < g.offsets[v + 1]; ++i) {
            const VertexId w = g.neighbours[i];
            if (level[w] < 0) {
                level[w] = level[v] + 1;
                order.push_back(w);
            }
        }
    }
}

// A vertex far from everything in its component (George-Liu pseudo-peripheral search). `level`
// is -1 everywhere on entry and on return: each round resets only the vertices it reached, so a
// mesh of many small components (unused vertices, say) costs no pass over all vertices each.
VertexId pseudo_peripheral(const VertexGraph& g, VertexId start, std::vector<int>& level,
                           std::vector<VertexId>& order) {
    const auto degree = [&](VertexId v) { return g.offsets[v + 1] - g.offsets[v]; };
    int eccentricity = -1;
    for (int round = 0; round < 8; ++round) {
        bfs(g, start, level, order);
        const int depth = level[order.back()];
        VertexId best = order.back();
        for (auto it = order.rbegin(); it != order.rend() && level[*it] == depth; ++it)
            if (degree(*it) < degree(best)) best = *it;
        for (VertexId v : order) level[v] = -1;
        if (depth <= eccentricity) break;
        eccentricity = depth;
        start = best;
    }
    return start;
}

}  // namespace

std::vector<VertexId> locality_vertex_order(const Mesh& mesh) {
    const VertexGraph g = vertex_graph(mesh);
    const VertexId n = mesh.num_vertices();
    const auto degree = [&](VertexId v) { return g.offsets[v + 1] - g.offsets[v]; };
    std::vector<VertexId> order;
    order.reserve(static_cast<std::size_t>(n));
    std::vector<char> placed(static_cast<std::size_t>(n), 0);
    // Every vertex by degree, ties by id: a counting sort, as degrees are small.
    std::vector<VertexId> ranked(static_cast<std::size_t>(n));
    {
        std::int64_t most = 0;
        for (VertexId v = 0; v < n; ++v) most = std::max(most, degree(v));
        std::vector<std::int64_t> first_of(static_cast<std::size_t>(most) + 2, 0);
        for (VertexId v = 0; v < n; ++v) ++first_of[static_cast<std::size_t>(degree(v)) + 1];
        std::partial_sum(first_of.begin(), first_of.end(), first_of.begin());
        for (VertexId v = 0; v < n; ++v) ranked[static_cast<std::size_t>(first_of[static_cast<std::size_t>(degree(v))]++)] = v;
    }
    std::vector<VertexId> neighbours, visited;
    std::vector<int> level(static_cast<std::size_t>(n), -1);
    for (VertexId seed : ranked) {  // one Cuthill-McKee sweep per connected component
        if (placed[seed]) continue;
        const VertexId start = pseudo_peripheral(g, seed, level, visited);
        std::size_t head = order.size();
        order.push_back(start);
        placed[start] = 1;
        for (; head < order.size(); ++head) {
            prefetch_rows_ahead(g, order, head);
            const VertexId v = order[head];
            neighbours.clear();
            for (auto i = g.offsets[v]; i < g.offsets[v + 1]; ++i)
                if (!placed[g.neighbours[i]]) neighbours.push_back(g.neighbours[i]);
            stable_sort_short_by(neighbours.data(), neighbours.data() + neighbours.size(), degree);
            for (VertexId w : neighbours) {
                placed[w] = 1;
                order.push_back(w);
            }
        }
    }
    std::reverse(order.begin(), order.end());
    return order;
}

Renumbering locality_order(const Mesh& mesh, std::span<const std::uint8_t> last_group) {
    const VertexId n = mesh.num_vertices();
    Renumbering result;
    result.old_vertex = locality_vertex_order(mesh);
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
    Mesh out = mesh;
    out.permute(order.old_vertex, order.old_element);
    return out;
}

std::vector<GlobalId> canonical_element_positions(const Mesh& mesh, std::span<const GlobalId> vertex_key) {
    const ElementId m = mesh.num_elements();
    const int k = mesh.corners();
    const auto maps = mesh.corner_maps();
    // Sorted with their keys (an order of ids that looks its keys up would miss the cache at every
    // comparison). Two corners of different cells may share their vertices: their maps tell them
    // apart; no two elements have the same key and map.
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
    auto keyed = [&](ElementId e) {
        Keyed entry;
        entry.key.fill(-1);
        std::array<GlobalId, 4> corner{};
        for (int i = 0; i < k; ++i) corner[i] = vertex_key[mesh.element(e)[i]];
        place_by_rank(corner.data(), k, entry.key.data());
        entry.map = maps.empty() ? 0 : maps[e];
        entry.element = e;
        return entry;
    };
    std::vector<GlobalId> position(static_cast<std::size_t>(m));
    constexpr GlobalId kWord = GlobalId{1} << 32;
    const bool small_keys = std::all_of(vertex_key.begin(), vertex_key.end(),
                                        [](GlobalId key) { return key >= 0 && key < kWord - 1; });
    if (!small_keys) {
        std::vector<Keyed> sorted(static_cast<std::size_t>(m));
        for (ElementId e = 0; e < m; ++e) sorted[e] = keyed(e);
        std::sort(sorted.begin(), sorted.end());
        for (ElementId i = 0; i < m; ++i) position[sorted[i].element] = i;
        return position;
    }
    // Keys below 2^32 - 1 (a triangle's missing fourth key, -1, packs to 2^32 - 1 in every
    // element alike) fit two to a word: 24-byte records to sort instead of 40, the same order.
    struct Packed {
        std::uint64_t high, low;  // the sorted keys, two to a word
        ElementId element;
        std::uint8_t map;
        bool operator<(const Packed& o) const {
            return high != o.high ? high < o.high : low != o.low ? low < o.low : map < o.map;
        }
    };
    auto pack = [](const Keyed& entry) {
        auto word = [&](int i) { return static_cast<std::uint64_t>(static_cast<std::uint32_t>(entry.key[i])); };
        return Packed{word(0) << 32 | word(1), word(2) << 32 | word(3), entry.element, entry.map};
    };
    const GlobalId largest = vertex_key.empty() ? 0 : *std::max_element(vertex_key.begin(), vertex_key.end());
    if (largest > 2 * static_cast<GlobalId>(vertex_key.size())) {
        std::vector<Packed> sorted(static_cast<std::size_t>(m));
        for (ElementId e = 0; e < m; ++e) {
            // The keys of the corners of an element a few ahead: scattered in a mesh in file order.
            if (e + detail::kPrefetchAhead < m)
                for (VertexId v : mesh.element(e + static_cast<ElementId>(detail::kPrefetchAhead)))
                    __builtin_prefetch(&vertex_key[v]);
            sorted[e] = pack(keyed(e));
        }
        std::sort(sorted.begin(), sorted.end());
        for (ElementId i = 0; i < m; ++i) position[sorted[i].element] = i;
        return position;
    }
    // Dense keys (vertex positions: the serial set-up's): the elements go into buckets by their
    // smallest key (a counting sort of their ids), and each bucket, about six elements, is sorted
    // alone by its records. The order of one sort of all the records, without its twenty passes
    // over memory, and without scattering whole records (a cache miss each, on three times the
    // memory). `position` holds each element's smallest key until it gets its position.
    std::vector<ElementId> next(static_cast<std::size_t>(largest) + 2, 0);
    for (ElementId e = 0; e < m; ++e) {
        if (e + detail::kPrefetchAhead < m)
            for (VertexId v : mesh.element(e + static_cast<ElementId>(detail::kPrefetchAhead)))
                __builtin_prefetch(&vertex_key[v]);
        GlobalId smallest = vertex_key[mesh.element(e)[0]];
        for (int i = 1; i < k; ++i) smallest = std::min(smallest, vertex_key[mesh.element(e)[i]]);
        position[e] = smallest;
        ++next[static_cast<std::size_t>(smallest) + 1];
    }
    std::partial_sum(next.begin(), next.end(), next.begin());
    std::vector<ElementId> bucketed(static_cast<std::size_t>(m));
    for (ElementId e = 0; e < m; ++e) bucketed[static_cast<std::size_t>(next[static_cast<std::size_t>(position[e])]++)] = e;
    // Bucket by bucket: the elements lie scattered, so the corners of those a little ahead are
    // asked for, and their keys a little nearer (once the corners have come).
    const auto ahead = static_cast<std::size_t>(detail::kPrefetchAhead);
    const auto count = static_cast<std::size_t>(m);
    std::vector<Packed> bucket;
    // Bucket b now ends where next[b] has moved to, and the next one starts there.
    for (std::size_t b = 0, first = 0; b + 1 < next.size(); ++b) {
        const auto last = static_cast<std::size_t>(next[b]);
        bucket.clear();
        for (std::size_t i = first; i < last; ++i) {
            if (i + 2 * ahead < count) __builtin_prefetch(mesh.element(bucketed[i + 2 * ahead]).data());
            if (i + ahead < count)
                for (VertexId v : mesh.element(bucketed[i + ahead])) __builtin_prefetch(&vertex_key[v]);
            bucket.push_back(pack(keyed(bucketed[i])));
        }
        std::sort(bucket.begin(), bucket.end());
        for (std::size_t i = 0; i < bucket.size(); ++i) position[bucket[i].element] = static_cast<GlobalId>(first + i);
        first = last;
    }
    return position;
}

}  // namespace paloverde
