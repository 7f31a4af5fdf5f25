#pragma once
// Cube roots of a block of values, bit for bit what glibc's std::cbrt returns, in loops that
// vectorize. The block kernels need cube roots equal to the scalar kernels' (the scalar and block
// results are compared bit for bit), and the libm call per lane was a quarter of a mean-ratio pass.
// glibc computes cbrt (sysdeps/ieee754/dbl-64/s_cbrt.c) as: x = m 2^e with m in [0.5, 1); a
// degree-6 polynomial guess u of m's root; one Halley step u (u^3 + 2m) / (2u^3 + m); times 2^(r/3)
// for r = e mod 3 (C's truncated remainder); times 2^(e/3) (truncated). Every step below is that
// step in that order (no contraction into FMA: the including file turns it off), on positive
// normal numbers, whose roots are normal so that the last product is exact as ldexp's is. Any
// other lane (zero, negative, subnormal, infinite, NaN) is left to std::cbrt.
#include <cmath>
#include <cstdint>
#include <cstring>

namespace paloverde::metrics {

template <int N>
[[gnu::always_inline]] inline void cube_roots(double* values) {
    // Bits and doubles pass between arrays by memcpy: the vectorizer takes whole arrays of one
    // type where a bit_cast per lane stops it.
    alignas(64) std::uint64_t bits[N], m_bits[N], e_bits[N];
    alignas(64) double m[N], e[N], root[N];
    std::memcpy(bits, values, sizeof bits);
    std::uint64_t odd = 0;
    for (int j = 0; j < N; ++j) {
        const std::uint64_t biased = bits[j] >> 52;  // with the sign bit: positive normals are 1..2046
        odd |= static_cast<std::uint64_t>(biased - 1 >= 2046);
        // frexp: the significand with the exponent of 0.5; the exponent as 2^52 + biased.
        m_bits[j] = (bits[j] & 0x000f'ffff'ffff'ffffULL) | (1022ULL << 52);
        e_bits[j] = biased | 0x4330'0000'0000'0000ULL;
    }
    std::memcpy(m, m_bits, sizeof m);
    std::memcpy(e, e_bits, sizeof e);
    for (int j = 0; j < N; ++j) {
        const double mj = m[j];
        const double exponent = (e[j] - 0x1p52) - 1022.0;
        const double u =
            0.354895765043919860 +
            (1.50819193781584896 +
             (-2.11499494167371287 +
              (2.44693122563534430 + (-1.83469277483613086 + (0.784932344976639262 - 0.145263899385486377 * mj) * mj) * mj) *
                  mj) *
                 mj) *
                mj;
        const double t2 = u * u * u;
        // The exponent / 3 truncated, exactly (|exponent| < 1100: it never rounds across an
        // integer), and the remainder in -2..2.
        const double third = std::trunc(exponent / 3.0);
        const double r = exponent - 3.0 * third;
        double factor = 1.0;
        factor = r == 1.0 ? 1.2599210498948731648 : factor;
        factor = r == 2.0 ? 1.5874010519681994748 : factor;
        factor = r == -1.0 ? 1.0 / 1.2599210498948731648 : factor;
        factor = r == -2.0 ? 1.0 / 1.5874010519681994748 : factor;
        root[j] = u * (t2 + 2.0 * mj) / (2.0 * t2 + mj) * factor;
        // 2^third: 2^52 + (third + 1023), whose low bits are the exponent field wanted.
        e[j] = third + 1023.0 + 0x1p52;
    }
    std::memcpy(e_bits, e, sizeof e);
    for (int j = 0; j < N; ++j) e_bits[j] <<= 52;
    std::memcpy(e, e_bits, sizeof e);
    if (odd == 0) {
        for (int j = 0; j < N; ++j) values[j] = root[j] * e[j];
        return;
    }
    for (int j = 0; j < N; ++j) {
        const bool normal = (bits[j] >> 52) - 1 < 2046;
        values[j] = normal ? root[j] * e[j] : std::cbrt(values[j]);
    }
}

}  // namespace paloverde::metrics
