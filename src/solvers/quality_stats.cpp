#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include "core/blocked_sum.hpp"
#include "core/exact_sums.hpp"
#include "core/extremes.hpp"
#include "global_phase.hpp"

namespace paloverde::detail {

Frozen frozen_stats(const Reducer& reducer, std::span<const double> counted) {
    constexpr double kOut = std::numeric_limits<double>::infinity();
    Frozen f;
    std::int64_t count = 0, bad = 0;  // counted as integers, then summed exactly like the qualities
    double largest = 0.0;
    for (double q : counted) {
        if (q == kOut) continue;
        f.worst = std::min(f.worst, q);
        largest = std::max(largest, std::abs(q));
        ++count;
        bad += q <= 0.0;
    }
    largest = reducer.max(largest);
    // The qualities' sum as quality_stats takes it (only the mean reports it).
    std::array<ExactSum, 3> sums{bounded_block_sums<1>(
        counted.size(), {largest}, [&](std::size_t first, std::size_t length, const auto& terms) {
            for (std::size_t i = 0; i < length; ++i) {
                const double q = counted[first + i];
                terms[0][i] = q != kOut ? q : 0.0;  // a zero term adds nothing
            }
        })[0]};
    sums[1].add(static_cast<double>(count));
    sums[2].add(static_cast<double>(bad));
    reducer.sum(sums);
    f.worst = reducer.min(f.worst);
    f.sum = sums[0].value();
    f.count = sums[1].value();
    f.bad = static_cast<long>(sums[2].value());
    return f;
}

Stats quality_stats(const Workspace& work, std::span<const double> all, std::vector<double>& buffer,
                    const Frozen& frozen) {
    const Reducer& reducer = work.reducer();
    const auto q = work.counted(all, buffer);
    const Extremes range = extremes(q);  // NaN passed over
    Stats s{range.least, 0.0, 0, 0};
    double largest = range.least <= range.greatest ? std::max(std::abs(range.least), std::abs(range.greatest)) : 0.0;
    for (double v : q) {
        s.nan += std::isnan(v);
        s.bad += v <= 0.0;
    }
    largest = reducer.max(largest);
    // The qualities' sum, then the two counts: one reduction for all three.
    std::array<ExactSum, 3> sums{
        bounded_block_sums<1>(q.size(), {largest}, [&](std::size_t first, std::size_t count, const auto& terms) {
            for (std::size_t i = 0; i < count; ++i) terms[0][i] = std::isnan(q[first + i]) ? 0.0 : q[first + i];
        })[0]};
    sums[1].add(static_cast<double>(s.bad));
    sums[2].add(static_cast<double>(s.nan));
    reducer.sum(sums);
    s.worst = std::min(reducer.min(s.worst), frozen.worst);
    s.bad = static_cast<long>(sums[1].value()) + frozen.bad;
    s.nan = static_cast<long>(sums[2].value());
    sums[0].add(frozen.sum);
    s.mean = sums[0].value() / std::max(1.0, work.global_movable() + frozen.count);
    return s;
}

double worst_counted(const Workspace& work, std::span<const double> all, std::vector<double>& buffer) {
    return work.reducer().min(extremes(work.counted(all, buffer)).least);
}

}  // namespace paloverde::detail
