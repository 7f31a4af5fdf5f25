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

// ap_ = (A + Lambda) p_, p_ complete at ghosts, by a forward difference of the gradient pass
// along p_ (t held fixed: sum w_i Hess q_i - sum c_i g_i g_i^T), plus t's move, u (u.p) / C, with
// u.p = sum c_i g_i.p from the same difference of the qualities. The largest vertex move is 1e-6
// reference lengths (1e-7 and 1e-5 give the same worst quality: the difference is not sensitive
// to it), shrunk should an element leave the barrier's domain.
void NewtonDirection::product(const QualityMetric& metric, const ObjectiveFunction& objective, std::span<const double> x,
                              std::span<const double> q, std::span<const double> c, double c_total,
                              std::span<const double> gradient) {
    const auto owned = work_.owned();
    const auto free = work_.free_vertices();
    const std::size_t m = q.size();
    double largest = 0.0;
    for (const VertexId v : free)
        if (owned[v]) largest = std::max(largest, std::hypot(p_[3 * v], p_[3 * v + 1], p_[3 * v + 2]));
    largest = work_.reducer().max(largest);
    for_each_free([&](std::size_t i) { ap_[i] = 0.0; });
    if (!(largest > 0.0)) return;
    const double floor = objective.domain_floor();
    double h = 1e-6 * work_.reference_length() / largest;
    for (int attempt = 0;; ++attempt, h *= 0.01) {
        // xp_ equals x away from the free vertices (prepare).
        for_each_free([&](std::size_t i) { xp_[i] = x[i] + h * p_[i]; });
        work_.evaluate(metric, xp_, qp_);
        double outside = 0.0;
        for (std::size_t i = 0; i < m; ++i)
            if (!(qp_[i] > floor)) outside = 1.0;
        if (work_.reducer().max(outside) == 0.0) break;
        if (attempt == 3) {  // no curvature to be had along p: the caller sees p.Ap = 0
            for_each_free([&](std::size_t i) { xp_[i] = x[i]; });
            return;
        }
    }
    for (std::size_t i = 0; i < m; ++i) w_[i] = c[i] * ((qp_[i] - q[i]) / h);
    const double s = c_total > 0.0 ? element_sum(w_) / c_total : 0.0;
    objective.weights(qp_, w_);
    work_.gradient(metric, xp_, w_, ap_);
    for_each_free([&](std::size_t i) {
        ap_[i] = (gradient[i] - ap_[i]) / h - s * u_[i] + lambda_[i / 3] * p_[i];
        xp_[i] = x[i];
    });
}

void NewtonDirection::precondition(std::span<const double> curvature) {
    const auto owned = work_.owned();
    const auto free = work_.free_vertices();
#pragma omp parallel for schedule(static) if (free.size() > kParallelThreshold)
    for (std::size_t k = 0; k < free.size(); ++k) {
        const auto v = static_cast<std::size_t>(free[k]);
        if (owned[v]) solve_block(&curvature[6 * v], lambda_[v], &r_[3 * v], &z_[3 * v]);
        else z_[3 * v] = z_[3 * v + 1] = z_[3 * v + 2] = 0.0;
    }
}

double NewtonDirection::prepare(const QualityMetric& metric, std::span<const double> x, std::size_t elements,
                                std::span<const double> curvature_weight) {
    // Vertex fields are read and written at the free vertices only (a focus is a fraction of
    // the mesh); elsewhere they stay zero, and xp_ stays x. Within one focus only its free
    // vertices move, so only they are set afresh: a step then costs the focus, not the mesh.
    const std::size_t n = work_.owned().size();
    if (prepared_for_ != work_.focus_generation()) {
        for (auto* field : {&r_, &z_, &p_, &ap_, &u_}) field->assign(3 * n, 0.0);
        lambda_.assign(n, 0.0);
        xp_.assign(x.begin(), x.end());
        prepared_for_ = work_.focus_generation();
    } else {
        for_each_free([&](std::size_t i) {
            r_[i] = z_[i] = p_[i] = ap_[i] = u_[i] = 0.0;
            xp_[i] = x[i];
        });
        for (const VertexId v : work_.free_vertices()) lambda_[v] = 0.0;
    }
    qp_.resize(elements);
    w_.resize(elements);
    // u = sum c_i g_i: how t moves along a direction.
    work_.gradient(metric, x, curvature_weight, u_);
    return element_sum(curvature_weight);
}

void NewtonDirection::apply(const QualityMetric& metric, const ObjectiveFunction& objective, std::span<const double> x,
                            std::span<const double> q, std::span<const double> curvature_weight,
                            std::span<const double> gradient, std::span<const double> v, std::span<double> out) {
    const double c_total = prepare(metric, x, q.size(), curvature_weight);
    p_.assign(v.begin(), v.end());
    product(metric, objective, x, q, curvature_weight, c_total, gradient);
    std::copy(ap_.begin(), ap_.end(), out.begin());
}

NewtonStep NewtonDirection::solve(const QualityMetric& metric, const ObjectiveFunction& objective,
                                  std::span<const double> x, std::span<const double> q,
                                  std::span<const double> curvature_weight, std::span<const double> curvature,
                                  std::span<const double> gradient, double damping, double tolerance, int max_products,
                                  std::span<double> direction) {
    const auto owned = work_.owned();
    const auto free = work_.free_vertices();
    const double c_total = prepare(metric, x, q.size(), curvature_weight);
    for_each_free([&](std::size_t i) {
        r_[i] = gradient[i];
        direction[i] = 0.0;
    });
    auto trace = [&](VertexId v) { return curvature[6 * v] + curvature[6 * v + 3] + curvature[6 * v + 5]; };
    const auto [trace_sum, free_count] = free_owned_sums<2>(work_, [&](std::size_t v, auto& acc) {
        acc[0].add(trace(static_cast<VertexId>(v)));
        acc[1].add(1.0);
    });
    NewtonStep step;
    if (!(trace_sum > 0.0)) return step;
    const double mean_trace = trace_sum / free_count;
    for (const VertexId v : free)
        if (owned[v]) lambda_[v] = damping * trace(v) / 3.0 + 1e-8 * mean_trace;

    precondition(curvature);
    for_each_free([&](std::size_t i) { p_[i] = z_[i]; });
    double rz = free_owned_dot(work_, r_, z_);
    const double rz_first = rz;
    if (!(rz > 0.0)) return step;
    for (int k = 0; k < max_products; ++k) {
        work_.halo().update(p_, 3);  // the one exchange per product
        product(metric, objective, x, q, curvature_weight, c_total, gradient);
        ++step.products;
        const double pap = free_owned_dot(work_, p_, ap_);
        if (!(pap > 0.0)) {
            // Steihaug: along non-positive curvature the model has no maximum; keep what CG has,
            // or the preconditioned gradient when it has nothing yet.
            step.negative_curvature = true;
            if (k == 0)
                for (const VertexId v : free)
                    if (owned[v])
                        for (int c = 0; c < 3; ++c) direction[3 * v + c] = z_[3 * v + c];
            break;
        }
        const double alpha = rz / pap;
        for (const VertexId v : free) {
            if (!owned[v]) continue;
            for (int c = 0; c < 3; ++c) {
                direction[3 * v + c] += alpha * p_[3 * v + c];
                r_[3 * v + c] -= alpha * ap_[3 * v + c];
            }
        }
        precondition(curvature);
        const double rz_next = free_owned_dot(work_, r_, z_);
        if (!(rz_next > tolerance * tolerance * rz_first)) break;
        const double beta = rz_next / rz;
        rz = rz_next;
        for_each_free([&](std::size_t i) { p_[i] = z_[i] + beta * p_[i]; });
    }
    step.decrement = free_owned_dot(work_, gradient, direction);
    return step;
}

}  // namespace paloverde::detail
