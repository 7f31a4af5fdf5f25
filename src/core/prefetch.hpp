#pragma once
// Asking the cache for what a loop reads a little later. A pass over the elements in a mesh's
// file order (before any renumbering) finds each element's corners scattered over the
// coordinates, and without this would wait on their loads one element after another.
#include <cstddef>

#include "paloverde/core/types.hpp"

namespace paloverde::detail {

// How many elements ahead a pass asks for the corners it will read.
inline constexpr std::ptrdiff_t kPrefetchAhead = 8;
// The same for a walk over the elements around each vertex in turn (the vertex graph, the
// boundary faces): it does less with each element, so it asks further ahead (a large mesh's vertex
// graph is built 12-25% faster than eight ahead).
inline constexpr std::ptrdiff_t kPrefetchAroundAhead = 32;

// The coordinates (3 per vertex in xyz) of the `count` vertices at `vertices`.
inline void prefetch_corners(const VertexId* vertices, int count, const double* xyz) {
    for (int i = 0; i < count; ++i) {
        const double* p = xyz + 3 * static_cast<std::size_t>(vertices[i]);
        __builtin_prefetch(p);
        __builtin_prefetch(p + 2);  // a vertex may straddle two cache lines
    }
}

}  // namespace paloverde::detail
