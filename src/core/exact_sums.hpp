#pragma once
// Exact sums over index ranges, split among threads: each thread keeps its own accumulators,
// and since the accumulation is exact the combined result does not depend on the thread count
// (nor, once reduced, on the number of processes).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <utility>

#include "core/blocked_sum.hpp"
#include "paloverde/core/exact_sum.hpp"

namespace paloverde::detail {

// A fast accumulator for terms whose magnitude is known not to exceed `bound`, the same on every
// process. With 2^e >= bound, each term is rounded to a multiple of about 2^(e - 84), the same
// way wherever it is added, by splitting it against two fixed pivots: (pivot + x) - pivot keeps
// the bits of x above the pivot's last place, exactly, and the remainder goes to the next pivot.
// Up to kFlush such pieces sum exactly in a double (they share a grid and cannot outgrow the
// pivot), and are then moved into an ExactSum. The result is thus as order-free as ExactSum and
// within n 2^(e - 84) of the true sum, with only additions per term. Terms above the bound (NaN,
// or any term when the bound is not a positive number) are added to the ExactSum directly.
class BoundedSum {
public:
    static constexpr int kFlush = 1024;

    explicit BoundedSum(double bound) {
        if (std::isfinite(bound) && bound > 0.0) {
            int e = 0;
            std::frexp(bound, &e);  // bound <= 2^e
            bound_ = bound;
            // kFlush terms of up to 2^e stay below 2^(e + 11): a grid of 2^(e - 42) or finer.
            pivot_[0] = std::ldexp(1.0, e + 11);
            pivot_[1] = std::ldexp(1.0, e - 31);  // remainders are below 2^(e - 42)
        }
    }
    void add(double x) {
        if (!(std::abs(x) <= bound_)) {
            exact_.add(x);
            return;
        }
        const double high = (pivot_[0] + x) - pivot_[0];
        const double rest = x - high;  // exact
        partial_[0] += high;
        partial_[1] += (pivot_[1] + rest) - pivot_[1];
        if (++count_ == kFlush) flush();
    }
    // As add(), but exact: a term with bits below the finer grid (one far smaller than the bound)
    // goes whole to the ExactSum. The pieces are exact, so the result is exactly the terms' sum.
    void add_exact(double x) {
        const double high = (pivot_[0] + x) - pivot_[0];
        const double rest = x - high;  // exact
        const double low = (pivot_[1] + rest) - pivot_[1];
        if (!(std::abs(x) <= bound_) || low != rest) {
            exact_.add(x);
            return;
        }
        partial_[0] += high;
        partial_[1] += low;
        if (++count_ == kFlush) flush();
    }
    // Adds x[0], ..., x[count - 1] (count <= kFlush): the same as add() on each, in SIMD
    // instructions (bounded_sum.cpp): AVX2 where the processor has it, else SSE2, which tests
    // can ask for.
    enum class Simd { best, sse2 };
    void add_all(const double* x, std::size_t count, Simd simd = Simd::best);
    // Adds x[0], ..., x[count - 1] (count <= kFlush): add_exact() on each, in SIMD instructions.
    void add_all_exact(const double* x, std::size_t count, Simd simd = Simd::best);
    // Adds this sum to an ExactSum, exactly.
    void add_to(ExactSum& sum) {
        flush();
        sum += exact_;
    }

private:
    void flush() {
        exact_.add(partial_[0]);
        exact_.add(partial_[1]);
        partial_ = {};
        count_ = 0;
    }

    double bound_ = -1.0;  // no term is within a negative bound
    std::array<double, 2> pivot_{};
    std::array<double, 2> partial_{};
    int count_ = 0;
    ExactSum exact_;
};

// Calls term(i, sums) for i in [0, n); `term` adds its K contributions with sums[k].add(x). The
// terms are collected a block at a time and added as bounded sums under the block's own largest
// finite magnitude (BoundedSum::add_all_exact): exactly, so the result is ExactSum's of the terms
// one by one, bit for bit, at a few additions per term instead of a digit update each.
template <int K, class Term>
std::array<ExactSum, K> exact_sums(std::size_t n, Term term) {
    // What `term` sees as acc[k].
    struct Collector {
        std::size_t filled = 0;
        alignas(32) std::array<double, BoundedSum::kFlush> buffer;
        ExactSum sum;
        void add(double x) {
            buffer[filled] = x;
            if (++filled == buffer.size()) empty();
        }
        void empty() {
            if (filled == 0) return;
            double bound = 0.0;  // an infinite or NaN term is above it, and takes the exact path
            for (std::size_t i = 0; i < filled; ++i) {
                const double magnitude = std::abs(buffer[i]);
                bound = magnitude > bound && magnitude <= std::numeric_limits<double>::max() ? magnitude : bound;
            }
            BoundedSum pieces(bound);
            pieces.add_all_exact(buffer.data(), filled);
            pieces.add_to(sum);
            filled = 0;
        }
    };
    std::array<ExactSum, K> total{};
#pragma omp parallel if (n > kParallelThreshold)
    {
        std::array<Collector, K> mine;
#pragma omp for schedule(static) nowait
        for (std::ptrdiff_t i = 0; i < static_cast<std::ptrdiff_t>(n); ++i) term(static_cast<std::size_t>(i), mine);
#pragma omp critical(paloverde_exact_sums)
        for (int k = 0; k < K; ++k) {
            mine[k].empty();
            total[k] += mine[k].sum;
        }
    }
    return total;
}

// As exact_sums, for terms bounded as BoundedSum says: bounds[k] for the k-th sum. The terms are
// collected in small buffers and added a buffer at a time with BoundedSum::add_all (the sums
// being exact, the result is that of adding them one by one).
template <int K, class Term>
std::array<ExactSum, K> bounded_sums(std::size_t n, const std::array<double, K>& bounds, Term term) {
    constexpr std::size_t kBuffer = 256;
    // What `term` sees as acc[k]: add() stores the term, and hands a full buffer on.
    struct Collector {
        explicit Collector(double bound) : sum(bound) {}
        BoundedSum sum;
        std::size_t filled = 0;
        alignas(32) std::array<double, kBuffer> buffer;
        void add(double x) {
            buffer[filled] = x;
            if (++filled == kBuffer) empty();
        }
        void empty() {
            sum.add_all(buffer.data(), filled);
            filled = 0;
        }
    };
    std::array<ExactSum, K> total{};
#pragma omp parallel if (n > kParallelThreshold)
    {
        auto mine = [&]<std::size_t... k>(std::index_sequence<k...>) {
            return std::array<Collector, K>{Collector(bounds[k])...};
        }(std::make_index_sequence<K>{});
#pragma omp for schedule(static) nowait
        for (std::ptrdiff_t i = 0; i < static_cast<std::ptrdiff_t>(n); ++i) term(static_cast<std::size_t>(i), mine);
#pragma omp critical(paloverde_exact_sums)
        for (int k = 0; k < K; ++k) {
            mine[k].empty();
            mine[k].sum.add_to(total[k]);
        }
    }
    return total;
}

// As bounded_sums, with the terms made a block at a time: fill(first, count, terms) writes the
// k-th term of index first + i to terms[k][i], for i < count (at most kBlock). A fill that is a
// plain loop vectorizes, where terms handed over one at a time do not. The same sums, bit for bit.
template <int K, class Fill>
std::array<ExactSum, K> bounded_block_sums(std::size_t n, const std::array<double, K>& bounds, Fill fill) {
    constexpr std::size_t kBlock = 256;
    const std::size_t blocks = (n + kBlock - 1) / kBlock;
    std::array<ExactSum, K> total{};
#pragma omp parallel if (n > kParallelThreshold)
    {
        auto mine = [&]<std::size_t... k>(std::index_sequence<k...>) {
            return std::array<BoundedSum, K>{BoundedSum(bounds[k])...};
        }(std::make_index_sequence<K>{});
        alignas(32) std::array<std::array<double, kBlock>, K> terms;
#pragma omp for schedule(static) nowait
        for (std::ptrdiff_t b = 0; b < static_cast<std::ptrdiff_t>(blocks); ++b) {
            const std::size_t first = static_cast<std::size_t>(b) * kBlock;
            const std::size_t count = std::min(kBlock, n - first);
            std::array<double*, K> out;
            for (int k = 0; k < K; ++k) out[k] = terms[k].data();
            fill(first, count, out);
            for (int k = 0; k < K; ++k) mine[k].add_all(terms[k].data(), count);
        }
#pragma omp critical(paloverde_exact_sums)
        for (int k = 0; k < K; ++k) mine[k].add_to(total[k]);
    }
    return total;
}

// The exact sum of x, several terms to an instruction: bounded sums under the largest magnitude,
// add_all_exact's (terms far below it, infinite or NaN take the slower exact path), so the result
// is ExactSum's of the terms one by one, bit for bit.
inline ExactSum exact_sum(std::span<const double> x) {
    double bound = 0.0;
    for (double t : x) bound = std::max(bound, std::abs(t));  // NaN leaves it: the exact path takes NaN
    const auto n = static_cast<std::ptrdiff_t>(x.size());
    constexpr std::ptrdiff_t kBlock = BoundedSum::kFlush;
    ExactSum total;
#pragma omp parallel if (x.size() > kParallelThreshold)
    {
        BoundedSum mine(bound);
#pragma omp for schedule(static) nowait
        for (std::ptrdiff_t first = 0; first < n; first += kBlock)
            mine.add_all_exact(x.data() + first, static_cast<std::size_t>(std::min(kBlock, n - first)));
#pragma omp critical(paloverde_exact_sums)
        mine.add_to(total);
    }
    return total;
}

}  // namespace paloverde::detail
