#include "parallel/parts.hpp"

#include <algorithm>
#include <numeric>
#include <type_traits>

namespace paloverde::parallel {

Mesh part_mesh(PartArrays& arrays, ElementKind kind) {
    static_assert(std::is_same_v<std::int32_t, VertexId> && std::is_same_v<std::int64_t, GlobalId> &&
                  sizeof(CellType) == 1, "the part's arrays are moved into the mesh, not copied");
    Mesh mesh;
    if (arrays.cell_types.empty()) {
        mesh = Mesh(kind, std::move(arrays.coordinates), std::move(arrays.connectivity));
    } else {
        std::vector<CellType> types(arrays.cell_types.size());
        std::transform(arrays.cell_types.begin(), arrays.cell_types.end(), types.begin(),
                       [](std::uint8_t t) { return static_cast<CellType>(t); });
        std::vector<std::uint8_t>().swap(arrays.cell_types);
        // Kept as cells even if this part's are all simplices: every part is rated as the whole.
        mesh = Mesh::from_cells(std::move(arrays.coordinates), types, std::move(arrays.cell_connectivity), true);
    }
    mesh.set_fixed(std::move(arrays.fixed));
    mesh.set_global_ids(std::move(arrays.canonical));
    if (!arrays.reference.empty()) mesh.set_reference_coordinates(std::move(arrays.reference));
    if (!arrays.edge_lengths.empty()) mesh.set_target_edge_lengths(std::move(arrays.edge_lengths));
    if (!arrays.metrics.empty()) mesh.set_target_metrics(std::move(arrays.metrics));
    return mesh;
}

std::vector<std::uint8_t> counted_cells(const Mesh& mesh, std::span<const std::int32_t> owner, int rank) {
    std::vector<std::uint8_t> counted(static_cast<std::size_t>(mesh.num_cells()));
    for (ElementId c = 0; c < mesh.num_cells(); ++c) {
        const auto vertices = mesh.cell(c);
        counted[c] = owner[*std::min_element(vertices.begin(), vertices.end())] == rank;
    }
    return counted;
}

std::vector<std::uint8_t> per_element(const Mesh& mesh, std::span<const std::uint8_t> per_cell) {
    std::vector<std::uint8_t> out(static_cast<std::size_t>(mesh.num_elements()));
    for (ElementId e = 0; e < mesh.num_elements(); ++e) out[e] = per_cell[mesh.cell_of(e)];
    return out;
}

void append_element_key(const Mesh& mesh, ElementId e, int width, std::vector<std::int64_t>& keys) {
    const auto at = keys.size();
    keys.resize(at + static_cast<std::size_t>(width), -1);
    const auto corners = mesh.element(e);
    for (std::size_t i = 0; i < corners.size(); ++i) keys[at + i] = mesh.global_ids()[corners[i]];
    std::sort(keys.begin() + static_cast<std::ptrdiff_t>(at), keys.begin() + static_cast<std::ptrdiff_t>(at + corners.size()));
    if (width > 4) keys[at + 4] = mesh.has_cells() ? mesh.corner_maps()[e] : 0;
}

void append_cell_key(CellType type, std::span<const VertexId> cell, std::span<const GlobalId> ids,
                     std::vector<std::int64_t>& keys) {
    const auto at = keys.size();
    keys.resize(at + kCellKeyWidth, -1);
    for (std::size_t i = 0; i < cell.size(); ++i) keys[at + i] = ids[cell[i]];
    std::sort(keys.begin() + static_cast<std::ptrdiff_t>(at), keys.begin() + static_cast<std::ptrdiff_t>(at + cell.size()));
    keys[at + kMaxCellCorners] = static_cast<std::int64_t>(type);
}

std::vector<std::int64_t> key_positions(const std::vector<std::int64_t>& keys, int width, std::int64_t& distinct) {
    const std::size_t count = keys.size() / static_cast<std::size_t>(width);
    const auto key = [&](std::size_t i) { return keys.begin() + static_cast<std::ptrdiff_t>(i * width); };
    std::vector<std::size_t> sorted(count);
    std::iota(sorted.begin(), sorted.end(), std::size_t{0});
    std::sort(sorted.begin(), sorted.end(), [&](std::size_t a, std::size_t b) {
        return std::lexicographical_compare(key(a), key(a) + width, key(b), key(b) + width);
    });
    std::vector<std::int64_t> position(count);
    distinct = 0;
    for (std::size_t i = 0; i < count; ++i) {
        if (i > 0 && !std::equal(key(sorted[i]), key(sorted[i]) + width, key(sorted[i - 1]))) ++distinct;
        position[sorted[i]] = distinct;
    }
    if (count > 0) ++distinct;
    return position;
}

}  // namespace paloverde::parallel
