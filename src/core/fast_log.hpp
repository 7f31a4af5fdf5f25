#pragma once
// Natural logarithms of many numbers at once, in SIMD instructions. Only additions,
// multiplications, one division and bit operations, none of them fused, so AVX2 and SSE2 give the
// same bits (and so does every process of a run); within about one unit in the last place of
// std::log. Inputs that are not positive normal numbers (zero, negatives, subnormals, infinity,
// NaN) take std::log's values.
#include <cstddef>

namespace paloverde::detail {

// out[i] = log(x[i]) for i < count; out may be x. In AVX2 instructions where the processor has
// them, else SSE2, which tests can ask for.
enum class LogSimd { best, sse2 };
void log_all(const double* x, double* out, std::size_t count, LogSimd simd = LogSimd::best);

// log_all's logarithm of one number (its scalar path).
double log_one(double x);

}  // namespace paloverde::detail
