#include "local_untangle.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

namespace paloverde::detail {

namespace {

// Solves the (d+1)x(d+1) symmetric system H z = r by Gaussian elimination with partial pivoting.
template <int N>
bool solve(std::array<std::array<double, N>, N> h, std::array<double, N> r, std::array<double, N>& z) {
    for (int c = 0; c < N; ++c) {
        int p = c;
        for (int i = c + 1; i < N; ++i)
            if (std::abs(h[i][c]) > std::abs(h[p][c])) p = i;
        if (!(std::abs(h[p][c]) > 0.0)) return false;
        std::swap(h[c], h[p]);
        std::swap(r[c], r[p]);
        for (int i = c + 1; i < N; ++i) {
            const double f = h[i][c] / h[c][c];
            for (int j = c; j < N; ++j) h[i][j] -= f * h[c][j];
            r[i] -= f * r[c];
        }
    }
    for (int c = N - 1; c >= 0; --c) {
        double s = r[c];
        for (int j = c + 1; j < N; ++j) s -= h[c][j] * z[j];
        z[c] = s / h[c][c];
    }
    return true;
}

// maximize s  subject to  c_e + a_e . y >= s  and  |y_i| <= 1, by the barrier
//   s + mu (sum_e log(c_e + a_e.y - s) + sum_i log(1 - y_i) + log(1 + y_i))
// with mu shrinking. Returns y (in units of the box) and the final s.
template <int D>
std::pair<std::array<double, D>, double> max_min_linear(const std::vector<std::array<double, D>>& a,
                                                       const std::vector<double>& c) {
    constexpr int N = D + 1;  // unknowns y and s
    std::array<double, D> y{};
    double smin = std::numeric_limits<double>::infinity();
    for (double ce : c) smin = std::min(smin, ce);
    double spread = 0.0;
    for (double ce : c) spread = std::max(spread, std::abs(ce));
    spread = std::max(spread, 1e-300);
    double s = smin - spread;  // strictly feasible start
    auto slack = [&](std::size_t e, const std::array<double, D>& yy, double ss) {
        double v = c[e] - ss;
        for (int i = 0; i < D; ++i) v += a[e][i] * yy[i];
        return v;
    };
    for (double mu = spread; mu > 1e-10 * spread; mu *= 0.2) {
        for (int newton = 0; newton < 30; ++newton) {
            std::array<std::array<double, N>, N> h{};
            std::array<double, N> g{};
            g[D] = 1.0;
            for (std::size_t e = 0; e < c.size(); ++e) {
                const double r = 1.0 / slack(e, y, s);
                std::array<double, N> row{};
                for (int i = 0; i < D; ++i) row[i] = a[e][i];
                row[D] = -1.0;
                for (int i = 0; i < N; ++i) {
                    g[i] += mu * r * row[i];
                    for (int j = 0; j < N; ++j) h[i][j] += mu * r * r * row[i] * row[j];
                }
            }
            for (int i = 0; i < D; ++i) {
                const double up = 1.0 / (1.0 - y[i]), down = 1.0 / (1.0 + y[i]);
                g[i] += mu * (down - up);
                h[i][i] += mu * (up * up + down * down);
            }
            std::array<double, N> step{};
            if (!solve<N>(h, g, step)) break;  // Newton step for maximizing: H step = gradient
            // Largest step keeping every slack and box bound positive, then backtrack on the value.
            double t = 1.0;
            auto feasible = [&](double tt) {
                std::array<double, D> yy;
                for (int i = 0; i < D; ++i) {
                    yy[i] = y[i] + tt * step[i];
                    if (!(std::abs(yy[i]) < 1.0)) return false;
                }
                for (std::size_t e = 0; e < c.size(); ++e)
                    if (!(slack(e, yy, s + tt * step[D]) > 0.0)) return false;
                return true;
            };
            while (t > 1e-12 && !feasible(t)) t *= 0.5;
            if (t <= 1e-12) break;
            double decrement = 0.0;
            for (int i = 0; i < N; ++i) decrement += g[i] * step[i];
            for (int i = 0; i < D; ++i) y[i] += t * step[i];
            s += t * step[D];
            if (decrement < 1e-14 * spread) break;
        }
    }
    return {y, s};
}

}  // namespace

VertexUntangle untangle_vertex(const SimplexMesh& mesh, std::span<double> xyz, VertexId v, const MetricScale& scale) {
    VertexUntangle result;
    const int k = mesh.corners();
    const auto elements = mesh.elements_of(v);
    if (elements.empty() || mesh.fixed()[v]) return result;
    auto volume = make_metric("scaled_volume");
    volume->set_scale(scale);
    // Each element's scaled volume and its gradient with respect to v (exact: linear in v).
    std::vector<double> c;
    std::vector<std::array<double, 3>> grad;
    double corners[12], g[12];
    double box = 0.0;  // the largest edge at v: how far v may move
    const Vec3 p = {xyz[3 * v], xyz[3 * v + 1], xyz[3 * v + 2]};
    for (ElementId e : elements) {
        const auto element = mesh.element(e);
        int slot = 0;
        for (int i = 0; i < k; ++i) {
            const VertexId w = element[i];
            if (w == v) slot = i;
            for (int d = 0; d < 3; ++d) corners[3 * i + d] = xyz[3 * static_cast<std::size_t>(w) + d];
            box = std::max(box, std::hypot(corners[3 * i] - p[0], corners[3 * i + 1] - p[1], corners[3 * i + 2] - p[2]));
        }
        c.push_back(volume->value_and_gradient(mesh.kind(), corners, g));
        grad.push_back({g[3 * slot], g[3 * slot + 1], g[3 * slot + 2]});
    }
    result.before = *std::min_element(c.begin(), c.end());
    result.after = result.before;
    if (!(box > 0.0)) return result;

    // Directions v may move in, scaled by the box: all of space, or the plane of the triangles.
    std::vector<Vec3> basis;
    if (mesh.kind() == ElementKind::Tetrahedron) {
        basis = {{box, 0, 0}, {0, box, 0}, {0, 0, box}};
    } else {
        const Vec3& n = scale.plane_normal;
        Vec3 u = std::abs(n[0]) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
        const double along = u[0] * n[0] + u[1] * n[1] + u[2] * n[2];
        for (int d = 0; d < 3; ++d) u[d] -= along * n[d];
        const double length = std::hypot(u[0], u[1], u[2]);
        for (double& x : u) x /= length;
        const Vec3 w = {n[1] * u[2] - n[2] * u[1], n[2] * u[0] - n[0] * u[2], n[0] * u[1] - n[1] * u[0]};
        basis = {{box * u[0], box * u[1], box * u[2]}, {box * w[0], box * w[1], box * w[2]}};
    }
    auto project = [&](const std::array<double, 3>& gv, const Vec3& b) { return gv[0] * b[0] + gv[1] * b[1] + gv[2] * b[2]; };
    Vec3 move{0, 0, 0};
    double best = 0.0;
    if (basis.size() == 3) {
        std::vector<std::array<double, 3>> a;
        for (const auto& gv : grad) a.push_back({project(gv, basis[0]), project(gv, basis[1]), project(gv, basis[2])});
        const auto [y, s] = max_min_linear<3>(a, c);
        best = s;
        for (int i = 0; i < 3; ++i)
            for (int d = 0; d < 3; ++d) move[d] += y[i] * basis[i][d];
    } else {
        std::vector<std::array<double, 2>> a;
        for (const auto& gv : grad) a.push_back({project(gv, basis[0]), project(gv, basis[1])});
        const auto [y, s] = max_min_linear<2>(a, c);
        best = s;
        for (int i = 0; i < 2; ++i)
            for (int d = 0; d < 3; ++d) move[d] += y[i] * basis[i][d];
    }
    // Recheck at the new position with the exact volumes; keep it only if every element is valid.
    double after = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < c.size(); ++i)
        after = std::min(after, c[i] + grad[i][0] * move[0] + grad[i][1] * move[1] + grad[i][2] * move[2]);
    if (!(best > 0.0) || !(after > 0.0) || !(after > result.before)) return result;
    for (int d = 0; d < 3; ++d) xyz[3 * static_cast<std::size_t>(v) + d] += move[d];
    result.after = after;
    result.moved = true;
    return result;
}

}  // namespace paloverde::detail
