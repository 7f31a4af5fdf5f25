#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "core/exact_sums.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/objectives/objective_function.hpp"

namespace paloverde {

namespace {
double local_min(std::span<const double> q) {
    double m = std::numeric_limits<double>::infinity();
    for (double v : q) m = std::min(m, v);
    return m;
}
}  // namespace

LogBarrier::LogBarrier(double shrink, double initial_mu, double initial_active)
    : shrink_(shrink), initial_active_(initial_active), mu_(initial_mu) {
    if (!(initial_active >= 1.0)) throw OptionError("barrier_initial_active must be >= 1");
    if (!(shrink > 0.0 && shrink <= 1.0)) throw OptionError("barrier_shrink must lie in (0, 1]");
    if (!(initial_mu >= 0.0) || !std::isfinite(initial_mu)) throw OptionError("initial_mu must be >= 0 (0: automatic)");
}

void LogBarrier::update(std::span<const double> q, const Reducer& reducer) {
    const double qmin = reducer.min(local_min(q));
    std::array<ExactSum, 2> count_and_sum{};  // count, sum
    count_and_sum[0].add(static_cast<double>(q.size()));
    for (double v : q) count_and_sum[1].add(v);
    reducer.sum(count_and_sum);
    const double n = count_and_sum[0].value();
    if (n == 0.0) return;
    auto total = [&](auto term) {
        return reducer.total(detail::exact_sums<1>(q.size(), [&](std::size_t i, auto& acc) { acc[0].add(term(q[i])); })[0]);
    };
    if (mu_ <= 0.0) {
        // Start t half the spread below the worst quality, or closer where that would spread the
        // weight over more than about `initial_active_` elements (a large mesh would otherwise
        // spend its first hundreds of iterations on its average elements); take the mu for which
        // that t is optimal.
        const double mean = count_and_sum[1].value() / n;
        double gap = 0.5 * (mean - qmin);
        if (!(gap > 0.0)) gap = 0.1 * std::max(std::abs(qmin), 1e-12);
        // sum_i gap / (q_i - qmin + gap): how many elements weigh about as much as the worst.
        auto active = [&](double d) { return total([&](double v) { return d / (v - qmin + d); }); };
        if (active(gap) > initial_active_) {
            double lo = 0.0, hi = gap;
            for (int it = 0; it < 60; ++it) {
                const double mid = 0.5 * (lo + hi);
                (active(mid) > initial_active_ ? hi : lo) = mid;
            }
            gap = hi;
        }
        const double t0 = qmin - gap;
        mu_ = 1.0 / total([&](double v) { return 1.0 / (v - t0); });
        t_ = t0;
    }
    // dF/dt = 1 - mu * sum 1/(q_i - t) rises from 1 - 0 at t = -inf to -inf at t = qmin, so the
    // root is bracketed by [qmin - n mu, qmin). Newton steps, kept inside the bracket.
    double lo = qmin - n * mu_, hi = qmin;
    double t = (t_ > lo && t_ < hi) ? t_ : 0.5 * (lo + hi);
    for (int iteration = 0; iteration < 200; ++iteration) {
        auto s = detail::exact_sums<2>(q.size(), [&](std::size_t i, auto& acc) {
            const double r = 1.0 / (q[i] - t);
            acc[0].add(r);
            acc[1].add(r * r);
        });
        reducer.sum(s);
        const double h = mu_ * s[0].value() - 1.0;  // = -dF/dt
        if (h > 0.0) hi = t;
        else lo = t;
        if (std::abs(h) < 1e-13 || hi - lo <= 4.0 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(t)))
            break;
        double next = t - h / (mu_ * s[1].value());
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        t = next;
    }
    t_ = std::min(t, std::nextafter(qmin, -std::numeric_limits<double>::infinity()));
}

void LogBarrier::advance() { mu_ *= shrink_; }

double LogBarrier::value(std::span<const double> q, const Reducer& reducer) const {
    const double sum = reducer.total(detail::exact_sums<1>(q.size(), [&](std::size_t i, auto& acc) {
        acc[0].add(std::log(q[i] - t_));
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

void ObjectiveOptions::validate() const {
    if (!(barrier_shrink > 0.0 && barrier_shrink <= 1.0))
        throw OptionError("barrier_shrink must lie in (0, 1] (got " + std::to_string(barrier_shrink) + ")");
    if (!(initial_mu >= 0.0) || !std::isfinite(initial_mu))
        throw OptionError("initial_mu must be >= 0, 0 meaning automatic (got " + std::to_string(initial_mu) + ")");
    if (!(p != 0.0) || !std::isfinite(p)) throw OptionError("p must be a nonzero number (got " + std::to_string(p) + ")");
    if (!(barrier_initial_active >= 1.0)) throw OptionError("barrier_initial_active must be >= 1");
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
