// The logarithm as fdlibm takes it: x = 2^k m with m in [sqrt(2)/2, sqrt(2)), f = m - 1,
// s = f / (2 + f), and log(1 + f) = 2 atanh(s) = f - hf^2 + s (hf^2 + R(s^2)), R a minimax
// polynomial (its published coefficients below); k log 2 is added in two parts. Written once for
// vectors of any width; the scalar path repeats the operations one for one.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("no-trapping-math")  // lets the selects below vectorize; no one reads FP flags
#endif

#include "core/fast_log.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>

#if defined(__x86_64__)
#define PALOVERDE_X86 1
#endif

namespace paloverde::detail {
namespace {

constexpr double kLn2High = 6.93147180369123816490e-01;  // log 2 to 32 bits: k times it is exact
constexpr double kLn2Low = 1.90821492927058770002e-10;   // the rest of log 2
constexpr double kSqrt2 = 1.41421356237309514547;
constexpr double kLg1 = 6.666666666666735130e-01, kLg2 = 3.999999999940941908e-01,
                 kLg3 = 2.857142874366239149e-01, kLg4 = 2.222219843214978396e-01,
                 kLg5 = 1.818357216161805012e-01, kLg6 = 1.531383769920937332e-01,
                 kLg7 = 1.479819860511658591e-01;
constexpr std::int64_t kSmallestNormal = 0x0010000000000000;  // as bits
constexpr std::int64_t kInfinity = 0x7ff0000000000000;
constexpr std::int64_t kMantissa = 0x000fffffffffffff;
constexpr std::int64_t kOne = 0x3ff0000000000000;
// 1.5 * 2^52: adding an integer of magnitude below 2^51 to its bits adds it to its value.
constexpr std::int64_t kMagic = 0x4338000000000000;

// log(1 + f) + k log 2 from m = 1 + f and k (as a double). (By reference: a vector by value
// would pass differently with AVX than without.)
template <class V>
[[gnu::always_inline]] inline void combine(const V& m, const V& k, V& out) {
    const V f = m - 1.0;
    const V s = f / (2.0 + f);
    const V z = s * s, w = z * z;
    const V t1 = w * (kLg2 + w * (kLg4 + w * kLg6));
    const V t2 = z * (kLg1 + w * (kLg3 + w * (kLg5 + w * kLg7)));
    const V r = t2 + t1;
    const V hfsq = 0.5 * f * f;
    out = k * kLn2High - ((hfsq - (s * (hfsq + r) + k * kLn2Low)) - f);
}

template <int Width>
struct Vectors {
    typedef double V __attribute__((vector_size(8 * Width)));
    typedef long long I __attribute__((vector_size(8 * Width)));
    typedef unsigned long long U __attribute__((vector_size(8 * Width)));
};

// Logs of count values (a multiple of Width); lanes that are not positive normal numbers come
// out as garbage and are redone by the caller. Returns whether any lane was such.
template <int Width>
[[gnu::always_inline]] inline bool simd_logs(const double* x, double* out, std::size_t count) {
    using V = typename Vectors<Width>::V;
    using I = typename Vectors<Width>::I;
    using U = typename Vectors<Width>::U;
    I special = I{};
    for (std::size_t i = 0; i < count; i += Width) {
        V v;
        std::memcpy(&v, x + i, sizeof v);
        const I bits = (I)v;
        special |= (bits < kSmallestNormal) | (bits >= kInfinity);  // negatives are < as integers
        I exponent = (I)((U)bits >> 52) - 1023;  // logical shift (AVX2 has no arithmetic one); the sign is 0
        V m = (V)((bits & kMantissa) | kOne);  // in [1, 2)
        const I high = m > kSqrt2;             // all ones where m is halved
        m = (V)(((I)(m * 0.5) & high) | ((I)m & ~high));
        exponent -= high;                      // -1 where halved: one more
        const V k = (V)(exponent + kMagic) - 0x1.8p52;
        V y;
        combine(m, k, y);
        std::memcpy(out + i, &y, sizeof y);
    }
    for (int j = 0; j < Width; ++j)
        if (special[j] != 0) return true;
    return false;
}

template <int Width>
[[gnu::always_inline]] inline void logs(const double* x, double* out, std::size_t count) {
    const std::size_t whole = count - count % Width;
    // The special inputs' lanes are redone from the input, which out may overwrite: a copy of it.
    std::size_t done = 0;
    while (done < whole) {
        const std::size_t chunk = std::min<std::size_t>(whole - done, 64 * Width);
        double saved[64 * Width];
        std::memcpy(saved, x + done, chunk * sizeof(double));
        if (simd_logs<Width>(saved, out + done, chunk))
            for (std::size_t i = 0; i < chunk; ++i) {
                const auto bits = std::bit_cast<std::int64_t>(saved[i]);
                if (bits < kSmallestNormal || bits >= kInfinity) out[done + i] = std::log(saved[i]);
            }
        done += chunk;
    }
    for (std::size_t i = whole; i < count; ++i) out[i] = log_one(x[i]);
}

#ifdef PALOVERDE_X86
void logs_sse2(const double* x, double* out, std::size_t count) { logs<2>(x, out, count); }
[[gnu::target("avx2")]] void logs_avx2(const double* x, double* out, std::size_t count) { logs<4>(x, out, count); }
#endif

}  // namespace

double log_one(double x) {
    const auto bits = std::bit_cast<std::int64_t>(x);
    if (bits < kSmallestNormal || bits >= kInfinity) return std::log(x);
    std::int64_t exponent = (bits >> 52) - 1023;
    double m = std::bit_cast<double>((bits & kMantissa) | kOne);
    if (m > kSqrt2) {
        m = m * 0.5;
        exponent += 1;
    }
    const double k = std::bit_cast<double>(exponent + kMagic) - 0x1.8p52;
    double y;
    combine(m, k, y);
    return y;
}

void log_all(const double* x, double* out, std::size_t count, LogSimd simd) {
#ifdef PALOVERDE_X86
    static const bool avx2 = __builtin_cpu_supports("avx2");
    avx2 && simd == LogSimd::best ? logs_avx2(x, out, count) : logs_sse2(x, out, count);
#else
    (void)simd;
    for (std::size_t i = 0; i < count; ++i) out[i] = log_one(x[i]);
#endif
}

}  // namespace paloverde::detail
