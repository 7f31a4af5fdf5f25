#pragma once
// Reordering flat arrays by a permutation given as "new position i holds old item order[i]" (the
// way Renumbering and Mesh::permute state it).
#include <cstddef>
#include <span>
#include <vector>

namespace paloverde::detail {

// out[w i + c] = values[w order[i] + c] for c < w: items of `width` values each, in the new order.
// Empty values give an empty result (a field the mesh does not hold).
template <class T, class Id>
std::vector<T> gathered(const std::vector<T>& values, std::span<const Id> order, std::size_t width = 1) {
    if (values.empty()) return {};
    std::vector<T> out(width * order.size());
    for (std::size_t i = 0; i < order.size(); ++i)
        for (std::size_t c = 0; c < width; ++c) out[width * i + c] = values[width * static_cast<std::size_t>(order[i]) + c];
    return out;
}

// The order that undoes `order`: out[order[i]] = i.
template <class Id>
std::vector<Id> inverse(std::span<const Id> order) {
    std::vector<Id> out(order.size());
    for (std::size_t i = 0; i < order.size(); ++i) out[static_cast<std::size_t>(order[i])] = static_cast<Id>(i);
    return out;
}

}  // namespace paloverde::detail
