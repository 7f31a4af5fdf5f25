#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/blocked_sum.hpp"
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
    double local[2] = {static_cast<double>(q.size()), 0.0};  // count, sum
    for (double v : q) local[1] += v;
    const double qmin = reducer.min(local_min(q));
    reducer.sum(local);
    const double n = local[0];
    if (n == 0.0) return;
    if (mu_ <= 0.0) {
        // Start t half the spread below the worst quality, or closer where that would spread the
        // weight over more than about `initial_active_` elements (a large mesh would otherwise
        // spend its first hundreds of iterations on its average elements); take the mu for which
        // that t is optimal.
        const double mean = local[1] / n;
        double gap = 0.5 * (mean - qmin);
        if (!(gap > 0.0)) gap = 0.1 * std::max(std::abs(qmin), 1e-12);
        // sum_i gap / (q_i - qmin + gap): how many elements weigh about as much as the worst.
        auto active = [&](double d) {
            return reducer.sum(detail::blocked_sums<1>(q.size(), [&](std::size_t i, auto& acc) {
                acc[0] += d / (q[i] - qmin + d);
            })[0]);
        };
        if (active(gap) > initial_active_) {
            double lo = 0.0, hi = gap;
            for (int it = 0; it < 60; ++it) {
                const double mid = 0.5 * (lo + hi);
                (active(mid) > initial_active_ ? hi : lo) = mid;
            }
            gap = hi;
        }
        const double t0 = qmin - gap;
        const double s = reducer.sum(detail::blocked_sums<1>(q.size(), [&](std::size_t i, auto& acc) {
            acc[0] += 1.0 / (q[i] - t0);
        })[0]);
        mu_ = 1.0 / s;
        t_ = t0;
    }
    // dF/dt = 1 - mu * sum 1/(q_i - t) rises from 1 - 0 at t = -inf to -inf at t = qmin, so the
    // root is bracketed by [qmin - n mu, qmin). Newton steps, kept inside the bracket.
    double lo = qmin - n * mu_, hi = qmin;
    double t = (t_ > lo && t_ < hi) ? t_ : 0.5 * (lo + hi);
    for (int iteration = 0; iteration < 200; ++iteration) {
        const auto partial = detail::blocked_sums<2>(q.size(), [&](std::size_t i, auto& acc) {
            const double r = 1.0 / (q[i] - t);
            acc[0] += r;
            acc[1] += r * r;
        });
        double s[2] = {partial[0], partial[1]};
        reducer.sum(s);
        const double h = mu_ * s[0] - 1.0;  // = -dF/dt
        if (h > 0.0) hi = t;
        else lo = t;
        if (std::abs(h) < 1e-13 || hi - lo <= 4.0 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(t)))
            break;
        double next = t - h / (mu_ * s[1]);
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        t = next;
    }
    t_ = std::min(t, std::nextafter(qmin, -std::numeric_limits<double>::infinity()));
}

void LogBarrier::advance() { mu_ *= shrink_; }

double LogBarrier::value(std::span<const double> q, const Reducer& reducer) const {
    const double local = detail::blocked_sums<1>(q.size(), [&](std::size_t i, auto& acc) {
        acc[0] += std::log(q[i] - t_);
    })[0];
    const double sum = reducer.sum(local);
    return std::isnan(sum) ? -std::numeric_limits<double>::infinity() : t_ + mu_ * sum;
}

double LogBarrier::value_and_weights(std::span<const double> q, std::span<double> weight, const Reducer& reducer) const {
    for (std::size_t i = 0; i < q.size(); ++i) weight[i] = mu_ / (q[i] - t_);
    return value(q, reducer);
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
    double s[2] = {static_cast<double>(q.size()), detail::blocked_sums<1>(q.size(), [&](std::size_t i, auto& acc) {
                                                       acc[0] += std::pow(q[i], p_);
                                                   })[0]};
    reducer.sum(s);
    return s[0] > 0.0 ? std::pow(s[1] / s[0], 1.0 / p_) : 0.0;
}

double PMean::value_and_weights(std::span<const double> q, std::span<double> weight, const Reducer& reducer) const {
    const double mean = value(q, reducer);
    const double n = reducer.sum(static_cast<double>(q.size()));
    const double scale = std::pow(mean, 1.0 - p_) / n;
    for (std::size_t i = 0; i < q.size(); ++i) weight[i] = scale * std::pow(q[i], p_ - 1.0);
    return mean;
}

double MinQuality::value(std::span<const double> q, const Reducer& reducer) const { return reducer.min(local_min(q)); }

double MinQuality::value_and_weights(std::span<const double> q, std::span<double> weight, const Reducer& reducer) const {
    const double worst = value(q, reducer);
    for (std::size_t i = 0; i < q.size(); ++i) weight[i] = q[i] == worst ? 1.0 : 0.0;
    return worst;
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
