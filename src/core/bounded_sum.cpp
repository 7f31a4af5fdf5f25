// BoundedSum::add_all and add_all_exact: the splitting of add() and add_exact(), several terms per
// instruction. The pieces of the terms lie on a common grid and their sums are exact, so adding
// them in lanes gives the bits that adding them one by one gives.
#include <cmath>
#include <cstddef>
#include <cstring>

#include "core/exact_sums.hpp"

#if defined(__x86_64__)
#define PALOVERDE_X86 1
#endif

namespace paloverde::detail {
namespace {

// The sums of the high and low pieces of the terms within the bound (the others count as 0
// here), and whether any term was outside it (or NaN).
struct Pieces {
    double high = 0.0, low = 0.0;
    bool outside = false;
};

struct Grid {
    double bound, pivot_high, pivot_low;

    // Exact: a term whose low piece is not exact (bits below the finer grid) counts as outside
    // too, as in add_exact().
    template <bool Exact>
    void split(double x, Pieces& p) const {
        if (!(std::abs(x) <= bound)) {
            p.outside = true;
            return;
        }
        const double high = (pivot_high + x) - pivot_high;
        const double rest = x - high;
        const double low = (pivot_low + rest) - pivot_low;
        if (Exact && low != rest) {
            p.outside = true;
            return;
        }
        p.high += high;
        p.low += low;
    }
};

// The loop over Width-double vectors (GCC's vector extension, which Clang shares), two at a
// time so that each running sum waits on one addition in two. Vectors stay inside: compiled
// into the AVX2 function below, it is AVX2 code; elsewhere SSE2.
template <int Width>
struct Vectors;
template <>
struct Vectors<2> {
    typedef double V __attribute__((vector_size(16)));
    typedef long long Mask __attribute__((vector_size(16)));
};
template <>
struct Vectors<4> {
    typedef double V __attribute__((vector_size(32)));
    typedef long long Mask __attribute__((vector_size(32)));
};

template <int Width, bool Exact>
[[gnu::always_inline]] inline Pieces simd_pieces(const Grid& g, const double* x, std::size_t count) {
    using V = typename Vectors<Width>::V;
    using Mask = typename Vectors<Width>::Mask;
    constexpr int kStep = 2 * Width;
    const V bound = V{} + g.bound, ph = V{} + g.pivot_high, pl = V{} + g.pivot_low;
    const Mask magnitude = Mask{} + 0x7fffffffffffffffLL;
    V high[2] = {}, low[2] = {};
    Mask inside = Mask{} - 1;
    std::size_t i = 0;
    for (; i + kStep <= count; i += kStep)
        for (int lane = 0; lane < 2; ++lane) {
            V v;
            std::memcpy(&v, x + i + lane * Width, sizeof v);
            const Mask in = (V)((Mask)v & magnitude) <= bound;  // all ones, or 0 (also for NaN)
            inside &= in;
            const V y = (V)((Mask)v & in);  // the term, or 0 outside the bound
            V h = (ph + y) - ph;
            const V rest = y - h;
            V l = (pl + rest) - pl;
            if constexpr (Exact) {
                const Mask exact = l == rest;
                inside &= exact;
                h = (V)((Mask)h & exact);
                l = (V)((Mask)l & exact);
            }
            high[lane] += h;
            low[lane] += l;
        }
    Pieces p;
    for (int lane = 0; lane < 2; ++lane)
        for (int k = 0; k < Width; ++k) {  // exact: the pieces share a grid
            p.high += high[lane][k];
            p.low += low[lane][k];
            p.outside = p.outside || inside[k] == 0;
        }
    for (; i < count; ++i) g.template split<Exact>(x[i], p);
    return p;
}

#ifdef PALOVERDE_X86
template <bool Exact>
Pieces pieces_sse2(const Grid& g, const double* x, std::size_t count) {
    return simd_pieces<2, Exact>(g, x, count);
}
template <bool Exact>
[[gnu::target("avx2")]] Pieces pieces_avx2(const Grid& g, const double* x, std::size_t count) {
    return simd_pieces<4, Exact>(g, x, count);
}
#endif

template <bool Exact>
Pieces pieces(const Grid& g, const double* x, std::size_t count, BoundedSum::Simd simd) {
#ifdef PALOVERDE_X86
    static const bool avx2 = __builtin_cpu_supports("avx2");
    return avx2 && simd == BoundedSum::Simd::best ? pieces_avx2<Exact>(g, x, count) : pieces_sse2<Exact>(g, x, count);
#else
    (void)simd;
    return simd_pieces<2, Exact>(g, x, count);
#endif
}

}  // namespace

void BoundedSum::add_all(const double* x, std::size_t count, Simd simd) {
    if (count == 0) return;
    // The pieces of up to kFlush terms sum exactly: make room for these.
    if (count_ + static_cast<int>(count) > kFlush) flush();
    const Pieces p = pieces<false>(Grid{bound_, pivot_[0], pivot_[1]}, x, count, simd);
    partial_[0] += p.high;
    partial_[1] += p.low;
    count_ += static_cast<int>(count);
    if (p.outside)
        for (std::size_t i = 0; i < count; ++i)
            if (!(std::abs(x[i]) <= bound_)) exact_.add(x[i]);
    if (count_ == kFlush) flush();
}

void BoundedSum::add_all_exact(const double* x, std::size_t count, Simd simd) {
    if (count == 0) return;
    if (count_ + static_cast<int>(count) > kFlush) flush();
    const Grid grid{bound_, pivot_[0], pivot_[1]};
    const Pieces p = pieces<true>(grid, x, count, simd);
    partial_[0] += p.high;
    partial_[1] += p.low;
    count_ += static_cast<int>(count);
    if (p.outside)
        for (std::size_t i = 0; i < count; ++i) {
            Pieces one;
            grid.split<true>(x[i], one);
            if (one.outside) exact_.add(x[i]);
        }
    if (count_ == kFlush) flush();
}

}  // namespace paloverde::detail
