#include "newton_direction.hpp"

#include <algorithm>
#include <cmath>

#include "core/blocked_sum.hpp"
#include "core/exact_sums.hpp"

namespace paloverde::detail {

double NewtonDirection::element_sum(std::span<const double> values) {
    const auto counted = work_.counted(values, counted_);
    double largest = 0.0;
    for (double v : counted) largest = std::max(largest, std::abs(v));
    largest = work_.reducer().max(largest);
    auto sums = bounded_sums<1>(counted.size(), {largest}, [&](std::size_t i, auto& acc) { acc[0].add(counted[i]); });
    work_.reducer().sum(sums);
    return sums[0].value();
}

// ap_ = (A + Lambda) p_, p_ complete at ghosts. g_i.p by a forward difference of the qualities,
// the largest vertex move 1e-7 reference lengths: far below any element's size on the meshes we
// have, and far above the coordinates' rounding.
void NewtonDirection::product(const QualityMetric& metric, std::span<const double> x, std::span<const double> q,
                              std::span<const double> c, double c_total) {
    const auto owned = work_.owned();
    const std::size_t n = owned.size();
    double largest = 0.0;
    for (std::size_t v = 0; v < n; ++v)
        if (owned[v]) largest = std::max(largest, std::hypot(p_[3 * v], p_[3 * v + 1], p_[3 * v + 2]));
    largest = work_.reducer().max(largest);
    std::fill(ap_.begin(), ap_.end(), 0.0);
    if (!(largest > 0.0)) return;
    const double h = 1e-7 * work_.reference_length() / largest;
#pragma omp parallel for schedule(static) if (n > kParallelThreshold)
    for (std::size_t i = 0; i < 3 * n; ++i) xp_[i] = x[i] + h * p_[i];
    work_.evaluate(metric, xp_, qp_);
    const std::size_t m = q.size();
    for (std::size_t i = 0; i < m; ++i) w_[i] = c[i] * ((qp_[i] - q[i]) / h);
    // s = u.p / C, u = sum c_i g_i: t's move along p. Weights c_i (g_i.p - s) give A p.
    const double s = c_total > 0.0 ? element_sum(w_) / c_total : 0.0;
    for (std::size_t i = 0; i < m; ++i) w_[i] = c[i] * ((qp_[i] - q[i]) / h - s);
    work_.gradient(metric, x, w_, ap_);
    for (std::size_t v = 0; v < n; ++v)
        for (int k = 0; k < 3; ++k) ap_[3 * v + k] += lambda_[v] * p_[3 * v + k];
}

void NewtonDirection::precondition(std::span<const double> curvature) {
    const auto owned = work_.owned();
    const auto fixed = work_.fixed();
#pragma omp parallel for schedule(static) if (owned.size() > kParallelThreshold)
    for (std::size_t v = 0; v < owned.size(); ++v) {
        if (owned[v] && !fixed[v]) solve_block(&curvature[6 * v], lambda_[v], &r_[3 * v], &z_[3 * v]);
        else z_[3 * v] = z_[3 * v + 1] = z_[3 * v + 2] = 0.0;
    }
}

NewtonStep NewtonDirection::solve(const QualityMetric& metric, std::span<const double> x, std::span<const double> q,
                                  std::span<const double> curvature_weight, std::span<const double> curvature,
                                  std::span<const double> gradient, double damping, double tolerance, int max_products,
                                  std::span<double> direction) {
    const auto owned = work_.owned();
    const auto fixed = work_.fixed();
    const std::size_t n = owned.size();
    lambda_.assign(n, 0.0);
    r_.assign(gradient.begin(), gradient.end());
    z_.assign(3 * n, 0.0);
    p_.assign(3 * n, 0.0);
    ap_.assign(3 * n, 0.0);
    xp_.resize(3 * n);
    qp_.resize(q.size());
    w_.resize(q.size());
    std::fill(direction.begin(), direction.end(), 0.0);

    const auto [trace_sum, free_count] = owned_sums<2>(work_, [&](std::size_t v, auto& acc) {
        if (fixed[v]) return;
        acc[0].add(curvature[6 * v] + curvature[6 * v + 3] + curvature[6 * v + 5]);
        acc[1].add(1.0);
    });
    NewtonStep step;
    if (!(trace_sum > 0.0)) return step;
    const double mean_trace = trace_sum / free_count;
    for (std::size_t v = 0; v < n; ++v)
        if (owned[v] && !fixed[v])
            lambda_[v] = damping * (curvature[6 * v] + curvature[6 * v + 3] + curvature[6 * v + 5]) / 3.0 + 1e-8 * mean_trace;
    const double c_total = element_sum(curvature_weight);

    precondition(curvature);
    p_ = z_;
    double rz = owned_dot(work_, r_, z_);
    const double rz_first = rz;
    if (!(rz > 0.0)) return step;
    for (int k = 0; k < max_products; ++k) {
        work_.halo().update(p_, 3);  // the one exchange per product
        product(metric, x, q, curvature_weight, c_total);
        ++step.products;
        const double pap = owned_dot(work_, p_, ap_);
        if (!(pap > 0.0)) {
            // Steihaug: along non-positive curvature the model has no maximum; keep what CG has,
            // or the preconditioned gradient when it has nothing yet.
            step.negative_curvature = true;
            if (k == 0)
                for (std::size_t v = 0; v < n; ++v)
                    if (owned[v])
                        for (int c = 0; c < 3; ++c) direction[3 * v + c] = z_[3 * v + c];
            break;
        }
        const double alpha = rz / pap;
        for (std::size_t v = 0; v < n; ++v) {
            if (!owned[v]) continue;
            for (int c = 0; c < 3; ++c) {
                direction[3 * v + c] += alpha * p_[3 * v + c];
                r_[3 * v + c] -= alpha * ap_[3 * v + c];
            }
        }
        precondition(curvature);
        const double rz_next = owned_dot(work_, r_, z_);
        if (!(rz_next > tolerance * tolerance * rz_first)) break;
        const double beta = rz_next / rz;
        rz = rz_next;
        for (std::size_t i = 0; i < 3 * n; ++i) p_[i] = z_[i] + beta * p_[i];
    }
    step.decrement = owned_dot(work_, gradient, direction);
    return step;
}

}  // namespace paloverde::detail
