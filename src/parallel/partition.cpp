#include "paloverde/parallel/partition.hpp"

#include <metis.h>

#include <algorithm>
#include <limits>
#include <queue>
#include <set>
#include <string>
#include <type_traits>

#include "paloverde/core/error.hpp"
#include "paloverde/mesh/renumber.hpp"

namespace paloverde {

std::vector<int> partition_vertices(const Mesh& mesh, int parts) {
    const VertexId n = mesh.num_vertices();
    if (parts < 1) throw OptionError("the number of parts must be at least 1 (got " + std::to_string(parts) + ")");
    if (parts > n)
        throw OptionError("cannot split " + std::to_string(n) + " vertices into " + std::to_string(parts) +
                          " parts: use at most as many processes as the mesh has vertices");
    std::vector<int> part(static_cast<std::size_t>(n), 0);
    if (parts == 1) return part;
    // METIS's own working memory is a few times the graph's: only its copy of the graph stays.
    std::vector<idx_t> xadj, adjncy;
    {
        VertexGraph graph = vertex_graph(mesh);
        if (graph.neighbours.size() > static_cast<std::size_t>(std::numeric_limits<idx_t>::max()))
            throw OptionError("the mesh is too large for this METIS build (32-bit indices)");
        xadj.assign(graph.offsets.begin(), graph.offsets.end());
        if constexpr (std::is_same_v<idx_t, VertexId>) adjncy = std::move(graph.neighbours);
        else adjncy.assign(graph.neighbours.begin(), graph.neighbours.end());
    }
    idx_t vertices = n, constraints = 1, nparts = parts, cut = 0;
    idx_t options[METIS_NOPTIONS];
    METIS_SetDefaultOptions(options);
    options[METIS_OPTION_OBJTYPE] = METIS_OBJTYPE_CUT;
    options[METIS_OPTION_MINCONN] = 1;  // few neighbouring parts: fewer messages and colors
    options[METIS_OPTION_SEED] = 1;
    options[METIS_OPTION_NUMBERING] = 0;
    std::vector<idx_t> result(static_cast<std::size_t>(n));
    const int status = METIS_PartGraphKway(&vertices, &constraints, xadj.data(), adjncy.data(), nullptr, nullptr,
                                           nullptr, &nparts, nullptr, nullptr, options, &cut, result.data());
    if (status != METIS_OK) throw Error("METIS failed to partition the mesh (status " + std::to_string(status) + ")");
    std::copy(result.begin(), result.end(), part.begin());
    return part;
}

std::vector<int> color_process_graph(int parts, std::span<const std::pair<int, int>> edges) {
    std::vector<std::vector<std::pair<int, std::size_t>>> incident(static_cast<std::size_t>(parts));
    for (std::size_t i = 0; i < edges.size(); ++i) {
        incident[edges[i].first].push_back({edges[i].second, i});
        incident[edges[i].second].push_back({edges[i].first, i});
    }
    for (auto& list : incident) std::sort(list.begin(), list.end());
    std::vector<int> color(edges.size(), -1);
    std::vector<std::set<int>> used(static_cast<std::size_t>(parts));
    std::vector<char> seen(static_cast<std::size_t>(parts), 0);
    for (int root = 0; root < parts; ++root) {
        if (seen[root]) continue;
        std::queue<int> queue;
        queue.push(root);
        seen[root] = 1;
        while (!queue.empty()) {
            const int a = queue.front();
            queue.pop();
            for (const auto& [b, edge] : incident[a]) {
                if (color[edge] < 0) {
                    int c = 0;
                    while (used[a].count(c) || used[b].count(c)) ++c;
                    color[edge] = c;
                    used[a].insert(c);
                    used[b].insert(c);
                }
                if (!seen[b]) {
                    seen[b] = 1;
                    queue.push(b);
                }
            }
        }
    }
    return color;
}

PartitionStatistics partition_statistics(const Mesh& mesh, std::span<const int> part, int parts) {
    PartitionStatistics stats;
    stats.parts = parts;
    // Part p holds every cell (element, without cells) touching a vertex it owns; the other
    // vertices of those cells are its ghosts.
    std::vector<std::set<int>> holders(static_cast<std::size_t>(mesh.num_vertices()));
    std::vector<std::int64_t> held(static_cast<std::size_t>(parts), 0);
    std::vector<int> touching;
    for (ElementId c = 0; c < mesh.num_cells(); ++c) {
        touching.clear();
        for (VertexId v : mesh.cell(c)) touching.push_back(part[v]);
        std::sort(touching.begin(), touching.end());
        touching.erase(std::unique(touching.begin(), touching.end()), touching.end());
        for (int p : touching) {
            ++held[p];
            for (VertexId v : mesh.cell(c))
                if (part[v] != p) holders[v].insert(p);
        }
    }
    std::set<std::pair<int, int>> edges;
    for (VertexId v = 0; v < mesh.num_vertices(); ++v) {
        stats.ghost_copies += static_cast<std::int64_t>(holders[v].size());
        stats.shared_vertices += !holders[v].empty();
        for (int p : holders[v]) edges.insert({std::min(p, part[v]), std::max(p, part[v])});
    }
    stats.process_edges = static_cast<std::int64_t>(edges.size());
    const std::vector<std::pair<int, int>> list(edges.begin(), edges.end());
    const auto colors = color_process_graph(parts, list);
    stats.colors = colors.empty() ? 0 : *std::max_element(colors.begin(), colors.end()) + 1;
    std::vector<int> neighbours(static_cast<std::size_t>(parts), 0);
    for (const auto& [a, b] : list) ++neighbours[a], ++neighbours[b];
    stats.max_neighbours = parts > 0 ? *std::max_element(neighbours.begin(), neighbours.end()) : 0;
    stats.largest_part_elements = parts > 0 ? *std::max_element(held.begin(), held.end()) : 0;
    return stats;
}

}  // namespace paloverde
