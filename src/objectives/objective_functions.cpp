#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "core/exact_sums.hpp"
#include "core/extremes.hpp"
#include "core/fast_log.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/objectives/objective_function.hpp"

namespace paloverde {

namespace {
void check_state_size(std::string_view objective, std::span<const double> state, std::size_t size) {
    if (state.size() != size)
        throw Error("the " + std::string(objective) + " objective's state has " + std::to_string(size) + " numbers, got " +
                    std::to_string(state.size()));
}

double local_min(std::span<const double> q) { return detail::extremes(q).least; }
}  // namespace

LogBarrier::LogBarrier(double shrink, double initial_mu, double initial_active)
    : shrink_(shrink), initial_active_(initial_active), mu_(initial_mu) {
    if (!(initial_active == 0.0 || initial_active >= 1.0) || !std::isfinite(initial_active))
        throw OptionError("barrier_initial_active must be >= 1, or 0 for automatic");
    if (!(shrink > 0.0 && shrink <= 1.0)) throw OptionError("barrier_shrink must lie in (0, 1]");
    if (!(initial_mu >= 0.0) || !std::isfinite(initial_mu)) throw OptionError("initial_mu must be >= 0 (0: automatic)");
}

void LogBarrier::update(std::span<const double> q, const Reducer& reducer) {
    // The still elements count as terms of S below, at their bins' middles: t stays below them.
    const double qmin = worst(q, reducer);
    ExactSum count;
    count.add(static_cast<double>(q.size()));
    const double moving = reducer.total(count);
    const double n = moving + still_total_;
    if (moving == 0.0) return;  // nothing to weigh
    auto total = [&](auto term) {
        return reducer.total(detail::exact_sums<1>(q.size(), [&](std::size_t i, auto& acc) { acc[0].add(term(q[i])); })[0]);
    };
    if (mu_ <= 0.0) {
        // Start t half the spread below the worst quality, or closer where that would spread the
        // weight over more than about `active_limit` elements (a large mesh would otherwise
        // spend its first hundreds of iterations on its average elements); take the mu for which
        // that t is optimal.
        const double mean = total([](double v) { return v; }) / moving;
        // Where all elements are nearly alike the spread says nothing: start a tenth of the
        // qualities' size below (they are dimensionless, of order 1 at best). And never closer
        // than a thousandth of it: so steep a barrier lets each step raise the worst element
        // only by about the gap, and the ascent creeps.
        const double size = std::max({std::abs(qmin), std::abs(mean), 1e-9});
        const double floor = 1e-3 * size;
        double gap = 0.5 * (mean - qmin);
        if (!(gap >= 0.1 * size)) gap = 0.1 * size;
        // sum_i gap / (q_i - qmin + gap): how many elements weigh about as much as the worst.
        auto term = [&](double d, double v) { return d / (v - qmin + d); };
        // Whether that exceeds `limit`, as its exact sum says: a plain sum of the same terms (in
        // (0, 1]) settles it where it lies farther from the limit than its rounding can reach (n u
        // of it, doubled for the partial sums of threads and processes, and a few ulps for the
        // exact sum's own rounding); only a close call pays for the exact sum.
        auto more_active_than = [&](double d, double limit) {
            double plain = 0.0;
#pragma omp parallel for reduction(+ : plain) schedule(static) if (q.size() > detail::kParallelThreshold)
            for (std::size_t i = 0; i < q.size(); ++i) plain += term(d, q[i]);
            plain = reducer.total(plain);
            const double reach = 2.0 * moving * 0x1p-53 * plain + 0x1p-50 * limit;
            if (plain - limit > reach) return true;
            if (limit - plain > reach) return false;
            return total([&](double v) { return term(d, v); }) > limit;
        };
        const double active_limit = automatic_active(moving);
        if (more_active_than(gap, active_limit)) {
            // The count rises with the gap; a relative precision of 1e-3 is plenty, so bisect
            // geometrically between a negligible gap and this one.
            double lo = gap * 1e-15, hi = gap;
            while (hi > lo * (1.0 + 1e-3)) {
                const double mid = std::sqrt(lo * hi);
                (more_active_than(mid, active_limit) ? hi : lo) = mid;
            }
            gap = std::max(hi, floor);
        }
        if (first_gap_fraction_ > 0.0) gap = std::min(gap, first_gap_fraction_ * (ideal_ - qmin));
        const double t0 = qmin - gap;
        mu_ = 1.0 / total([&](double v) { return 1.0 / (v - t0); });
        t_ = t0;
    }
    // dF/dt = 0 where S = sum 1/(q_i - t) equals 1/mu. With the gap g = qmin - t, log S falls
    // with slope between -1 and 0 in log g (-1 where the worst elements dominate, near 0 where
    // the bulk does), so Newton's method on log S + log mu in log g converges in a few steps
    // where it creeps in t. The root lies in g in [mu, n mu], as 1/g <= S <= n/g.
    const double log_mu = std::log(mu_);
    double lo = log_mu, hi = std::log(n * mu_);
    // Start from the last solve's gap in units of mu, in [1, n]: it moves little from one
    // iteration to the next, where the last t (below the last worst quality, which has since
    // risen) can lie far from the root. The first solve after the automatic start begins at its t.
    double s = 0.5 * (lo + hi);
    if (gap_ratio_ > 0.0) s = std::clamp(std::log(gap_ratio_) + log_mu, lo, hi);
    else if (t_ < qmin && qmin - t_ > mu_ && qmin - t_ < n * mu_) s = std::log(qmin - t_);
    for (int iteration = 0; iteration < 100 && lo < hi; ++iteration) {
        const double gap = std::exp(s);
        // 1/gap bounds every term of S (qmin is the global minimum): the fast bounded sums do.
        auto sums = detail::bounded_block_sums<2>(
            q.size(), {1.0 / gap, 1.0 / (gap * gap)}, [&](std::size_t first, std::size_t count, const auto& terms) {
                const double* qi = q.data() + first;
                double* __restrict r = terms[0];
                double* __restrict squares = terms[1];
                for (std::size_t i = 0; i < count; ++i) {
                    r[i] = 1.0 / ((qi[i] - qmin) + gap);
                    squares[i] = r[i] * r[i];
                }
            });
        reducer.sum(sums);
        double sum = sums[0].value(), squares = sums[1].value();
        // The still elements' terms: the same bins on every process, so the same numbers.
        for (std::size_t b = 0; b < still_quality_.size(); ++b) {
            const double r = 1.0 / ((still_quality_[b] - qmin) + gap);
            sum += still_count_[b] * r;
            squares += still_count_[b] * r * r;
        }
        const double excess = std::log(sum * mu_);  // > 0: the gap is too small
        if (excess > 0.0) lo = s;
        else if (excess < 0.0) hi = s;
        else break;
        double next = s + excess * sum / (gap * squares);  // d(log S)/d(log g) = -g squares / S
        // The root can sit at a bound (one element far worse than the rest: g = mu), where
        // rounding may push Newton's step just past it.
        next = std::isfinite(next) ? std::clamp(next, lo, hi) : 0.5 * (lo + hi);
        // Quadratic convergence: a step of 1e-8 leaves an error of order 1e-16 after it.
        const bool converged = std::abs(next - s) <= 1e-8 || hi - lo <= 1e-12;
        s = next;
        if (converged) break;
    }
    const double t = qmin - std::exp(s);
    t_ = std::min(t, std::nextafter(qmin, -std::numeric_limits<double>::infinity()));
    gap_ratio_ = std::exp(s - log_mu);
}

// 0.5% of the elements, at least 10,000: a share of the mesh, so that the first t stands below
// the many elements near the worst on a mesh of any size rather than within reach of a few, and a
// floor, so that a small mesh's first barrier is not so tight that one element drives the steps
// (the measurements behind the numbers: docs/benchmarks.md).
double LogBarrier::automatic_active(double elements) const {
    return initial_active_ > 0.0 ? initial_active_ : std::max(1e4, 0.005 * elements);
}

void LogBarrier::advance() { mu_ *= shrink_; }

void ObjectiveFunction::restore_state(std::span<const double> state) { check_state_size(name(), state, 0); }

void ObjectiveFunction::hold_still(std::span<const double>, const Reducer&) {}

void LogBarrier::focus_on_band(double fraction, double ideal) {
    first_gap_fraction_ = fraction;
    ideal_ = ideal;
}

double LogBarrier::worst(std::span<const double> q, const Reducer& reducer) const {
    const double still = still_quality_.empty() ? std::numeric_limits<double>::infinity() : still_quality_.front();
    return std::min(reducer.min(local_min(q)), still);
}

void LogBarrier::keep_weighting(std::span<const double> q, const Reducer& reducer) {
    if (mu_ <= 0.0) return;
    const double qmin = worst(q, reducer);
    // A wider focus can take in an element below t: outside the focus it was no term, and a Newton
    // step lifted the focus's own elements past it. Solved for at this mu with the many more
    // terms, t would sink far below the worst and the steps would then trade the worst elements
    // for the rest; it keeps its gap below the worst instead.
    if (!(t_ < qmin)) {
        if (!(gap_ratio_ > 0.0)) return;  // no gap known yet: update() solves for t
        t_ = qmin - gap_ratio_ * mu_;
    }
    double sum = reducer.total(
        detail::exact_sums<1>(q.size(), [&](std::size_t i, auto& acc) { acc[0].add(1.0 / (q[i] - t_)); })[0]);
    for (std::size_t b = 0; b < still_quality_.size(); ++b) sum += still_count_[b] / (still_quality_[b] - t_);
    mu_ = 1.0 / sum;
    gap_ratio_ = (qmin - t_) / mu_;
}

void LogBarrier::hold_still(std::span<const double> q, const Reducer& reducer) {
    still_quality_.clear();
    still_count_.clear();
    still_total_ = 0.0;
    double low = std::numeric_limits<double>::infinity(), high = -low;
    for (double v : q)
        if (std::isfinite(v)) low = std::min(low, v), high = std::max(high, v);
    low = reducer.min(low);
    high = reducer.max(high);
    if (!(low <= high)) return;  // no still element anywhere
    constexpr int kBins = 1 << 14;
    const double width = (high - low) / kBins;
    std::vector<std::int64_t> count(width > 0.0 ? kBins : 1, 0);
    for (double v : q)
        if (std::isfinite(v)) {
            // (v - low) / width >= 0, so truncation floors it (one instruction, where floor is a call).
            const double x = width > 0.0 ? (v - low) / width : 0.0;
            ++count[x < kBins - 1.0 ? static_cast<std::size_t>(x) : kBins - 1];
        }
    reducer.sum_counts(count);
    for (std::size_t b = 0; b < count.size(); ++b)
        if (count[b] > 0) {
            still_quality_.push_back(low + (static_cast<double>(b) + 0.5) * width);
            still_count_.push_back(static_cast<double>(count[b]));
            still_total_ += static_cast<double>(count[b]);
        }
}

void LogBarrier::restore_state(std::span<const double> state) {
    check_state_size(name(), state, 3);
    mu_ = state[0];
    t_ = state[1];
    gap_ratio_ = state[2];
}

void PMean::restore_state(std::span<const double> state) {
    check_state_size(name(), state, 2);
    mean_ = state[0];
    count_ = state[1];
}

void MinQuality::restore_state(std::span<const double> state) {
    check_state_size(name(), state, 1);
    worst_ = state[0];
}

double LogBarrier::value(std::span<const double> q, const Reducer& reducer) const {
    // log(q - t) is monotone in q: the extreme qualities bound its terms.
    const detail::Extremes range = detail::extremes(q);
    const double low = reducer.min(range.least), high = reducer.max(range.greatest);
    const double bound = std::max(std::abs(std::log(low - t_)), std::abs(std::log(high - t_)));
    const double sum = reducer.total(
        detail::bounded_block_sums<1>(q.size(), {bound}, [&](std::size_t first, std::size_t count, const auto& terms) {
            for (std::size_t i = 0; i < count; ++i) terms[0][i] = q[first + i] - t_;
            detail::log_all(terms[0], terms[0], count);
        })[0]);
    return std::isnan(sum) ? -std::numeric_limits<double>::infinity() : t_ + mu_ * sum;
}

void LogBarrier::weights(std::span<const double> q, std::span<double> weight) const {
    for (std::size_t i = 0; i < q.size(); ++i) weight[i] = mu_ / (q[i] - t_);
}

void ObjectiveFunction::curvature_weights(std::span<const double>, std::span<double> curvature) const {
    std::fill(curvature.begin(), curvature.end(), 0.0);
}

void LogBarrier::curvature_weights(std::span<const double> q, std::span<double> curvature) const {
    for (std::size_t i = 0; i < q.size(); ++i) {
        const double r = 1.0 / (q[i] - t_);
        curvature[i] = mu_ * r * r;
    }
}

PMean::PMean(double p) : p_(p) {
    if (!(p != 0.0) || !std::isfinite(p)) throw OptionError("p_mean exponent p must be a nonzero number");
}

double PMean::value(std::span<const double> q, const Reducer& reducer) const {
    auto s = detail::exact_sums<2>(q.size(), [&](std::size_t i, auto& acc) { acc[1].add(std::pow(q[i], p_)); });
    s[0].add(static_cast<double>(q.size()));
    reducer.sum(s);
    const double n = s[0].value();
    return n > 0.0 ? std::pow(s[1].value() / n, 1.0 / p_) : 0.0;
}

void PMean::update(std::span<const double> q, const Reducer& reducer) {
    mean_ = value(q, reducer);
    count_ = reducer.total(static_cast<double>(q.size()));
}

void PMean::weights(std::span<const double> q, std::span<double> weight) const {
    const double scale = count_ > 0.0 ? std::pow(mean_, 1.0 - p_) / count_ : 0.0;
    for (std::size_t i = 0; i < q.size(); ++i) weight[i] = scale * std::pow(q[i], p_ - 1.0);
}

double MinQuality::value(std::span<const double> q, const Reducer& reducer) const { return reducer.min(local_min(q)); }

void MinQuality::update(std::span<const double> q, const Reducer& reducer) { worst_ = value(q, reducer); }

void MinQuality::weights(std::span<const double> q, std::span<double> weight) const {
    for (std::size_t i = 0; i < q.size(); ++i) weight[i] = q[i] == worst_ ? 1.0 : 0.0;
}

void MeanAboveFloor::set_floor(double floor, double mu) {
    if (!std::isfinite(floor)) throw OptionError("the mean_above_floor objective's floor must be a finite number");
    if (!(mu > 0.0) || !std::isfinite(mu)) throw OptionError("the mean_above_floor objective's mu must be > 0");
    floor_ = floor;
    mu_ = mu;
}

void MeanAboveFloor::restore_state(std::span<const double> state) {
    check_state_size(name(), state, 2);
    set_floor(state[0], state[1]);
}

double MeanAboveFloor::value(std::span<const double> q, const Reducer& reducer) const {
    // Both kinds of terms are monotone in q: the extreme qualities bound them.
    const detail::Extremes range = detail::extremes(q);
    const double low = reducer.min(range.least), high = reducer.max(range.greatest);
    if (!(low > floor_)) return -std::numeric_limits<double>::infinity();  // (also: no quality anywhere)
    const double log_bound = std::max(std::abs(std::log(low - floor_)), std::abs(std::log(high - floor_)));
    const double q_bound = std::max(std::abs(low), std::abs(high));
    auto sums = detail::bounded_block_sums<2>(q.size(), {q_bound, log_bound},
                                              [&](std::size_t first, std::size_t count, const auto& terms) {
                                                  for (std::size_t i = 0; i < count; ++i) {
                                                      terms[0][i] = q[first + i];
                                                      terms[1][i] = q[first + i] - floor_;
                                                  }
                                                  detail::log_all(terms[1], terms[1], count);
                                              });
    reducer.sum(sums);
    const double sum = sums[0].value() + mu_ * sums[1].value();
    return std::isnan(sum) ? -std::numeric_limits<double>::infinity() : sum;
}

void MeanAboveFloor::weights(std::span<const double> q, std::span<double> weight) const {
    for (std::size_t i = 0; i < q.size(); ++i) weight[i] = 1.0 + mu_ / (q[i] - floor_);
}

void MeanAboveFloor::curvature_weights(std::span<const double> q, std::span<double> curvature) const {
    for (std::size_t i = 0; i < q.size(); ++i) {
        const double r = 1.0 / (q[i] - floor_);
        curvature[i] = mu_ * r * r;
    }
}

void ObjectiveOptions::validate() const {
    if (!(barrier_shrink > 0.0 && barrier_shrink <= 1.0))
        throw OptionError("barrier_shrink must lie in (0, 1] (got " + std::to_string(barrier_shrink) + ")");
    if (!(initial_mu >= 0.0) || !std::isfinite(initial_mu))
        throw OptionError("initial_mu must be >= 0, 0 meaning automatic (got " + std::to_string(initial_mu) + ")");
    if (!(p != 0.0) || !std::isfinite(p)) throw OptionError("p must be a nonzero number (got " + std::to_string(p) + ")");
    if (!(barrier_initial_active == 0.0 || barrier_initial_active >= 1.0) || !std::isfinite(barrier_initial_active))
        throw OptionError("barrier_initial_active must be >= 1, or 0 for automatic (got " +
                          std::to_string(barrier_initial_active) + ")");
}

std::unique_ptr<ObjectiveFunction> make_objective(std::string_view name, const ObjectiveOptions& options) {
    options.validate();
    if (name == "log_barrier")
        return std::make_unique<LogBarrier>(options.barrier_shrink, options.initial_mu, options.barrier_initial_active);
    if (name == "p_mean") return std::make_unique<PMean>(options.p);
    if (name == "min_quality") return std::make_unique<MinQuality>();
    throw OptionError("unknown objective function '" + std::string(name) + "' (known: log_barrier, p_mean, min_quality)");
}

}  // namespace paloverde
