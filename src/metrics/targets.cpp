#include "paloverde/metrics/targets.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <vector>

#include "core/exact_sums.hpp"
#include "geometry.hpp"
#include "mesh/small_matrix.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/mesh/boundary_surface.hpp"
#include "paloverde/mesh/cell_types.hpp"

namespace paloverde {

namespace {

using Matrix = CornerMap;  // m[row][column]; the upper-left d x d block is used

constexpr std::array<std::string_view, 4> kFactorNames = {"size", "orientation", "aspect", "skew"};

TargetSource& factor_of(TargetOptions& o, std::size_t i) {
    TargetSource* factors[] = {&o.size, &o.orientation, &o.aspect, &o.skew};
    return *factors[i];
}
TargetSource factor_of(const TargetOptions& o, std::size_t i) {
    const TargetSource factors[] = {o.size, o.orientation, o.aspect, o.skew};
    return factors[i];
}

Matrix product(const Matrix& a, const Matrix& b, int d) {
    Matrix out{};
    for (int i = 0; i < d; ++i)
        for (int j = 0; j < d; ++j)
            for (int k = 0; k < d; ++k) out[i][j] += a[i][k] * b[k][j];
    return out;
}

using detail::determinant;
using detail::inverse;

Matrix transpose(const Matrix& m, int d) {
    Matrix out{};
    for (int i = 0; i < d; ++i)
        for (int j = 0; j < d; ++j) out[i][j] = m[j][i];
    return out;
}

// The rotation (or reflection) U of the polar decomposition x = U P, P symmetric positive
// definite: the orthogonal matrix nearest x, by Newton's iteration U <- (g U + U^-T / g) / 2 with
// Higham's scaling g, which converges in a few steps even for a thin boundary layer's corner.
Matrix polar_rotation(const Matrix& x, int d) {
    Matrix u = x;
    for (int step = 0; step < 60; ++step) {
        const Matrix inverse_transpose = transpose(inverse(u, d), d);
        double norm = 0.0, inverse_norm = 0.0;
        for (int i = 0; i < d; ++i)
            for (int j = 0; j < d; ++j) norm += u[i][j] * u[i][j], inverse_norm += inverse_transpose[i][j] * inverse_transpose[i][j];
        const double g = std::sqrt(std::sqrt(inverse_norm / norm));
        double change = 0.0;
        for (int i = 0; i < d; ++i)
            for (int j = 0; j < d; ++j) {
                const double next = 0.5 * (g * u[i][j] + inverse_transpose[i][j] / g);
                change = std::max(change, std::abs(next - u[i][j]));
                u[i][j] = next;
            }
        if (change <= 1e-15) break;
    }
    return u;
}

// f applied to the symmetric d x d matrix s: V diag(f(eigenvalues)) V^T, the eigenvectors by
// cyclic Jacobi rotations (exact to rounding for d <= 3 in a few sweeps).
template <class F>
Matrix symmetric_function(Matrix s, int d, F f) {
    Matrix vectors{};
    for (int i = 0; i < d; ++i) vectors[i][i] = 1.0;
    for (int sweep = 0; sweep < 50; ++sweep) {
        double off = 0.0, scale = 0.0;
        for (int i = 0; i < d; ++i)
            for (int j = 0; j < d; ++j) (i == j ? scale : off) += s[i][j] * s[i][j];
        if (off <= 1e-30 * scale) break;
        for (int p = 0; p < d; ++p)
            for (int q = p + 1; q < d; ++q) {
                if (s[p][q] == 0.0) continue;
                const double theta = (s[q][q] - s[p][p]) / (2.0 * s[p][q]);
                const double t = (theta >= 0.0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1.0));
                const double c = 1.0 / std::sqrt(t * t + 1.0), sn = t * c;
                for (int k = 0; k < d; ++k) {  // s <- J^T s J, columns then rows
                    const double kp = s[k][p], kq = s[k][q];
                    s[k][p] = c * kp - sn * kq, s[k][q] = sn * kp + c * kq;
                }
                for (int k = 0; k < d; ++k) {
                    const double pk = s[p][k], qk = s[q][k];
                    s[p][k] = c * pk - sn * qk, s[q][k] = sn * pk + c * qk;
                }
                for (int k = 0; k < d; ++k) {
                    const double kp = vectors[k][p], kq = vectors[k][q];
                    vectors[k][p] = c * kp - sn * kq, vectors[k][q] = sn * kp + c * kq;
                }
            }
    }
    Matrix out{};
    for (int k = 0; k < d; ++k) {
        const double value = f(s[k][k]);
        for (int i = 0; i < d; ++i)
            for (int j = 0; j < d; ++j) out[i][j] += vectors[i][k] * value * vectors[j][k];
    }
    return out;
}

// m scaled to determinant 1.
Matrix at_unit_determinant(Matrix m, int d) {
    const double unit = std::pow(determinant(m, d), 1.0 / d);
    for (int i = 0; i < d; ++i)
        for (int j = 0; j < d; ++j) m[i][j] /= unit;
    return m;
}

// A corner's factors W = lambda V Q D (targets.hpp).
struct Factors {
    double lambda = 1.0;
    Matrix frame{};  // the corner's edge matrix itself
    Matrix v{}, q{}, d{};
    bool valid = false;     // not degenerate: every factor is usable
    bool positive = false;  // positively oriented: V is a rotation
};

// Factors of the d x d matrix x by Gram-Schmidt QR (with one reorthogonalization: thin boundary
// layer corners would lose their small edge's direction to rounding otherwise).
Factors factor(const Matrix& x, int d) {
    Factors f;
    f.frame = x;
    Matrix r{};
    std::array<std::array<double, 3>, 3> q{};  // q[j]: column j of V
    double largest = 0.0;
    for (int j = 0; j < d; ++j) {
        std::array<double, 3> u{};
        for (int i = 0; i < d; ++i) u[i] = x[i][j];
        for (int pass = 0; pass < 2; ++pass)
            for (int k = 0; k < j; ++k) {
                double c = 0.0;
                for (int i = 0; i < d; ++i) c += q[k][i] * u[i];
                r[k][j] += c;
                for (int i = 0; i < d; ++i) u[i] -= c * q[k][i];
            }
        double length = 0.0;
        for (int i = 0; i < d; ++i) length += u[i] * u[i];
        length = std::sqrt(length);
        r[j][j] = length;
        largest = std::max(largest, length);
        if (length > 0.0)
            for (int i = 0; i < d; ++i) q[j][i] = u[i] / length;
    }
    double smallest = INFINITY;
    for (int j = 0; j < d; ++j) smallest = std::min(smallest, r[j][j]);
    f.valid = std::isfinite(largest) && smallest > 1e-10 * largest;
    if (!f.valid) return f;
    for (int i = 0; i < d; ++i)
        for (int j = 0; j < d; ++j) f.v[i][j] = q[j][i];
    f.positive = determinant(x, d) > 0.0;
    const double det_r = determinant(r, d);
    f.lambda = std::pow(det_r, 1.0 / d);
    double lengths[3], product_of_lengths = 1.0;
    for (int j = 0; j < d; ++j) {
        double sum = 0.0;
        for (int i = 0; i <= j; ++i) sum += r[i][j] * r[i][j];
        lengths[j] = std::sqrt(sum);
        product_of_lengths *= lengths[j];
    }
    const double mean_length = std::pow(product_of_lengths, 1.0 / d);
    const double skew_scale = std::pow(det_r / product_of_lengths, 1.0 / d);  // det of the unit-column R
    for (int j = 0; j < d; ++j) {
        f.d[j][j] = lengths[j] / mean_length;
        for (int i = 0; i <= j; ++i) f.q[i][j] = r[i][j] / lengths[j] / skew_scale;
    }
    return f;
}

// How a corner is turned within a metric whose root is `root` (any positive multiple of M^1/2),
// from the ideal corner `ideal`: the polar rotation of root A ideal^-1; none for an inverted or
// degenerate corner.
Matrix turn_in_metric(const Matrix& root, const Factors& corner, const Matrix& ideal, int d) {
    Matrix turn{};
    for (int i = 0; i < d; ++i) turn[i][i] = 1.0;
    if (corner.valid && corner.positive)
        turn = polar_rotation(product(root, product(corner.frame, inverse(ideal, d), d), d), d);
    return turn;
}

// Element e's corner edges at xyz, as the columns of a d x d matrix: in 3D as they are, in 2D in
// the plane's basis (a, b).
Matrix edge_matrix(const Mesh& mesh, std::span<const double> xyz, ElementId e, const metrics::P& a,
                   const metrics::P& b) {
    const auto corners = mesh.element(e);
    const metrics::P origin = metrics::load(xyz.data(), corners[0]);
    Matrix m{};
    const int d = mesh.corners() - 1;
    for (int j = 0; j < d; ++j) {
        const metrics::P edge = metrics::load(xyz.data(), corners[j + 1]) - origin;
        if (d == 3) {
            m[0][j] = edge.x, m[1][j] = edge.y, m[2][j] = edge.z;
        } else {
            m[0][j] = metrics::dot(edge, a), m[1][j] = metrics::dot(edge, b);
        }
    }
    return m;
}

// A surface element's metric root: the map of space that takes its input plane's basis (a, b) to
// the x and y axes through the plane's metric root n (2 x 2: the identity for an element rated in
// no metric), and its normal a x b to the z axis. Carried by it, the element lies in the xy plane
// in the frame its target was taken in, and the metrics rate it about the z axis (scale_of in
// metrics.cpp): its input corners against its own target are exactly the target.
CornerMap surface_root(const Matrix& n, const metrics::P& a, const metrics::P& b) {
    const metrics::P normal = metrics::cross(a, b);
    const double basis[3][3] = {{a.x, a.y, a.z}, {b.x, b.y, b.z}, {normal.x, normal.y, normal.z}};
    CornerMap out{};
    for (int c = 0; c < 3; ++c) {
        for (int r = 0; r < 2; ++r) out[r][c] = n[r][0] * basis[0][c] + n[r][1] * basis[1][c];
        out[2][c] = basis[2][c];
    }
    return out;
}

// A symmetric 3 x 3 matrix seen in the plane of basis (a, b) (u^T M w for u, w of the basis), and
// a symmetric 2 x 2 matrix m in that basis as one of space (B m B^T, B = [a b]).
Matrix in_plane(const Matrix& full, const metrics::P& a, const metrics::P& b) {
    const double u[2][3] = {{a.x, a.y, a.z}, {b.x, b.y, b.z}};
    Matrix out{};
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j) {
            double sum = 0.0;
            for (int p = 0; p < 3; ++p)
                for (int q = 0; q < 3; ++q) sum += u[i][p] * full[p][q] * u[j][q];
            out[i][j] = sum;
        }
    return out;
}
Matrix in_space(const Matrix& m, const metrics::P& a, const metrics::P& b) {
    const double u[2][3] = {{a.x, a.y, a.z}, {b.x, b.y, b.z}};
    Matrix out{};
    for (int p = 0; p < 3; ++p)
        for (int q = 0; q < 3; ++q)
            for (int i = 0; i < 2; ++i)
                for (int j = 0; j < 2; ++j) out[p][q] += u[i][p] * m[i][j] * u[j][q];
    return out;
}

// The regular simplex's corner (unit edges) and, for element e, the ideal element's corner, both
// in the ideal element's coordinates: the cell's corner map M = W^-1 W_regular gives W.
Matrix regular_frame(int d) {
    const auto x = ideal_cell(d == 3 ? CellType::Tetrahedron : CellType::Triangle);
    Matrix w{};
    for (int j = 0; j < d; ++j)
        for (int i = 0; i < d; ++i) w[i][j] = x[j + 1][i] - x[0][i];
    return w;
}
Matrix ideal_frame(const Mesh& mesh, ElementId e, const Matrix& regular, int d) {
    const auto maps = mesh.corner_maps();
    if (maps.empty() || maps[e] == 0) return regular;
    return product(regular, inverse(corner_map(maps[e]), d), d);
}

// Simplices take their aspect from their neighbourhood's metric (targets.hpp).
bool is_simplex(const Mesh& mesh, ElementId e) {
    const CellType type = mesh.cell_type(mesh.cell_of(e));
    return type == CellType::Tetrahedron || type == CellType::Triangle;
}

// Element e's metric at xyz: the symmetric M = (S S^T)^-1 in which the element is the regular
// simplex (S = A W_regular^-1 carries the regular simplex onto it), scaled to determinant 1 so that
// it holds the stretch and not the size. False for a degenerate element.
bool element_metric(const Mesh& mesh, std::span<const double> xyz, ElementId e, const metrics::P& a, const metrics::P& b,
                    const Matrix& regular_inverse, Matrix& out) {
    const int d = mesh.corners() - 1;
    const Matrix edges = edge_matrix(mesh, xyz, e, a, b);
    if (!factor(edges, d).valid) return false;
    const Matrix s = product(edges, regular_inverse, d);
    out = at_unit_determinant(inverse(product(s, transpose(s, d), d), d), d);
    for (int i = 0; i < d; ++i)
        for (int j = 0; j < d; ++j)
            if (!std::isfinite(out[i][j])) return false;
    return true;
}

constexpr int kMetricIndex[Mesh::kMetricValues][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {1, 2}, {0, 2}};  // Mesh's order

}  // namespace

void check_reference(const Mesh& mesh, const Mesh& reference) {
    if (reference.kind() != mesh.kind() || reference.num_vertices() != mesh.num_vertices() ||
        reference.num_cells() != mesh.num_cells() || reference.num_elements() != mesh.num_elements())
        throw MeshError("the reference mesh has " + std::to_string(reference.num_vertices()) + " vertices and " +
                        std::to_string(reference.num_cells()) + " elements, the mesh " +
                        std::to_string(mesh.num_vertices()) + " and " + std::to_string(mesh.num_cells()) +
                        ": a reference must have the mesh's connectivity");
    for (ElementId c = 0; c < mesh.num_cells(); ++c) {
        const auto mine = mesh.cell(c), theirs = reference.cell(c);
        if (mesh.cell_type(c) != reference.cell_type(c) || !std::equal(mine.begin(), mine.end(), theirs.begin(), theirs.end()))
            throw MeshError("element " + std::to_string(c) + " of the reference mesh has other vertices than the mesh's: "
                            "a reference must have the mesh's connectivity");
    }
}

TargetOptions TargetOptions::from(std::string_view list, TargetSource source) {
    TargetOptions o;
    std::string known;
    for (std::string_view name : kFactorNames) known += (known.empty() ? "" : ", ") + std::string(name);
    while (!list.empty()) {
        const std::size_t comma = list.find(',');
        std::string_view word = list.substr(0, comma);
        list = comma == std::string_view::npos ? std::string_view{} : list.substr(comma + 1);
        while (!word.empty() && word.front() == ' ') word.remove_prefix(1);
        while (!word.empty() && word.back() == ' ') word.remove_suffix(1);
        if (word == "all") {
            for (std::size_t i = 0; i < kFactorNames.size(); ++i) factor_of(o, i) = source;
            continue;
        }
        const auto* found = std::find(kFactorNames.begin(), kFactorNames.end(), word);
        if (found == kFactorNames.end())
            throw OptionError("unknown target factor '" + std::string(word) + "' (known: " + known + ", all)");
        factor_of(o, static_cast<std::size_t>(found - kFactorNames.begin())) = source;
    }
    return o;
}

bool TargetOptions::any() const {
    return size != TargetSource::Ideal || orientation != TargetSource::Ideal || aspect != TargetSource::Ideal ||
           skew != TargetSource::Ideal;
}

bool TargetOptions::uses(TargetSource source) const {
    for (std::size_t i = 0; i < kFactorNames.size(); ++i)
        if (factor_of(*this, i) == source) return true;
    return false;
}

std::string TargetOptions::list(TargetSource source) const {
    std::string out;
    for (std::size_t i = 0; i < kFactorNames.size(); ++i)
        if (factor_of(*this, i) == source) {
            if (!out.empty()) out += ',';
            out += kFactorNames[i];
        }
    return out;
}

std::string TargetOptions::metric(std::string_view shape_metric) const {
    if (orientation == TargetSource::Metric) return "shape_size";
    if (orientation != TargetSource::Ideal) return "shape_size_orient";
    if (size != TargetSource::Ideal) return "shape_size";
    return std::string(shape_metric);
}

namespace {
// The plane's basis (a, b) of a 2D mesh; the coordinate axes x and y for a volume mesh, whose
// edge matrices use their coordinates as they are.
void basis_of(const Mesh& mesh, metrics::P& a, metrics::P& b) {
    a = {1.0, 0.0, 0.0}, b = {0.0, 1.0, 0.0};
    if (mesh.kind() != ElementKind::Triangle) return;
    const Vec3& n = mesh.plane_normal();
    metrics::plane_basis({n[0], n[1], n[2]}, a, b);
}

// The basis each element's corner edges are read in (edge_matrix): the mesh's (basis_of), or on a
// surface mesh each element's own, the basis (plane_basis) of its corners' own normal in the
// input, where its target is taken; surface_root carries it to the x and y axes.
class Frames {
public:
    Frames(const Mesh& mesh, bool surface) : surface_(surface) { basis_of(mesh, a_, b_); }
    void of(const Mesh& mesh, ElementId e, metrics::P& a, metrics::P& b) const {
        if (!surface_) {
            a = a_, b = b_;
            return;
        }
        const auto corners = mesh.element(e);
        const double* xyz = mesh.coordinates().data();
        const metrics::P origin = metrics::load(xyz, corners[0]);
        const metrics::P n = metrics::cross(metrics::load(xyz, corners[1]) - origin, metrics::load(xyz, corners[2]) - origin);
        const double length = metrics::norm(n);
        // A degenerate element has no plane; its target is then the ideal one (factor() says so).
        metrics::plane_basis(length > 0.0 ? (1.0 / length) * n : metrics::P{0.0, 0.0, 1.0}, a, b);
    }

private:
    bool surface_;
    metrics::P a_, b_;
};

// |det A| / det W_ideal of element e: its size against the ideal element's.
double size_ratio(const Mesh& mesh, ElementId e, const Matrix& regular, const Frames& frames) {
    const int d = mesh.corners() - 1;
    metrics::P a, b;
    frames.of(mesh, e, a, b);
    return std::abs(determinant(edge_matrix(mesh, mesh.coordinates(), e, a, b), d)) /
           determinant(ideal_frame(mesh, e, regular, d), d);
}
// Whether the symmetric d x d matrix m is positive definite: its leading minors are positive.
bool positive_definite(const Matrix& m, int d) {
    return m[0][0] > 0.0 && m[0][0] * m[1][1] - m[0][1] * m[1][0] > 0.0 && (d < 3 || determinant(m, 3) > 0.0);
}

// The mean over element e's vertices of a symmetric matrix per vertex (Mesh::target_metrics' order).
Matrix mean_at_corners(const Mesh& mesh, ElementId e, std::span<const double> per_vertex) {
    Matrix mean{};
    for (VertexId vertex : mesh.element(e))
        for (int k = 0; k < Mesh::kMetricValues; ++k) {
            const auto [i, j] = kMetricIndex[k];
            const double value = per_vertex[static_cast<std::size_t>(vertex) * Mesh::kMetricValues + k] / mesh.corners();
            mean[i][j] += value;
            if (i != j) mean[j][i] += value;
        }
    return mean;
}

// A simplex rated in the space of the symmetric positive definite metric `metric` (d x d, in the
// plane's basis a, b for a 2D mesh): its target is the regular simplex there, turned as the
// `source` corner is turned there (the polar rotation of M^1/2 A W_regular^-1; none when the
// source corner is inverted or degenerate). Returns the target's shape (det 1) and the metric's
// root M^1/2 at determinant 1 as a map of space (3 x 3; in 2D, the identity off the plane).
struct MetricSpace {
    Matrix shape;
    CornerMap root;
};
MetricSpace metric_space(const Matrix& metric, const Factors& source, const Matrix& regular, int d, const metrics::P& a,
                         const metrics::P& b, bool surface) {
    const Matrix root = at_unit_determinant(symmetric_function(metric, d, [](double x) { return std::sqrt(x); }), d);
    MetricSpace out;
    out.shape = at_unit_determinant(product(turn_in_metric(root, source, regular, d), regular, d), d);
    if (d == 3) {
        out.root = root;
    } else if (surface) {
        out.root = surface_root(root, a, b);
    } else {  // B N B^T + n n^T, B = [a b], n = a x b
        const double u[2][3] = {{a.x, a.y, a.z}, {b.x, b.y, b.z}};
        const double n[3] = {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) {
                double sum = n[r] * n[c];
                for (int i = 0; i < 2; ++i)
                    for (int j = 0; j < 2; ++j) sum += u[i][r] * root[i][j] * u[j][c];
                out.root[r][c] = sum;
            }
    }
    return out;
}

// Element e's target from the mean M of its vertices' target metrics (in the plane's basis a, b for
// a 2D mesh), sized so that its edges have unit length in M: a simplex rated in M (metric_space);
// a cell's corner against its ideal corner carried into M, W = M^-1/2 R W_ideal, R turning it
// within M as the element is (the polar rotation of M^1/2 A W_ideal^-1; none for an inverted or
// degenerate element). Returns what Mesh::set_targets takes for it.
struct MetricTarget {
    CornerMap map;
    double volume;
    std::optional<CornerMap> root;  // a simplex is rated in the metric's space
};
MetricTarget metric_target(const Mesh& mesh, ElementId element, const Matrix& ideal, const Factors& in,
                           const metrics::P& a, const metrics::P& b, const Matrix& regular) {
    const int d = mesh.corners() - 1;
    const Matrix full = mean_at_corners(mesh, element, mesh.target_metrics());
    const Matrix mean = d == 2 ? in_plane(full, a, b) : full;
    if (!(mean[0][0] > 0.0 && determinant(mean, d) > 0.0 && (d == 2 || mean[0][0] * mean[1][1] > mean[0][1] * mean[0][1])))
        throw MeshError("element " + std::to_string(element) + ": the mean of its vertices' target metrics is not positive definite" +
                        (d == 2 ? " in the mesh's plane" : ""));
    // Its size: the ideal corner with unit edges in M, det W = det(M)^-1/2 det W_ideal.
    const double volume_ratio = determinant(ideal, d) / std::sqrt(determinant(mean, d));  // lambda^d
    MetricTarget out;
    out.volume = volume_ratio * determinant(regular, d) / (d == 3 ? 6.0 : 2.0);
    Matrix shape;
    if (is_simplex(mesh, element)) {
        const MetricSpace space = metric_space(mean, in, regular, d, a, b, false);
        shape = space.shape;
        out.root = space.root;
    } else {
        // A cell's corner: its ideal corner carried into M, W = M^-1/2 R W_ideal.
        const Matrix root = symmetric_function(mean, d, [](double x) { return 1.0 / std::sqrt(x); });
        const Matrix inverse_root = symmetric_function(mean, d, [](double x) { return std::sqrt(x); });
        shape = at_unit_determinant(product(root, product(turn_in_metric(inverse_root, in, ideal, d), ideal, d), d), d);
    }
    const Matrix map = product(inverse(shape, d), regular, d);
    out.map = CornerMap{};
    for (int i = 0; i < d; ++i)
        for (int j = 0; j < d; ++j) out.map[i][j] = map[i][j];
    return out;
}
}  // namespace

bool stretches_from_neighbourhood(const TargetOptions& options) {
    return (options.aspect == TargetSource::Input || options.aspect == TargetSource::Reference) &&
           options.skew == TargetSource::Ideal;
}

std::vector<double> vertex_metrics(const Mesh& mesh, const TargetOptions& options, const Mesh* reference) {
    return vertex_metrics(mesh, options, reference, is_surface_mesh(mesh));
}

std::vector<double> vertex_metrics(const Mesh& mesh, const TargetOptions& options, const Mesh* reference, bool surface) {
    if (!stretches_from_neighbourhood(options)) return {};
    if (options.aspect == TargetSource::Reference && (!reference || surface)) return {};  // set_targets says what is missing
    if (reference) check_reference(mesh, *reference);
    const Mesh& source = options.aspect == TargetSource::Reference ? *reference : mesh;
    const Frames frames(source, surface);
    const int d = mesh.corners() - 1;
    const Matrix regular_inverse = inverse(regular_frame(d), d);
    const auto m = static_cast<std::size_t>(mesh.num_elements());
    std::vector<std::array<double, Mesh::kMetricValues>> metric(m);
    std::vector<std::uint8_t> usable(m);
    for (std::size_t e = 0; e < m; ++e) {
        Matrix element{};
        metrics::P a, b;
        frames.of(source, static_cast<ElementId>(e), a, b);
        if (!is_simplex(mesh, static_cast<ElementId>(e)) ||
            !element_metric(source, source.coordinates(), static_cast<ElementId>(e), a, b, regular_inverse, element))
            continue;
        // A surface's elements each have their own plane: their metrics meet at a vertex in space.
        if (surface) element = in_space(element, a, b);
        usable[e] = 1;
        for (int k = 0; k < Mesh::kMetricValues; ++k) metric[e][k] = element[kMetricIndex[k][0]][kMetricIndex[k][1]];
    }
    // Exact sums: a part lists a vertex's elements in another order than the whole mesh does.
    std::vector<double> out(static_cast<std::size_t>(mesh.num_vertices()) * Mesh::kMetricValues, 0.0);
    for (VertexId v = 0; v < mesh.num_vertices(); ++v) {
        std::array<ExactSum, Mesh::kMetricValues> sums{};
        double count = 0.0;
        for (ElementId e : mesh.elements_of(v)) {
            if (!usable[static_cast<std::size_t>(e)]) continue;
            count += 1.0;
            for (int k = 0; k < Mesh::kMetricValues; ++k) sums[k].add(metric[static_cast<std::size_t>(e)][k]);
        }
        if (count == 0.0) continue;
        for (int k = 0; k < Mesh::kMetricValues; ++k) out[static_cast<std::size_t>(v) * Mesh::kMetricValues + k] = sums[k].value() / count;
    }
    return out;
}

ExactSum ideal_size_sum(const Mesh& mesh, std::span<const std::uint8_t> counted) {
    return ideal_size_sum(mesh, counted, is_surface_mesh(mesh));
}

ExactSum ideal_size_sum(const Mesh& mesh, std::span<const std::uint8_t> counted, bool surface) {
    const Frames frames(mesh, surface);
    const Matrix regular = regular_frame(mesh.corners() - 1);
    const auto sums = detail::exact_sums<1>(static_cast<std::size_t>(mesh.num_elements()), [&](std::size_t e, auto& acc) {
        if (counted.empty() || counted[e]) acc[0].add(size_ratio(mesh, static_cast<ElementId>(e), regular, frames));
    });
    return sums[0];
}

void set_targets(Mesh& mesh, const TargetOptions& options, const Mesh* reference) {
    const double elements = static_cast<double>(mesh.num_elements());
    set_targets(mesh, options, reference, elements > 0 ? ideal_size_sum(mesh).value() / elements : 1.0,
                vertex_metrics(mesh, options, reference));
}

void set_targets(Mesh& mesh, const TargetOptions& options, const Mesh* reference, double ideal_scale,
                 std::span<const double> metrics) {
    set_targets(mesh, options, reference, ideal_scale, metrics, is_surface_mesh(mesh));
}

void set_targets(Mesh& mesh, const TargetOptions& options, const Mesh* reference, double ideal_scale,
                 std::span<const double> metrics, bool surface) {
    if (!options.any()) {
        mesh.clear_targets();
        return;
    }
    if (options.uses(TargetSource::Reference) && !reference)
        throw OptionError("targets from a reference mesh (" + options.list(TargetSource::Reference) +
                          ") need the reference mesh (targets.reference, input.displacement, or Mesh::set_reference_coordinates)");
    if (options.orientation == TargetSource::Field || options.aspect == TargetSource::Field ||
        options.skew == TargetSource::Field)
        throw OptionError("only the size comes from a size field (targets.size_field); got " + options.list(TargetSource::Field));
    const auto lengths = mesh.target_edge_lengths();
    if (options.size == TargetSource::Field && lengths.empty())
        throw OptionError("target sizes from a size field need its edge lengths (targets.size_field, --size-field, or "
                          "Mesh::set_target_edge_lengths)");
    const bool from_metric = options.uses(TargetSource::Metric);
    if (from_metric && !(options.size == TargetSource::Metric && options.aspect == TargetSource::Metric &&
                         options.orientation == TargetSource::Metric && options.skew == TargetSource::Ideal))
        throw OptionError("a metric field gives size, aspect and orientation together and the skew is ideal in it; got " +
                          options.list(TargetSource::Metric) + " from it");
    if (from_metric && mesh.target_metrics().empty())
        throw OptionError("targets from a metric field need its metrics (targets.metric_field, --metric-field, or "
                          "Mesh::set_target_metrics)");
    if (surface && (options.uses(TargetSource::Reference) || from_metric))
        throw OptionError("targets on a surface mesh come from the input (keep) or a size field: a reference mesh and a "
                          "metric field do not go with surface meshes yet");
    if (reference) check_reference(mesh, *reference);
    const int d = mesh.corners() - 1;
    const auto m = static_cast<std::size_t>(mesh.num_elements());
    const Frames frames(mesh, surface);
    metrics::P ra, rb;
    if (reference) basis_of(*reference, ra, rb);
    const Matrix regular = regular_frame(d);
    const double regular_volume = determinant(regular, d) / (d == 3 ? 6.0 : 2.0);
    // Every corner flat: nothing to size by.
    const double scale = ideal_scale > 0.0 && std::isfinite(ideal_scale) ? ideal_scale : 1.0;

    std::vector<CornerMap> maps(m);
    std::vector<double> volumes(m);
    // Metric roots, where some element is rated in a metric's space; the identity for the others.
    std::vector<CornerMap> roots;
    const auto set_root = [&](std::size_t e, const CornerMap& root) {
        if (roots.empty()) roots.assign(m, CornerMap{{{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}}});
        roots[e] = root;
    };
    for (std::size_t e = 0; e < m; ++e) {
        const auto element = static_cast<ElementId>(e);
        metrics::P a, b;
        frames.of(mesh, element, a, b);
        const Matrix ideal = ideal_frame(mesh, element, regular, d);
        const Factors id = factor(ideal, d);
        const Factors in = factor(edge_matrix(mesh, mesh.coordinates(), element, a, b), d);
        const Factors ref = reference ? factor(edge_matrix(*reference, reference->coordinates(), element, ra, rb), d)
                                      : Factors{};
        if (from_metric) {
            const MetricTarget target = metric_target(mesh, element, ideal, in, a, b, regular);
            maps[e] = target.map;
            volumes[e] = target.volume;
            if (target.root) set_root(e, *target.root);
            continue;
        }
        auto pick = [&](TargetSource source) -> const Factors& {
            const Factors& f = source == TargetSource::Input ? in : source == TargetSource::Reference ? ref : id;
            return f.valid ? f : id;
        };
        const Factors& sized = pick(options.size);
        double lambda = &sized != &id ? sized.lambda : std::pow(scale * determinant(ideal, d), 1.0 / d);
        if (options.size == TargetSource::Field) {
            // The ideal corner with its edges at the mean of the vertices' lengths (its own edges
            // are of unit length).
            double sum = 0.0;
            for (VertexId v : mesh.element(element)) sum += lengths[static_cast<std::size_t>(v)];
            lambda = sum / static_cast<double>(mesh.corners()) * std::pow(determinant(ideal, d), 1.0 / d);
        }
        // W / lambda = V Q D. The orientation V is chosen so that W's polar rotation is the
        // source corner's: a corner's orientation then does not depend on which of its edges is
        // listed first (QR's V does), and the corners of one sheared cell agree on it. With every
        // factor from one corner, V is QR's and W is that corner.
        const Factors& oriented = pick(options.orientation);
        const Matrix& source = oriented.positive ? oriented.frame : id.frame;
        Matrix shape;
        // A simplex none of whose vertices has a simplex that is not degenerate around it has no
        // metric (its vertices' are 0): like a degenerate corner, it gives no aspect.
        std::optional<Matrix> mean;
        if (!metrics.empty() && is_simplex(mesh, element)) {
            const Matrix at_corners = mean_at_corners(mesh, element, metrics);
            if (positive_definite(surface ? in_plane(at_corners, a, b) : at_corners, d)) mean = at_corners;
        }
        if (mean) {
            // Rated in the mean M of its vertices' metrics, against the regular simplex turned
            // there as the aspect's source corner is (shape metrics ignore the turn, orientation
            // metrics compare with it; an ideal orientation leaves it out).
            const MetricSpace space = metric_space(surface ? in_plane(*mean, a, b) : *mean, pick(options.aspect), regular, d,
                                                   a, b, surface);
            shape = space.shape;
            if (options.orientation == TargetSource::Ideal) shape = at_unit_determinant(regular, d);
            set_root(e, space.root);
        } else {
            const Matrix skew_aspect = product(pick(options.skew).q, pick(options.aspect).d, d);
            const Matrix v = product(polar_rotation(source, d), transpose(polar_rotation(skew_aspect, d), d), d);
            shape = product(v, skew_aspect, d);
            if (surface) set_root(e, surface_root(Matrix{{{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}}}, a, b));
        }
        const Matrix map = product(inverse(shape, d), regular, d);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) maps[e][i][j] = i < d && j < d ? map[i][j] : 0.0;
        volumes[e] = std::pow(lambda, d) * regular_volume;
    }
    mesh.set_targets(std::move(maps), std::move(volumes), std::move(roots));
}

}  // namespace paloverde
