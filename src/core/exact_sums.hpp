#pragma once
// Exact sums over index ranges, split among threads: each thread keeps its own accumulators,
// and since the accumulation is exact the combined result does not depend on the thread count.
#include <array>
#include <cstddef>

#include "core/blocked_sum.hpp"
#include "paloverde/core/exact_sum.hpp"

namespace paloverde::detail {

// Calls term(i, sums) for i in [0, n); `term` adds its K contributions with sums[k].add(x).
template <int K, class Term>
std::array<ExactSum, K> exact_sums(std::size_t n, Term term) {
    std::array<ExactSum, K> total{};
#pragma omp parallel if (n > kParallelThreshold)
    {
        std::array<ExactSum, K> mine{};
#pragma omp for schedule(static) nowait
        for (std::ptrdiff_t i = 0; i < static_cast<std::ptrdiff_t>(n); ++i) term(static_cast<std::size_t>(i), mine);
#pragma omp critical(paloverde_exact_sums)
        for (int k = 0; k < K; ++k) total[k] += mine[k];
    }
    return total;
}

}  // namespace paloverde::detail
