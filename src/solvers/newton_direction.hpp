#pragma once
// Truncated Newton directions for the log-barrier's shape phase (issue 16). At fixed mu, the
// barrier F(x) = max_t [t + mu sum_i log(q_i - t)] has (with t following x, by the envelope
// theorem) the Hessian -A,
//     A = -sum_i w_i Hess q_i + sum_i c_i g_i g_i^T - u u^T / C,
// with w_i = mu/(q_i - t), c_i = mu/(q_i - t)^2, g_i = grad q_i, u = sum c_i g_i, C = sum c_i.
// A product A v is a forward difference of the gradient pass along v (one quality pass for the
// weights, one gradient pass) plus t's move: the existing block kernels and lane sums, so it is
// the same bit for bit at any thread and rank count. Without the first term (Gauss-Newton) the
// worst elements' own curvature is lost, and with it the length of the steps that raise them
// (measured: docs/global_solver.md). The direction solves (A + Lambda) d = gradient by conjugate
// gradients preconditioned with the per-vertex 3x3 blocks of sum c_i g_i g_i^T, Lambda a
// Marquardt damping per vertex, and stops at non-positive curvature (A is indefinite where the
// quality is not concave).
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "paloverde/objectives/objective_function.hpp"
#include "workspace.hpp"

namespace paloverde::detail {

// z = (m + lambda I)^-1 g for the symmetric 3x3 block m = [m0 m1 m2; . m3 m4; . . m5]; zero when
// the block (with lambda) is not positive definite.
inline void solve_block(const double* m, double lambda, const double* g, double* z) {
    const double a = m[0] + lambda, b = m[1], c = m[2], d = m[3] + lambda, e = m[4], f = m[5] + lambda;
    const double A = d * f - e * e, B = c * e - b * f, C = b * e - c * d;
    const double det = a * A + b * B + c * C;
    if (!(det > 0.0)) {
        z[0] = z[1] = z[2] = 0.0;
        return;
    }
    const double D = a * f - c * c, E = b * c - a * e, F = a * d - b * b;
    z[0] = (A * g[0] + B * g[1] + C * g[2]) / det;
    z[1] = (B * g[0] + D * g[1] + E * g[2]) / det;
    z[2] = (C * g[0] + E * g[1] + F * g[2]) / det;
}

struct NewtonStep {
    double decrement = 0.0;  // gradient . direction: twice the model's gain (0 when none)
    int products = 0;        // Hessian-vector products (a quality and a gradient pass each)
    bool negative_curvature = false;
};

class NewtonDirection {
public:
    explicit NewtonDirection(Workspace& work) : work_(work) {}

    // direction ~ (A + Lambda)^-1 gradient at x (qualities q, the barrier `objective` whose
    // weights give the gradient, its curvature weights c_i and their per-vertex blocks
    // `curvature` from the gradient pass that gave `gradient`). Lambda per free owned
    // vertex: damping * its block's trace / 3 (Marquardt), plus 1e-8 of the mean trace so that
    // every block is invertible; the line search reins in vertices whose steps come out too long
    // (a Levenberg term, damping * the mean trace, damps every vertex alike, and the worst
    // element then rose more slowly). CG stops when the preconditioned
    // residual falls below `tolerance` of its start, after `max_products` products, or at
    // non-positive curvature (Steihaug). Collective; the direction is complete at owned vertices
    // (ghosts: the caller's halo update).
    NewtonStep solve(const QualityMetric& metric, const ObjectiveFunction& objective, std::span<const double> x,
                     std::span<const double> q,
                     std::span<const double> curvature_weight, std::span<const double> curvature,
                     std::span<const double> gradient, double damping, double tolerance, int max_products,
                     std::span<double> direction);

    // out = A v (no damping) at x, v complete at ghosts: what solve() multiplies by, for checks.
    void apply(const QualityMetric& metric, const ObjectiveFunction& objective, std::span<const double> x,
               std::span<const double> q, std::span<const double> curvature_weight, std::span<const double> gradient,
               std::span<const double> v, std::span<double> out);

private:
    // lambda_ zero, u_ = sum c_i g_i, buffers sized; returns C = sum c_i.
    double prepare(const QualityMetric& metric, std::span<const double> x, std::size_t elements,
                   std::span<const double> curvature_weight);
    void product(const QualityMetric& metric, const ObjectiveFunction& objective, std::span<const double> x,
                 std::span<const double> q, std::span<const double> c, double c_total, std::span<const double> gradient);
    void precondition(std::span<const double> curvature);
    // The exact sum over the elements this process counts, over all processes.
    double element_sum(std::span<const double> values);
    template <class Coordinate>
    void for_each_free(Coordinate coordinate) const {
        for_each_free_coordinate(work_, coordinate);
    }

    Workspace& work_;
    std::vector<double> lambda_, r_, z_, p_, ap_, xp_, qp_, w_, counted_, u_;
    std::optional<std::uint64_t> prepared_for_;  // the focus generation the vertex fields were set up for
};

}  // namespace paloverde::detail
