#include "paloverde/core/exact_sum.hpp"

#include <cmath>
#include <cstring>
#include <limits>

namespace paloverde {

namespace {
constexpr std::int64_t kNaN = 1, kPlusInf = 2, kMinusInf = 4;
constexpr std::int64_t kDigitMask = 0xffffffff;
constexpr std::uint32_t kNormalizeAfter = 1u << 30;
}  // namespace

void ExactSum::add_nonzero(double x) {
    std::uint64_t bits;
    std::memcpy(&bits, &x, sizeof bits);
    const bool negative = bits >> 63;
    const int biased = static_cast<int>((bits >> 52) & 0x7ff);
    std::uint64_t mantissa = bits & ((std::uint64_t{1} << 52) - 1);
    if (biased == 0x7ff) {
        special_ |= mantissa != 0 ? kNaN : (negative ? kMinusInf : kPlusInf);
        return;
    }
    // x = mantissa * 2^(position - 1074), position in [0, 2045].
    int position = 0;
    if (biased != 0) {
        mantissa |= std::uint64_t{1} << 52;
        position = biased - 1;
    }
    const int digit = position >> 5;
    const unsigned __int128 shifted = static_cast<unsigned __int128>(mantissa) << (position & 31);
    const auto d0 = static_cast<std::int64_t>(shifted & kDigitMask);
    const auto d1 = static_cast<std::int64_t>((shifted >> 32) & kDigitMask);
    const auto d2 = static_cast<std::int64_t>(shifted >> 64);
    if (negative) {
        digits_[digit] -= d0;
        digits_[digit + 1] -= d1;
        digits_[digit + 2] -= d2;
    } else {
        digits_[digit] += d0;
        digits_[digit + 1] += d1;
        digits_[digit + 2] += d2;
    }
    if (++pending_ >= kNormalizeAfter) normalize();
}

ExactSum& ExactSum::operator+=(const ExactSum& other) {
    for (int i = 0; i < kDigits; ++i) digits_[i] += other.digits_[i];
    special_ |= other.special_;
    pending_ += other.pending_ + 1;
    if (pending_ >= kNormalizeAfter) normalize();
    return *this;
}

void ExactSum::normalize() {
    // Every digit but the last into [0, 2^32); the last keeps the sign. The representation of a
    // value is then unique, whatever the order of the terms that made it.
    for (int i = 0; i + 1 < kDigits; ++i) {
        const std::int64_t carry = digits_[i] >> 32;  // floor division by 2^32
        digits_[i] &= kDigitMask;
        digits_[i + 1] += carry;
    }
    pending_ = 0;
}

double ExactSum::value() const {
    if ((special_ & kNaN) || ((special_ & kPlusInf) && (special_ & kMinusInf)))
        return std::numeric_limits<double>::quiet_NaN();
    if (special_ & kPlusInf) return std::numeric_limits<double>::infinity();
    if (special_ & kMinusInf) return -std::numeric_limits<double>::infinity();
    ExactSum s = *this;
    s.normalize();
    double sign = 1.0;
    if (s.digits_[kDigits - 1] < 0) {
        for (auto& d : s.digits_) d = -d;
        s.normalize();
        sign = -1.0;
    }
    int top = kDigits - 1;
    while (top >= 0 && s.digits_[top] == 0) --top;
    if (top < 0) return 0.0;
    // The three leading digits carry more than 64 bits; adding them from the smallest up rounds
    // at most twice.
    double result = 0.0;
    for (int i = std::max(0, top - 2); i <= top; ++i)
        result += std::ldexp(static_cast<double>(s.digits_[i]), 32 * i - 1074);
    return sign * result;
}

}  // namespace paloverde
