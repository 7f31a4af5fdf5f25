#pragma once
// Deterministic parallel sums: the terms are summed in fixed blocks (each in order), and the
// block partials combined in order with compensated addition. The result does not depend on the
// number of threads, and is accurate to about one rounding of the total.
#include <array>
#include <cstddef>
#include <vector>

namespace paloverde::detail {

inline constexpr std::size_t kSumBlock = 4096;
// Loops shorter than this many items run on one thread: starting threads costs more, and on a
// loaded machine waiting threads spin and steal the worker's time.
inline constexpr std::size_t kParallelThreshold = 32768;

// Knuth's TwoSum accumulation: hi + lo carries the running sum exactly.
struct CompensatedSum {
    double hi = 0.0, lo = 0.0;
    void add(double x) {
        const double s = hi + x;
        const double bp = s - hi;
        lo += (hi - (s - bp)) + (x - bp);
        hi = s;
    }
    double value() const { return hi + lo; }
};

// Calls term(i, partial) for i in [0, n); `term` adds its K contributions into partial[0..K).
template <int K, class Term>
std::array<double, K> blocked_sums(std::size_t n, Term term) {
    const std::size_t blocks = (n + kSumBlock - 1) / kSumBlock;
    std::vector<std::array<double, K>> partial(blocks);
#pragma omp parallel for schedule(static) if (n > kParallelThreshold)
    for (std::ptrdiff_t b = 0; b < static_cast<std::ptrdiff_t>(blocks); ++b) {
        std::array<double, K> acc{};
        const std::size_t end = std::min(n, (static_cast<std::size_t>(b) + 1) * kSumBlock);
        for (std::size_t i = static_cast<std::size_t>(b) * kSumBlock; i < end; ++i) term(i, acc);
        partial[static_cast<std::size_t>(b)] = acc;
    }
    std::array<CompensatedSum, K> total{};
    for (const auto& p : partial)
        for (int k = 0; k < K; ++k) total[k].add(p[k]);
    std::array<double, K> out{};
    for (int k = 0; k < K; ++k) out[k] = total[k].value();
    return out;
}

}  // namespace paloverde::detail
