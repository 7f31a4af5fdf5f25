#pragma once
// An exact sum of doubles: every term is added without rounding into a wide fixed-point
// accumulator, so the result does not depend on the order of the terms, on how they were split
// among threads or processes, or on how the partial sums were combined. This is what makes a run
// on any number of ranks give the same answer as the serial run.
#include <array>
#include <cstdint>
#include <span>

namespace paloverde {

class ExactSum {
public:
    // Digits of 32 bits, stored in 64-bit words so that about 2^31 terms can be added before the
    // carries must be propagated. Digit i weighs 2^(32 i - 1074): from the smallest subnormal up
    // to past the largest double, with room for the carries of many large terms.
    static constexpr int kDigits = 68;

    void add(double x) {
        if (x == 0.0) return;
        add_nonzero(x);
    }
    ExactSum& operator+=(const ExactSum& other);

    // The sum rounded to a double (within one unit in the last place). NaN when a term was NaN
    // or both infinities were added; +-inf when one infinity was.
    double value() const;

    // For reductions across processes: carries are propagated so that each digit fits in 32
    // bits; the digit-wise sum of up to 2^31 normalized sums is then exact.
    void normalize();
    std::span<std::int64_t> digits() { return digits_; }
    std::span<const std::int64_t> digits() const { return digits_; }
    // Bits 0/1/2: a NaN / +inf / -inf term was added (combined with bitwise or).
    std::int64_t& special() { return special_; }

private:
    void add_nonzero(double x);

    std::array<std::int64_t, kDigits> digits_{};
    std::int64_t special_ = 0;
    std::uint32_t pending_ = 0;  // terms added since the last normalize()
};

}  // namespace paloverde
