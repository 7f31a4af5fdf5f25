#include "local_untangle.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "paloverde/mesh/orientation.hpp"
#include "run_support.hpp"

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

// Unit directions a free vertex moves in: all of space, or the plane of the triangles.
std::vector<Vec3> move_basis(ElementKind kind, const MetricScale& scale) {
    if (kind == ElementKind::Tetrahedron) return {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    const Vec3& n = scale.plane_normal;
    Vec3 u = std::abs(n[0]) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
    const double along = u[0] * n[0] + u[1] * n[1] + u[2] * n[2];
    for (int d = 0; d < 3; ++d) u[d] -= along * n[d];
    const double length = std::hypot(u[0], u[1], u[2]);
    for (double& x : u) x /= length;
    const Vec3 w = {n[1] * u[2] - n[2] * u[1], n[2] * u[0] - n[0] * u[2], n[0] * u[1] - n[1] * u[0]};
    return {u, w};
}

// Unit directions a sliding vertex v moves in: an orthonormal basis of its tangent plane (2
// degrees of freedom) or its curve's direction (1), from the tangents of the axes.
std::vector<Vec3> slide_basis(const Mesh& mesh, const VertexSlide& slide, VertexId v) {
    const int dimensions = mesh.degrees_of_freedom(v);
    std::vector<Vec3> basis;
    for (int k = 0; k < dimensions; ++k) {
        Vec3 longest{0, 0, 0};
        double longest_norm = 0.0;
        for (int axis = 0; axis < 3; ++axis) {
            Vec3 e{0, 0, 0};
            e[axis] = 1.0;
            Vec3 t = slide.tangent(v, e);
            for (const Vec3& b : basis) {
                const double along = t[0] * b[0] + t[1] * b[1] + t[2] * b[2];
                for (int d = 0; d < 3; ++d) t[d] -= along * b[d];
            }
            const double norm = std::hypot(t[0], t[1], t[2]);
            if (norm > longest_norm) longest = t, longest_norm = norm;
        }
        if (!(longest_norm > 0.0)) break;
        for (double& x : longest) x /= longest_norm;
        basis.push_back(longest);
    }
    return basis;
}

// The move (and the linear program's smallest volume) in D directions of `basis`.
template <int D>
std::pair<Vec3, double> best_move(const std::vector<std::array<double, 3>>& grad, const std::vector<double>& c,
                                  const std::vector<Vec3>& basis) {
    std::vector<std::array<double, D>> a;
    for (const auto& gv : grad) {
        std::array<double, D> row{};
        for (int i = 0; i < D; ++i) row[i] = gv[0] * basis[i][0] + gv[1] * basis[i][1] + gv[2] * basis[i][2];
        a.push_back(row);
    }
    const auto [y, s] = max_min_linear<D>(a, c);
    Vec3 move{0, 0, 0};
    for (int i = 0; i < D; ++i)
        for (int d = 0; d < 3; ++d) move[d] += y[i] * basis[i][d];
    return {move, s};
}

}  // namespace

VertexUntangle untangle_vertex(const Mesh& mesh, std::span<double> xyz, VertexId v, const MetricScale& scale,
                               const VertexSlide* slide) {
    VertexUntangle result;
    const int k = mesh.corners();
    const auto elements = mesh.elements_of(v);
    if (elements.empty() || !mesh.can_move(v)) return result;
    auto volume = make_metric("scaled_volume");
    volume->set_scale(scale);
    // Each element's scaled volume and its gradient with respect to v (exact: linear in v).
    std::vector<double> c;
    std::vector<std::array<double, 3>> grad;
    double g[12];
    double box = 0.0;  // the largest edge at v: how far v may move
    const Vec3 p = {xyz[3 * v], xyz[3 * v + 1], xyz[3 * v + 2]};
    for (ElementId e : elements) {
        const auto element = mesh.element(e);
        int slot = 0;
        for (int i = 0; i < k; ++i) {
            const VertexId w = element[i];
            if (w == v) slot = i;
            const double* q = xyz.data() + 3 * static_cast<std::size_t>(w);
            box = std::max(box, std::hypot(q[0] - p[0], q[1] - p[1], q[2] - p[2]));
        }
        c.push_back(volume->element_value(mesh, xyz, e, g));
        grad.push_back({g[3 * slot], g[3 * slot + 1], g[3 * slot + 2]});
    }
    result.before = *std::min_element(c.begin(), c.end());
    result.after = result.before;
    if (!(box > 0.0)) return result;

    // Directions v may move in, scaled by the box: all of space, the plane of the triangles, or
    // a sliding vertex's tangent plane or curve.
    const bool slides = slide && mesh.slides(v);
    std::vector<Vec3> basis = slides ? slide_basis(mesh, *slide, v) : move_basis(mesh.kind(), scale);
    for (Vec3& b : basis)
        for (double& x : b) x *= box;
    auto [move, best] = basis.size() == 3   ? best_move<3>(grad, c, basis)
                        : basis.size() == 2 ? best_move<2>(grad, c, basis)
                        : basis.size() == 1 ? best_move<1>(grad, c, basis)
                                            : std::pair<Vec3, double>{Vec3{0, 0, 0}, 0.0};
    // Recheck at the new position with the exact volumes; keep it only if every element is valid.
    double after = std::numeric_limits<double>::infinity();
    double* at = &xyz[3 * static_cast<std::size_t>(v)];
    if (slides) {
        // The volumes are linear in the tangent plane, not on the surface: the projected place
        // is judged, and stays only if it passes.
        const Vec3 there = slide->project(v, {p[0] + move[0], p[1] + move[1], p[2] + move[2]});
        for (int d = 0; d < 3; ++d) at[d] = there[d];
        for (ElementId e : elements) after = std::min(after, volume->element_value(mesh, xyz, e));
        if (!(best > 0.0) || !(after > 0.0) || !(after > result.before)) {
            for (int d = 0; d < 3; ++d) at[d] = p[d];
            return result;
        }
    } else {
        for (std::size_t i = 0; i < c.size(); ++i)
            after = std::min(after, c[i] + grad[i][0] * move[0] + grad[i][1] * move[1] + grad[i][2] * move[2]);
        if (!(best > 0.0) || !(after > 0.0) || !(after > result.before)) return result;
        for (int d = 0; d < 3; ++d) at[d] += move[d];
    }
    result.after = after;
    result.moved = true;
    return result;
}

std::vector<double> local_reference_volumes(const Mesh& mesh, std::span<const double> xyz,
                                            const MetricScale& scale, const Halo& halo, ElementId count) {
    std::vector<double> volume(static_cast<std::size_t>(mesh.num_elements()));
    MetricScale unit = scale;
    unit.reference_volume = 1.0;
    unit.element_reference_volume = {};
    auto measure = make_metric("scaled_volume");
    measure->set_scale(unit);
    measure->evaluate(mesh, xyz, 0, mesh.num_elements(), volume.data());
    std::vector<double> vertex_mean(static_cast<std::size_t>(mesh.num_vertices()), 0.0);
    for (VertexId v = 0; v < mesh.num_vertices(); ++v) {
        const auto elements = mesh.elements_of(v);
        for (ElementId e : elements) vertex_mean[v] += std::abs(volume[e]);
        if (!elements.empty()) vertex_mean[v] /= static_cast<double>(elements.size());
    }
    // A ghost sees only some of its elements; its owner sees them all.
    halo.update(vertex_mean, 1);
    std::vector<double> out(static_cast<std::size_t>(count));
    for (ElementId e = 0; e < count; ++e) {
        double sum = 0.0;
        for (VertexId v : mesh.element(e)) sum += vertex_mean[v];
        const double local = sum / mesh.corners();
        // Flat neighbourhoods have no size of their own: fall back on the mesh's.
        out[e] = local > 1e-12 * scale.reference_volume ? local : scale.reference_volume;
    }
    return out;
}

double regularized_volume(double v, double epsilon) {
    const double r = std::sqrt(epsilon * epsilon + v * v);
    return v >= 0.0 ? 0.5 * (v + r) : 0.5 * epsilon * epsilon / (r - v);
}

double next_epsilon(double epsilon, double energy_start, double energy_end, double worst) {
    const double sigma = std::max(1.0 - energy_end / energy_start, 0.1);
    // chi(worst, eps') = mu solves to eps' = 2 sqrt(mu (mu - worst)).
    const double mu = (1.0 - sigma) * regularized_volume(worst, epsilon);
    return worst < mu ? 2.0 * std::sqrt(mu * (mu - worst)) : 0.1 * epsilon;
}

namespace {

// Newton steps per visit, and the forward-difference step in units of the vertex's local length.
constexpr int kNewtonSteps = 4;
constexpr double kDifference = 1e-6;

// Solves the symmetric D x D system (H + tau I) z = r by Cholesky, raising tau from 0 until H + tau I
// is positive definite: then z is a descent direction for r = -gradient.
template <int D>
std::array<double, D> shifted_solve(const std::array<std::array<double, D>, D>& h, const std::array<double, D>& r) {
    double trace = 0.0;
    for (int i = 0; i < D; ++i) trace += std::abs(h[i][i]);
    for (double tau = 0.0;; tau = tau == 0.0 ? 1e-10 * std::max(trace, 1e-300) : 10.0 * tau) {
        std::array<std::array<double, D>, D> l{};
        bool ok = true;
        for (int i = 0; i < D && ok; ++i)
            for (int j = 0; j <= i && ok; ++j) {
                double s = h[i][j] + (i == j ? tau : 0.0);
                for (int k = 0; k < j; ++k) s -= l[i][k] * l[j][k];
                if (i == j) {
                    ok = s > 0.0 && std::isfinite(s);
                    if (ok) l[i][i] = std::sqrt(s);
                } else {
                    l[i][j] = s / l[j][j];
                }
            }
        if (!ok) {
            if (!(tau < 1e300)) return {};
            continue;
        }
        std::array<double, D> z{};
        for (int i = 0; i < D; ++i) {
            double s = r[i];
            for (int k = 0; k < i; ++k) s -= l[i][k] * z[k];
            z[i] = s / l[i][i];
        }
        for (int i = D - 1; i >= 0; --i) {
            double s = z[i];
            for (int k = i + 1; k < D; ++k) s -= l[k][i] * z[k];
            z[i] = s / l[i][i];
        }
        return z;
    }
}

// One damped Newton step in the D directions of `basis` (scaled by `length`): the direction,
// from the gradient g at x and the gradients at x + h basis_i.
template <int D>
std::array<double, D> newton_direction(const std::array<double, 3>& g, const std::vector<std::array<double, 3>>& basis,
                                       double length, const std::array<std::array<double, 3>, 3>& shifted) {
    auto along = [&](const std::array<double, 3>& v, int i) {
        return length * (v[0] * basis[i][0] + v[1] * basis[i][1] + v[2] * basis[i][2]);
    };
    std::array<std::array<double, D>, D> h{};
    std::array<double, D> r{};
    for (int i = 0; i < D; ++i) {
        r[i] = -along(g, i);
        for (int j = 0; j < D; ++j) h[i][j] = (along(shifted[j], i) - along(g, i)) / kDifference;
    }
    for (int i = 0; i < D; ++i)
        for (int j = 0; j < i; ++j) h[i][j] = h[j][i] = 0.5 * (h[i][j] + h[j][i]);
    return shifted_solve<D>(h, r);
}

}  // namespace

VertexEnergy::VertexEnergy(const Mesh& mesh, std::span<const double> reference, const MetricScale& scale,
                           double epsilon, const VertexSlide* slide)
    : mesh_(mesh), reference_(reference), scale_(scale), metric_(make_untangle_energy(epsilon, kUntangleTheta)),
      slide_(slide), basis_(move_basis(mesh.kind(), scale)) {
    scale_.element_reference_volume = {};
}

double VertexEnergy::energy(std::span<const double> xyz, VertexId v, std::array<double, 3>* gradient) {
    double g[12];
    double sum = 0.0;
    if (gradient) *gradient = {0.0, 0.0, 0.0};
    MetricScale scale = scale_;
    const int k = mesh_.corners();
    for (ElementId e : mesh_.elements_of(v)) {
        const auto element = mesh_.element(e);
        int slot = 0;
        for (int i = 0; i < k; ++i)
            if (element[i] == v) slot = i;
        // Each element against its own size (the one-element calls use the metric's scale).
        scale.reference_volume = reference_[static_cast<std::size_t>(e)];
        metric_->set_scale(scale);
        // The metric is minus the energy.
        if (gradient) {
            sum -= metric_->element_value(mesh_, xyz, e, g);
            for (int d = 0; d < 3; ++d) (*gradient)[d] -= g[3 * slot + d];
        } else {
            sum -= metric_->element_value(mesh_, xyz, e);
        }
    }
    return sum;
}

int VertexEnergy::inverted(std::span<const double> xyz, VertexId v) const {
    int count = 0;
    for (ElementId e : mesh_.elements_of(v)) count += element_orientation(mesh_, xyz, e) <= 0;
    return count;
}

bool VertexEnergy::improve(std::span<double> xyz, VertexId v) {
    if (!mesh_.can_move(v) || mesh_.elements_of(v).empty()) return false;
    const double length = local_length(mesh_, xyz, v);
    if (!(length > 0.0)) return false;
    double* p = &xyz[3 * static_cast<std::size_t>(v)];
    const int allowed = inverted(xyz, v);
    const bool slides = slide_ && mesh_.slides(v);
    if (slides) slide_basis_ = slide_basis(mesh_, *slide_, v);
    const std::vector<std::array<double, 3>>& basis = slides ? slide_basis_ : basis_;
    const int dims = static_cast<int>(basis.size());
    if (dims == 0) return false;
    std::array<double, 3> g{};
    std::array<std::array<double, 3>, 3> shifted{};
    double f = energy(xyz, v, &g);
    if (!std::isfinite(f)) return false;
    bool moved = false;
    for (int step = 0; step < kNewtonSteps; ++step) {
        const std::array<double, 3> origin = {p[0], p[1], p[2]};
        for (int i = 0; i < dims; ++i) {
            for (int d = 0; d < 3; ++d) p[d] = origin[d] + kDifference * length * basis[i][d];
            energy(xyz, v, &shifted[i]);
        }
        for (int d = 0; d < 3; ++d) p[d] = origin[d];
        std::array<double, 3> y{};  // the step, in units of `length` along the basis
        if (dims == 3) {
            y = newton_direction<3>(g, basis, length, shifted);
        } else if (dims == 2) {
            const auto y2 = newton_direction<2>(g, basis, length, shifted);
            y = {y2[0], y2[1], 0.0};
        } else {
            y = {newton_direction<1>(g, basis, length, shifted)[0], 0.0, 0.0};
        }
        // A vertex never needs to travel more than a local length in one step.
        const double norm = std::sqrt(y[0] * y[0] + y[1] * y[1] + y[2] * y[2]);
        if (!(norm > 0.0) || !std::isfinite(norm)) break;
        if (norm > 1.0)
            for (double& c : y) c /= norm;
        std::array<double, 3> move{};
        for (int i = 0; i < dims; ++i)
            for (int d = 0; d < 3; ++d) move[d] += length * y[i] * basis[i][d];
        const double slope = g[0] * move[0] + g[1] * move[1] + g[2] * move[2];
        if (!(slope < 0.0)) break;
        bool accepted = false;
        double trial = f;
        for (double t = 1.0; t > 1e-9 && !accepted; t *= 0.5) {
            for (int d = 0; d < 3; ++d) p[d] = origin[d] + t * move[d];
            if (slides) {
                const Vec3 there = slide_->project(v, {p[0], p[1], p[2]});
                for (int d = 0; d < 3; ++d) p[d] = there[d];
            }
            trial = energy(xyz, v, nullptr);
            accepted = trial < f && trial <= f + 1e-4 * t * slope && inverted(xyz, v) <= allowed;
        }
        if (!accepted) {
            for (int d = 0; d < 3; ++d) p[d] = origin[d];
            break;
        }
        moved = true;
        const double gain = f - trial;
        f = energy(xyz, v, &g);
        if (gain <= 1e-10 * std::abs(f)) break;
    }
    return moved;
}

}  // namespace paloverde::detail
