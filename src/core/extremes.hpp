#pragma once
// The least and the greatest of many numbers. A single running minimum waits for each comparison
// before the next (four cycles a number); eight independent lanes compare a vector at a time, and
// the barrier asks for the extremes of its terms several times an iteration.
//
// The same numbers as std::min and std::max folded in order: a NaN is passed over (both keep the
// running value when a comparison is false). Only which of two equal zeros comes back, -0 or +0,
// may differ; the barrier adds the least to a positive gap or takes its distance to t, where the
// two agree.
#include <cstddef>
#include <limits>
#include <span>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace paloverde::detail {

struct Extremes {
    double least = std::numeric_limits<double>::infinity();
    double greatest = -std::numeric_limits<double>::infinity();

    void add(double v) {
        least = v < least ? v : least;
        greatest = greatest < v ? v : greatest;
    }
};

inline Extremes extremes(std::span<const double> values) {
    constexpr std::size_t kLanes = 8;
    const double* v = values.data();
    const std::size_t n = values.size(), whole = n - n % kLanes;
    Extremes result;
    if (whole > 0) {
        double least[kLanes], greatest[kLanes];
#if defined(__SSE2__)
        // _mm_min_pd(x, m) is x < m ? x : m, lane by lane; _mm_max_pd(x, m) is x > m ? x : m.
        constexpr double kInfinity = std::numeric_limits<double>::infinity();
        __m128d low[kLanes / 2], high[kLanes / 2];
        for (std::size_t j = 0; j < kLanes / 2; ++j) low[j] = _mm_set1_pd(kInfinity), high[j] = _mm_set1_pd(-kInfinity);
        for (std::size_t i = 0; i < whole; i += kLanes)
            for (std::size_t j = 0; j < kLanes / 2; ++j) {
                const __m128d x = _mm_loadu_pd(v + i + 2 * j);
                low[j] = _mm_min_pd(x, low[j]);
                high[j] = _mm_max_pd(x, high[j]);
            }
        for (std::size_t j = 0; j < kLanes / 2; ++j) {
            _mm_storeu_pd(least + 2 * j, low[j]);
            _mm_storeu_pd(greatest + 2 * j, high[j]);
        }
#else
        Extremes lane[kLanes];
        for (std::size_t i = 0; i < whole; i += kLanes)
            for (std::size_t j = 0; j < kLanes; ++j) lane[j].add(v[i + j]);
        for (std::size_t j = 0; j < kLanes; ++j) least[j] = lane[j].least, greatest[j] = lane[j].greatest;
#endif
        for (std::size_t j = 0; j < kLanes; ++j) {
            result.least = least[j] < result.least ? least[j] : result.least;
            result.greatest = result.greatest < greatest[j] ? greatest[j] : result.greatest;
        }
    }
    for (std::size_t i = whole; i < n; ++i) result.add(v[i]);
    return result;
}

}  // namespace paloverde::detail
