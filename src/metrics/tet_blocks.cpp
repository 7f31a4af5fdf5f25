// GCC's -ftrapping-math (the default) forbids computing the values a select discards (those of
// degenerate elements) unconditionally, and so stops the loops below from vectorizing. Nothing
// reads the FP exception flags; the results are the same either way. Contraction into FMA is
// off: G++ contracts by default even in ISO mode, and AVX-512 brings FMA instructions with it.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("no-trapping-math", "fp-contract=off")
#endif

#include "tet_blocks.hpp"

#include <array>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <utility>

#include "cube_root.hpp"
#include "kernels.hpp"

#if defined(__x86_64__)
#include <immintrin.h>
#define PALOVERDE_X86 1
#endif

namespace paloverde::metrics {
namespace {

// The loops below repeat the formulas of TetGeometry, tet_aspect() and UntangleHybrid::blend()
// operation for operation, with selects instead of the early return for degenerate elements,
// so that they vectorize and round exactly like the scalar code.

// Square roots of a block with explicit SIMD instructions (correctly rounded, as std::sqrt):
// the library's -frounding-math (for CGAL) makes std::sqrt a call the vectorizer leaves alone.
struct Sqrt128 {
    [[gnu::always_inline]] static void run(const double* in, double* out) {
#ifdef PALOVERDE_X86
        for (int j = 0; j < kTetBlock; j += 2) _mm_store_pd(out + j, _mm_sqrt_pd(_mm_load_pd(in + j)));
#else
        for (int j = 0; j < kTetBlock; ++j) out[j] = std::sqrt(in[j]);
#endif
    }
};
#ifdef PALOVERDE_X86
struct Sqrt256 {
    [[gnu::target("avx2")]] static void run(const double* in, double* out) {
        for (int j = 0; j < kTetBlock; j += 4) _mm256_store_pd(out + j, _mm256_sqrt_pd(_mm256_load_pd(in + j)));
    }
};
struct Sqrt512 {
    [[gnu::target("avx512f")]] static void run(const double* in, double* out) {
        // The masked form with every lane set: _mm512_sqrt_pd's undefined pass-through operand
        // trips GCC 12's -Wmaybe-uninitialized.
        for (int j = 0; j < kTetBlock; j += 8) {
            const __m512d a = _mm512_load_pd(in + j);
            _mm512_store_pd(out + j, _mm512_mask_sqrt_pd(a, static_cast<__mmask8>(0xFF), a));
        }
    }
};
#endif

[[gnu::always_inline]] inline void corners_of(const TetBlock& x, int j, P* c) {
    for (int i = 0; i < 4; ++i) c[i] = {x.at[3 * i][j], x.at[3 * i + 1][j], x.at[3 * i + 2][j]};
}
[[gnu::always_inline]] inline std::array<P, 4> corners_of(const TetBlock& x, int j) {
    std::array<P, 4> c;
    corners_of(x, j, c.data());
    return c;
}

// Element j's signed volume and squared edge sum; with Gradient, the volume's gradient too.
template <bool Gradient>
[[gnu::always_inline]] inline void measure(const TetBlock& x, int j, double* volume, double* edge_sum, TetBlock* dvolume) {
    P c[4], dv[4];
    corners_of(x, j, c);
    volume[j] = TetGeometry::tet_volume(c, dv);
    edge_sum[j] = TetGeometry::tet_edge_sum(c);
    if constexpr (Gradient)
        for (int i = 0; i < 4; ++i) {
            dvolume->at[3 * i][j] = dv[i].x;
            dvolume->at[3 * i + 1][j] = dv[i].y;
            dvolume->at[3 * i + 2][j] = dv[i].z;
        }
}

// Quality into quality[j], signed volume into volume[j]; with Gradient, also the gradients of
// both. Two loops around the square roots: the first measures, the second rates.
template <class Sqrt, bool Gradient>
[[gnu::always_inline]] inline void aspect_loop(const TetBlock& x, double* quality, TetBlock* gradient, double* volume,
                                               TetBlock* dvolume) {
    alignas(64) double edge_sum[kTetBlock], root[kTetBlock];
    for (int j = 0; j < kTetBlock; ++j) measure<Gradient>(x, j, volume, edge_sum, dvolume);
    Sqrt::run(edge_sum, root);
    for (int j = 0; j < kTetBlock; ++j) {
        const double l = edge_sum[j];
        const bool valid = l > 0.0;
        const double inv = 1.0 / (l * root[j]);
        const double q = kTetAspectScale * volume[j] * inv;
        quality[j] = valid ? q : 0.0;
        if constexpr (Gradient) {
            P c[4], de[4];
            corners_of(x, j, c);
            TetGeometry::tet_dedge_sum(c, de);
            const double a = kTetAspectScale * inv, b = 1.5 * q / l;
            for (int i = 0; i < 4; ++i) {
                const P dv{dvolume->at[3 * i][j], dvolume->at[3 * i + 1][j], dvolume->at[3 * i + 2][j]};
                const P g = a * dv - b * de[i];
                gradient->at[3 * i][j] = valid ? g.x : 0.0;
                gradient->at[3 * i + 1][j] = valid ? g.y : 0.0;
                gradient->at[3 * i + 2][j] = valid ? g.z : 0.0;
            }
        }
    }
}

template <class Sqrt>
[[gnu::always_inline]] inline void aspect(const TetBlock& x, double* quality, TetBlock* gradient) {
    alignas(64) double volume[kTetBlock];
    if (gradient) {
        TetBlock dvolume;
        aspect_loop<Sqrt, true>(x, quality, gradient, volume, &dvolume);
    } else {
        aspect_loop<Sqrt, false>(x, quality, nullptr, volume, nullptr);
    }
}

template <class Sqrt, bool Gradient>
[[gnu::always_inline]] inline void hybrid_loop(const TetBlock& x, const double* reference_volume, double alpha,
                                               double* quality, TetBlock* gradient) {
    alignas(64) double q[kTetBlock], volume[kTetBlock], e[kTetBlock];
    TetBlock qgrad, dvolume;
    aspect_loop<Sqrt, Gradient>(x, q, &qgrad, volume, &dvolume);
    // exp has no vector version that rounds like the scalar one: a scalar loop.
    for (int j = 0; j < kTetBlock; ++j) e[j] = std::exp(alpha * (volume[j] / reference_volume[j]));
    for (int j = 0; j < kTetBlock; ++j) {
        const double v = volume[j] / reference_volume[j];
        const double w = 1.0 / (1.0 + e[j]);
        quality[j] = w * v + (1.0 - w) * q[j];
        if constexpr (Gradient) {
            // dw/dv = -alpha w (1 - w)
            const double dq_dvolume = (w - alpha * w * (1.0 - w) * (v - q[j])) / reference_volume[j];
            for (int k = 0; k < 12; ++k) gradient->at[k][j] = dq_dvolume * dvolume.at[k][j] + (1.0 - w) * qgrad.at[k][j];
        }
    }
}

template <class Sqrt>
[[gnu::always_inline]] inline void hybrid(const TetBlock& x, const double* reference_volume, double alpha,
                                          double* quality, TetBlock* gradient) {
    if (gradient) hybrid_loop<Sqrt, true>(x, reference_volume, alpha, quality, gradient);
    else hybrid_loop<Sqrt, false>(x, reference_volume, alpha, quality, nullptr);
}

// The lanes' 3 x 3 maps side by side, entry by entry across the lanes (m[k][i][lane]), so that
// the loops over lanes vectorize: lane by lane with scalar loads, or with AVX2 (AVX-512) four
// (eight) lanes at a time, each lane's first eight entries in two loads (one), regrouped across
// the lanes by shuffles, and the ninth alone. (Gathers, one instruction per entry for eight lanes,
// measured up to twice as slow for a whole pass with targets: docs/targets.md.) The values are the
// same.
struct LayOutScalar {
    [[gnu::always_inline]] static void run(const CornerMap* const* maps, double (&m)[3][3][kTetBlock]) {
        for (int k = 0; k < 3; ++k)
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < kTetBlock; ++j) m[k][i][j] = (*maps[j])[k][i];
    }
};
#ifdef PALOVERDE_X86
struct LayOut256 {
    [[gnu::target("avx2")]] static void run(const CornerMap* const* maps, double (&m)[3][3][kTetBlock]) {
        static_assert(sizeof(CornerMap) == 9 * sizeof(double));
        double* entry[9];
        for (int c = 0; c < 9; ++c) entry[c] = &m[c / 3][c % 3][0];
        for (int j = 0; j < kTetBlock; j += 4) {
            for (int half = 0; half < 2; ++half) {
                __m256d row[4];
                // row[r]: lane j + r's entries 4 * half to 4 * half + 3; then a 4 x 4 transpose.
                for (int r = 0; r < 4; ++r) row[r] = _mm256_loadu_pd(maps[j + r]->front().data() + 4 * half);
                const __m256d t0 = _mm256_unpacklo_pd(row[0], row[1]), t1 = _mm256_unpackhi_pd(row[0], row[1]);
                const __m256d t2 = _mm256_unpacklo_pd(row[2], row[3]), t3 = _mm256_unpackhi_pd(row[2], row[3]);
                _mm256_store_pd(entry[4 * half + 0] + j, _mm256_permute2f128_pd(t0, t2, 0x20));
                _mm256_store_pd(entry[4 * half + 1] + j, _mm256_permute2f128_pd(t1, t3, 0x20));
                _mm256_store_pd(entry[4 * half + 2] + j, _mm256_permute2f128_pd(t0, t2, 0x31));
                _mm256_store_pd(entry[4 * half + 3] + j, _mm256_permute2f128_pd(t1, t3, 0x31));
            }
            for (int r = 0; r < 4; ++r) entry[8][j + r] = (*maps[j + r])[2][2];
        }
    }
};
struct LayOut512 {
    [[gnu::target("avx512f")]] static void run(const CornerMap* const* maps, double (&m)[3][3][kTetBlock]) {
        static_assert(sizeof(CornerMap) == 9 * sizeof(double));
        // Index vectors for _mm512_permutex2var_pd(a, index, b): 0-7 pick a's elements, 8-15 b's.
        const __m512i pairs_low = _mm512_set_epi64(13, 12, 5, 4, 9, 8, 1, 0);
        const __m512i pairs_high = _mm512_set_epi64(15, 14, 7, 6, 11, 10, 3, 2);
        const __m512i halves_low = _mm512_set_epi64(11, 10, 9, 8, 3, 2, 1, 0);
        const __m512i halves_high = _mm512_set_epi64(15, 14, 13, 12, 7, 6, 5, 4);
        double* entry[9];
        for (int c = 0; c < 9; ++c) entry[c] = &m[c / 3][c % 3][0];
        for (int j = 0; j < kTetBlock; j += 8) {
            __m512d row[8];
            for (int r = 0; r < 8; ++r) row[r] = _mm512_loadu_pd(maps[j + r]->front().data());
            // row[r]: lane j + r's entries 0..7. Rows interleaved pairwise: t[2p] holds entries
            // 0, 2, 4, 6 of rows 2p and 2p + 1, t[2p + 1] entries 1, 3, 5, 7 (the masked forms
            // with every lane set, as in Sqrt512).
            __m512d t[8], u[8];
            const auto all = static_cast<__mmask8>(0xFF);
            for (int p = 0; p < 4; ++p) {
                t[2 * p] = _mm512_mask_unpacklo_pd(row[2 * p], all, row[2 * p], row[2 * p + 1]);
                t[2 * p + 1] = _mm512_mask_unpackhi_pd(row[2 * p], all, row[2 * p], row[2 * p + 1]);
            }
            // u[4h + e]: rows 4h..4h+3 of entry e (first half) and entry e + 4 (second half), e < 4.
            for (int h = 0; h < 2; ++h) {
                const __m512d* q = t + 4 * h;
                u[4 * h + 0] = _mm512_permutex2var_pd(q[0], pairs_low, q[2]);
                u[4 * h + 1] = _mm512_permutex2var_pd(q[1], pairs_low, q[3]);
                u[4 * h + 2] = _mm512_permutex2var_pd(q[0], pairs_high, q[2]);
                u[4 * h + 3] = _mm512_permutex2var_pd(q[1], pairs_high, q[3]);
            }
            for (int e = 0; e < 4; ++e) {
                _mm512_store_pd(entry[e] + j, _mm512_permutex2var_pd(u[e], halves_low, u[4 + e]));
                _mm512_store_pd(entry[e + 4] + j, _mm512_permutex2var_pd(u[e], halves_high, u[4 + e]));
            }
            for (int r = 0; r < 8; ++r) entry[8][j + r] = (*maps[j + r])[2][2];
        }
    }
};
#endif

template <class LayOut = LayOutScalar>
[[gnu::always_inline]] inline void map_loop(const CornerMap* const* maps, const CornerMap* const* roots, TetBlock& x) {
    alignas(64) double m[3][3][kTetBlock];
    LayOut::run(maps, m);
    for (int j = 0; j < kTetBlock; ++j) {
        double e[3][3];
        for (int k = 0; k < 3; ++k)
            for (int d = 0; d < 3; ++d) e[k][d] = x.at[3 * (k + 1) + d][j] - x.at[d][j];
        for (int i = 0; i < 3; ++i)
            for (int d = 0; d < 3; ++d) {
                double sum = 0.0;
                for (int k = 0; k < 3; ++k) sum += e[k][d] * m[k][i][j];
                x.at[3 * (i + 1) + d][j] = x.at[d][j] + sum;
            }
    }
    if (!roots) return;
    LayOut::run(roots, m);
    for (int j = 0; j < kTetBlock; ++j)
        for (int i = 0; i < 4; ++i) {
            const double y[3] = {x.at[3 * i][j], x.at[3 * i + 1][j], x.at[3 * i + 2][j]};
            for (int r = 0; r < 3; ++r) x.at[3 * i + r][j] = m[r][0][j] * y[0] + m[r][1][j] * y[1] + m[r][2][j] * y[2];
        }
}

template <class LayOut = LayOutScalar>
[[gnu::always_inline]] inline void unmap_loop(const CornerMap* const* maps, const CornerMap* const* roots, TetBlock& g) {
    alignas(64) double m[3][3][kTetBlock];
    if (roots) {
        LayOut::run(roots, m);
        for (int j = 0; j < kTetBlock; ++j)
            for (int i = 0; i < 4; ++i) {
                const double gz[3] = {g.at[3 * i][j], g.at[3 * i + 1][j], g.at[3 * i + 2][j]};
                for (int c = 0; c < 3; ++c) g.at[3 * i + c][j] = m[0][c][j] * gz[0] + m[1][c][j] * gz[1] + m[2][c][j] * gz[2];
            }
    }
    LayOut::run(maps, m);
    for (int j = 0; j < kTetBlock; ++j) {
        double gy[4][3], total[3] = {0.0, 0.0, 0.0};
        for (int i = 0; i < 4; ++i)
            for (int d = 0; d < 3; ++d) gy[i][d] = g.at[3 * i + d][j], total[d] += gy[i][d];
        for (int k = 0; k < 3; ++k)
            for (int d = 0; d < 3; ++d) {
                double sum = 0.0;
                for (int i = 0; i < 3; ++i) sum += gy[i + 1][d] * m[k][i][j];
                g.at[3 * (k + 1) + d][j] = sum;
                total[d] -= sum;
            }
        for (int d = 0; d < 3; ++d) g.at[d][j] = total[d];
    }
}

// MeanRatio::tet() and, Sized, ShapeSize::tet(), operation for operation: MeanRatio::of(), then
// shape_orientation_size() with no orientation factor (h = 1, which the scalar products multiply
// by exactly).
template <class Sqrt, bool Gradient, bool Sized>
[[gnu::always_inline]] inline void mean_ratio_loop(const TetBlock& x, const double* reference_volume, double* quality,
                                                   TetBlock* gradient) {
    alignas(64) double volume[kTetBlock], edge_sum[kTetBlock], root[kTetBlock];
    TetBlock dvolume;
    for (int j = 0; j < kTetBlock; ++j) measure<Gradient>(x, j, volume, edge_sum, &dvolume);
    Sqrt::run(edge_sum, root);
    for (int j = 0; j < kTetBlock; ++j) root[j] = MeanRatio::floored_volume(volume[j], edge_sum[j], root[j]);
    cube_roots<kTetBlock>(root);
    for (int j = 0; j < kTetBlock; ++j) {
        const double l = edge_sum[j];
        const bool valid = l > 0.0;
        const double m = valid ? MeanRatio::rated(volume[j], l, root[j]) : 0.0;
        const SizeTerm size(Sized ? volume[j] / reference_volume[j] : 1.0);
        quality[j] = Sized ? m * size.value : m;
        if constexpr (Gradient) {
            P c[4], de[4];
            corners_of(x, j, c);
            TetGeometry::tet_dedge_sum(c, de);
            const double dq_dv = 12.0 * 2.0 / root[j] / l, by_edge_sum = m / l;
            const double by_volume = Sized ? m * size.derivative / reference_volume[j] : 0.0;
            for (int i = 0; i < 4; ++i) {
                const P dv{dvolume.at[3 * i][j], dvolume.at[3 * i + 1][j], dvolume.at[3 * i + 2][j]};
                const P dm = dq_dv * dv - by_edge_sum * de[i];
                const P shape{valid ? dm.x : 0.0, valid ? dm.y : 0.0, valid ? dm.z : 0.0};
                const P g = Sized ? size.value * shape + by_volume * dv : shape;
                gradient->at[3 * i][j] = g.x;
                gradient->at[3 * i + 1][j] = g.y;
                gradient->at[3 * i + 2][j] = g.z;
            }
        }
    }
}

template <class Sqrt, bool Sized>
[[gnu::always_inline]] inline void mean_ratio(const TetBlock& x, const double* reference_volume, double* quality,
                                              TetBlock* gradient) {
    if (gradient) mean_ratio_loop<Sqrt, true, Sized>(x, reference_volume, quality, gradient);
    else mean_ratio_loop<Sqrt, false, Sized>(x, reference_volume, quality, nullptr);
}

// RegularizedEnergy::energy<3>, operation for operation.
template <class Sqrt, bool Gradient>
[[gnu::always_inline]] inline void energy_loop(const TetBlock& x, const double* reference_volume, double epsilon,
                                               double theta, double* quality, TetBlock* gradient) {
    alignas(64) double volume[kTetBlock], edge_sum[kTetBlock], v[kTetBlock], r[kTetBlock], chi[kTetBlock],
        root[kTetBlock];
    TetBlock dvolume;
    for (int j = 0; j < kTetBlock; ++j) {
        measure<Gradient>(x, j, volume, edge_sum, &dvolume);
        v[j] = volume[j] / reference_volume[j];
        r[j] = epsilon * epsilon + v[j] * v[j];
    }
    Sqrt::run(r, r);
    for (int j = 0; j < kTetBlock; ++j) {
        chi[j] = v[j] >= 0.0 ? 0.5 * (v[j] + r[j]) : 0.5 * epsilon * epsilon / (r[j] - v[j]);
        root[j] = 9.0 * (reference_volume[j] * chi[j]) * (reference_volume[j] * chi[j]);
    }
    cube_roots<kTetBlock>(root);
    for (int j = 0; j < kTetBlock; ++j) {
        const double per_edge_sum = 1.0 / (12.0 * root[j]);
        const double f1 = edge_sum[j] * per_edge_sum;
        const double f2 = 0.5 * (v[j] * v[j] + 1.0) / chi[j];
        quality[j] = -((1.0 - theta) * f1 + theta * f2);
        if constexpr (Gradient) {
            P c[4], de[4];
            corners_of(x, j, c);
            TetGeometry::tet_dedge_sum(c, de);
            const double df_dv = -(1.0 - theta) * (2.0 / 3) * f1 / r[j] + theta * (v[j] / chi[j] - f2 / r[j]);
            const double a = -df_dv / reference_volume[j], b = (1.0 - theta) * per_edge_sum;
            for (int i = 0; i < 4; ++i) {
                const P dv{dvolume.at[3 * i][j], dvolume.at[3 * i + 1][j], dvolume.at[3 * i + 2][j]};
                const P g = a * dv - b * de[i];
                gradient->at[3 * i][j] = g.x;
                gradient->at[3 * i + 1][j] = g.y;
                gradient->at[3 * i + 2][j] = g.z;
            }
        }
    }
}

template <class Sqrt>
[[gnu::always_inline]] inline void energy(const TetBlock& x, const double* reference_volume, double epsilon,
                                          double theta, double* quality, TetBlock* gradient) {
    if (gradient) energy_loop<Sqrt, true>(x, reference_volume, epsilon, theta, quality, gradient);
    else energy_loop<Sqrt, false>(x, reference_volume, epsilon, theta, quality, nullptr);
}

// The report's value-only kernels, on the pieces of kernels.hpp they share with the scalar ones.
template <class Sqrt>
[[gnu::always_inline]] inline void inverse_condition(const TetBlock& x, double* quality) {
    alignas(64) double det[kTetBlock], n[kTetBlock], c[kTetBlock];
    for (int j = 0; j < kTetBlock; ++j) {
        const InverseCondition::Frame f(corners_of(x, j).data());
        det[j] = f.det();
        n[j] = f.norm_squared();
        c[j] = f.adjugate_norm_squared();
    }
    Sqrt::run(n, n);
    Sqrt::run(c, c);
    for (int j = 0; j < kTetBlock; ++j) {
        const double nc = n[j] * c[j];
        quality[j] = nc > 0.0 ? 3.0 * det[j] / nc : 0.0;
    }
}

// The shortest and longest edges from the squared lengths, rooted after: the square root rounds
// monotonically, so the root of the least square is the least root, as the scalar kernel finds it.
template <class Sqrt>
[[gnu::always_inline]] inline void edge_ratio(const TetBlock& x, double* quality) {
    alignas(64) double volume[kTetBlock], shortest[kTetBlock], longest[kTetBlock];
    for (int j = 0; j < kTetBlock; ++j) {
        const std::array<P, 4> c = corners_of(x, j);
        double low = INFINITY, high = 0.0;
        for (const auto& [p, q] : kTetEdges) {
            const P d = c[q] - c[p];
            const double l = dot(d, d);
            low = l < low ? l : low;
            high = l > high ? l : high;
        }
        shortest[j] = low;
        longest[j] = high;
        P dvolume[4];
        volume[j] = TetGeometry::tet_volume(c.data(), dvolume);
    }
    Sqrt::run(shortest, shortest);
    Sqrt::run(longest, longest);
    for (int j = 0; j < kTetBlock; ++j) {
        const double orientation = sign_of(volume[j]);
        quality[j] = !(longest[j] > 0.0) || orientation == 0.0 ? 0.0 : orientation * (shortest[j] / longest[j]);
    }
}

[[gnu::always_inline]] inline void scaled_volume(const TetBlock& x, const double* reference_volume, double* quality) {
    alignas(64) double volume[kTetBlock], edge_sum[kTetBlock];
    for (int j = 0; j < kTetBlock; ++j) measure<false>(x, j, volume, edge_sum, nullptr);
    for (int j = 0; j < kTetBlock; ++j) quality[j] = volume[j] / reference_volume[j];
}

template <class Sqrt>
[[gnu::always_inline]] inline void min_dihedral(const TetBlock& x, double* quality) {
    alignas(64) double volume[kTetBlock], edge_sum[kTetBlock], length[4][kTetBlock], sine[kTetBlock],
        cosine[kTetBlock];
    TetBlock dvolume;
    for (int j = 0; j < kTetBlock; ++j) {
        measure<true>(x, j, volume, edge_sum, &dvolume);
        for (int k = 0; k < 4; ++k) {
            const P n{dvolume.at[3 * k][j], dvolume.at[3 * k + 1][j], dvolume.at[3 * k + 2][j]};
            length[k][j] = dot(n, n);
        }
    }
    for (auto& l : length) Sqrt::run(l, l);
    for (int j = 0; j < kTetBlock; ++j) {
        P n[4], u, w;
        double l[4];
        for (int k = 0; k < 4; ++k) {
            n[k] = {dvolume.at[3 * k][j], dvolume.at[3 * k + 1][j], dvolume.at[3 * k + 2][j]};
            l[k] = length[k][j];
        }
        MinDihedralAngle::widest_pair(n, l, u, w);
        const P normal = cross(u, w);
        sine[j] = dot(normal, normal);
        cosine[j] = -dot(u, w);
    }
    Sqrt::run(sine, sine);
    // atan2 has no vector version that rounds like the scalar one: a scalar loop.
    for (int j = 0; j < kTetBlock; ++j) quality[j] = MinDihedralAngle::degrees(volume[j], std::atan2(sine[j], cosine[j]));
}

// The scaled Jacobian of scaled_jacobian.cpp (a tetrahedron alone): each edge's length from the
// later corner minus the earlier, as the scalar code measures it, then its corners in its order.
template <class Sqrt>
[[gnu::always_inline]] inline void scaled_jacobian(const TetBlock& x, double* quality) {
    alignas(64) double length[4][4][kTetBlock];
    for (int j = 0; j < kTetBlock; ++j) {
        const std::array<P, 4> c = corners_of(x, j);
        for (int a = 0; a < 4; ++a)
            for (int b = a + 1; b < 4; ++b) {
                const P d = c[b] - c[a];
                length[a][b][j] = dot(d, d);
            }
    }
    for (int a = 0; a < 4; ++a)
        for (int b = a + 1; b < 4; ++b) Sqrt::run(length[a][b], length[a][b]);
    for (int j = 0; j < kTetBlock; ++j) {
        const std::array<P, 4> c = corners_of(x, j);
        auto l = [&](int a, int b) { return a < b ? length[a][b][j] : length[b][a][j]; };
        double worst = INFINITY;
        for (const auto& k : kTetJacobianCorners) {
            const P e1 = c[k[1]] - c[k[0]], e2 = c[k[2]] - c[k[0]], e3 = c[k[3]] - c[k[0]];
            const double lengths = l(k[0], k[1]) * l(k[0], k[2]) * l(k[0], k[3]);
            const double corner = lengths > 0.0 ? dot(e1, cross(e2, e3)) / lengths : 0.0;
            worst = corner < worst ? corner : worst;  // std::min's choice
        }
        quality[j] = std::numbers::sqrt2 * worst;
    }
}

template <class Sqrt>
[[gnu::always_inline]] inline void values(TetValueMetric metric, const TetBlock& x, const double* reference_volume,
                                          double* quality) {
    switch (metric) {
        case TetValueMetric::inverse_condition: return inverse_condition<Sqrt>(x, quality);
        case TetValueMetric::edge_ratio: return edge_ratio<Sqrt>(x, quality);
        case TetValueMetric::scaled_volume: return scaled_volume(x, reference_volume, quality);
        case TetValueMetric::min_dihedral: return min_dihedral<Sqrt>(x, quality);
        case TetValueMetric::scaled_jacobian: return scaled_jacobian<Sqrt>(x, quality);
    }
}

void aspect_baseline(const TetBlock& x, double* quality, TetBlock* gradient) { aspect<Sqrt128>(x, quality, gradient); }
void values_baseline(TetValueMetric metric, const TetBlock& x, const double* reference_volume, double* quality) {
    values<Sqrt128>(metric, x, reference_volume, quality);
}
void hybrid_baseline(const TetBlock& x, const double* reference_volume, double alpha, double* quality,
                     TetBlock* gradient) {
    hybrid<Sqrt128>(x, reference_volume, alpha, quality, gradient);
}
void map_baseline(const CornerMap* const* maps, const CornerMap* const* roots, TetBlock& x) { map_loop(maps, roots, x); }
void unmap_baseline(const CornerMap* const* maps, const CornerMap* const* roots, TetBlock& g) { unmap_loop(maps, roots, g); }
void shape_size_baseline(const TetBlock& x, const double* reference_volume, double* quality, TetBlock* gradient) {
    mean_ratio<Sqrt128, true>(x, reference_volume, quality, gradient);
}
void mean_ratio_baseline(const TetBlock& x, double* quality, TetBlock* gradient) {
    mean_ratio<Sqrt128, false>(x, nullptr, quality, gradient);
}
void energy_baseline(const TetBlock& x, const double* reference_volume, double epsilon, double theta, double* quality,
                     TetBlock* gradient) {
    energy<Sqrt128>(x, reference_volume, epsilon, theta, quality, gradient);
}
#ifdef PALOVERDE_X86
// AVX2 without FMA (so no contraction); for AVX-512 the pragma at the top forbids it.
[[gnu::target("avx2")]] void energy_avx2(const TetBlock& x, const double* reference_volume, double epsilon,
                                         double theta, double* quality, TetBlock* gradient) {
    energy<Sqrt256>(x, reference_volume, epsilon, theta, quality, gradient);
}
[[gnu::target("avx2")]] void map_avx2(const CornerMap* const* maps, const CornerMap* const* roots, TetBlock& x) {
    map_loop<LayOut256>(maps, roots, x);
}
[[gnu::target("avx2")]] void unmap_avx2(const CornerMap* const* maps, const CornerMap* const* roots, TetBlock& g) {
    unmap_loop<LayOut256>(maps, roots, g);
}
[[gnu::target("avx2")]] void shape_size_avx2(const TetBlock& x, const double* reference_volume, double* quality,
                                             TetBlock* gradient) {
    mean_ratio<Sqrt256, true>(x, reference_volume, quality, gradient);
}
[[gnu::target("avx2")]] void mean_ratio_avx2(const TetBlock& x, double* quality, TetBlock* gradient) {
    mean_ratio<Sqrt256, false>(x, nullptr, quality, gradient);
}
[[gnu::target("avx2")]] void values_avx2(TetValueMetric metric, const TetBlock& x, const double* reference_volume,
                                         double* quality) {
    values<Sqrt256>(metric, x, reference_volume, quality);
}
[[gnu::target("avx2")]] void aspect_avx2(const TetBlock& x, double* quality, TetBlock* gradient) {
    aspect<Sqrt256>(x, quality, gradient);
}
[[gnu::target("avx2")]] void hybrid_avx2(const TetBlock& x, const double* reference_volume, double alpha,
                                         double* quality, TetBlock* gradient) {
    hybrid<Sqrt256>(x, reference_volume, alpha, quality, gradient);
}
// Full-width vectors asked for: GCC's tuning may otherwise keep AVX-512 loops at 256 bits (a
// gradient pass measured about 16 ns per tet at full width against AVX2's 19).
#define PALOVERDE_AVX512 gnu::target("avx512f,prefer-vector-width=512")
[[PALOVERDE_AVX512]] void energy_avx512(const TetBlock& x, const double* reference_volume, double epsilon,
                                         double theta, double* quality, TetBlock* gradient) {
    energy<Sqrt512>(x, reference_volume, epsilon, theta, quality, gradient);
}
[[PALOVERDE_AVX512]] void map_avx512(const CornerMap* const* maps, const CornerMap* const* roots, TetBlock& x) {
    map_loop<LayOut512>(maps, roots, x);
}
[[PALOVERDE_AVX512]] void unmap_avx512(const CornerMap* const* maps, const CornerMap* const* roots, TetBlock& g) {
    unmap_loop<LayOut512>(maps, roots, g);
}
[[PALOVERDE_AVX512]] void shape_size_avx512(const TetBlock& x, const double* reference_volume, double* quality,
                                             TetBlock* gradient) {
    mean_ratio<Sqrt512, true>(x, reference_volume, quality, gradient);
}
[[PALOVERDE_AVX512]] void mean_ratio_avx512(const TetBlock& x, double* quality, TetBlock* gradient) {
    mean_ratio<Sqrt512, false>(x, nullptr, quality, gradient);
}
[[PALOVERDE_AVX512]] void values_avx512(TetValueMetric metric, const TetBlock& x, const double* reference_volume,
                                         double* quality) {
    values<Sqrt512>(metric, x, reference_volume, quality);
}
[[PALOVERDE_AVX512]] void aspect_avx512(const TetBlock& x, double* quality, TetBlock* gradient) {
    aspect<Sqrt512>(x, quality, gradient);
}
[[PALOVERDE_AVX512]] void hybrid_avx512(const TetBlock& x, const double* reference_volume, double alpha,
                                         double* quality, TetBlock* gradient) {
    hybrid<Sqrt512>(x, reference_volume, alpha, quality, gradient);
}
#undef PALOVERDE_AVX512
#endif

// ON_PATH(kernel, args...) calls the copy of `kernel` compiled for `path`: kernel_avx512,
// kernel_avx2 or kernel_baseline (the only copy off x86).
#ifdef PALOVERDE_X86
template <class Kernel, class... Args>
void on_path(BlockPath path, Kernel* avx512, Kernel* avx2, Kernel* baseline, Args&&... args) {
    if (path == BlockPath::avx512) return avx512(std::forward<Args>(args)...);
    if (path == BlockPath::avx2) return avx2(std::forward<Args>(args)...);
    baseline(std::forward<Args>(args)...);
}
#define ON_PATH(kernel, ...) on_path(path, kernel##_avx512, kernel##_avx2, kernel##_baseline, __VA_ARGS__)
#else
#define ON_PATH(kernel, ...) kernel##_baseline(__VA_ARGS__)
#endif

}  // namespace

// Two elements at a time with 128-bit loads and a transpose where SSE2 is: about 2/3 of the
// time of copying coordinate by coordinate, which is bound by the number of loads and stores.
// (AVX2 versions of this and of the scatter measured no faster.)
void gather_tets(const VertexId* connectivity, const double* coordinates, int count, TetBlock& x) {
    int j = 0;
#ifdef PALOVERDE_X86
    for (; j + 2 <= count; j += 2)
        for (int i = 0; i < 4; ++i) {
            const double* p0 = coordinates + 3 * static_cast<std::size_t>(connectivity[4 * j + i]);
            const double* p1 = coordinates + 3 * static_cast<std::size_t>(connectivity[4 * (j + 1) + i]);
            const __m128d a = _mm_loadu_pd(p0), b = _mm_loadu_pd(p1);  // x y
            _mm_store_pd(&x.at[3 * i][j], _mm_unpacklo_pd(a, b));
            _mm_store_pd(&x.at[3 * i + 1][j], _mm_unpackhi_pd(a, b));
            _mm_store_pd(&x.at[3 * i + 2][j], _mm_loadh_pd(_mm_load_sd(p0 + 2), p1 + 2));
        }
#endif
    for (; j < count; ++j)
        for (int i = 0; i < 4; ++i) {
            const double* p = coordinates + 3 * static_cast<std::size_t>(connectivity[4 * j + i]);
            for (int d = 0; d < 3; ++d) x.at[3 * i + d][j] = p[d];
        }
    for (; j < kTetBlock; ++j)
        for (int k = 0; k < 12; ++k) x.at[k][j] = 0.0;
}

bool block_path_supported(BlockPath path) {
    switch (path) {
        case BlockPath::baseline: return true;
#ifdef PALOVERDE_X86
        case BlockPath::avx2: return __builtin_cpu_supports("avx2");
        case BlockPath::avx512: return __builtin_cpu_supports("avx512f");
#else
        default: return false;
#endif
    }
    return false;
}

BlockPath best_block_path() {
#ifdef PALOVERDE_X86
    static const BlockPath path = block_path_supported(BlockPath::avx512) ? BlockPath::avx512
                                  : block_path_supported(BlockPath::avx2)   ? BlockPath::avx2
                                                                            : BlockPath::baseline;
    return path;
#else
    return BlockPath::baseline;
#endif
}

void tet_aspect_block(BlockPath path, const TetBlock& corners, double* quality, TetBlock* gradient) {
    ON_PATH(aspect, corners, quality, gradient);
}

void tet_hybrid_block(BlockPath path, const TetBlock& corners, const double* reference_volume, double alpha,
                      double* quality, TetBlock* gradient) {
    ON_PATH(hybrid, corners, reference_volume, alpha, quality, gradient);
}

void map_tets(BlockPath path, const CornerMap* const* maps, const CornerMap* const* roots, TetBlock& x) {
    ON_PATH(map, maps, roots, x);
}

void unmap_tets(BlockPath path, const CornerMap* const* maps, const CornerMap* const* roots, TetBlock& gradient) {
    ON_PATH(unmap, maps, roots, gradient);
}

void tet_mean_ratio_block(BlockPath path, const TetBlock& corners, double* quality, TetBlock* gradient) {
    ON_PATH(mean_ratio, corners, quality, gradient);
}

void tet_shape_size_block(BlockPath path, const TetBlock& corners, const double* reference_volume, double* quality,
                          TetBlock* gradient) {
    ON_PATH(shape_size, corners, reference_volume, quality, gradient);
}

void tet_energy_block(BlockPath path, const TetBlock& corners, const double* reference_volume, double epsilon,
                      double theta, double* quality, TetBlock* gradient) {
    ON_PATH(energy, corners, reference_volume, epsilon, theta, quality, gradient);
}

void tet_values_block(BlockPath path, TetValueMetric metric, const TetBlock& corners, const double* reference_volume,
                      double* quality) {
    ON_PATH(values, metric, corners, reference_volume, quality);
}

#undef ON_PATH

}  // namespace paloverde::metrics
