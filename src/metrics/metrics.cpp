#include <algorithm>
#include <cmath>
#include <numbers>

#include "kernels.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/mesh/simplex_mesh.hpp"

namespace paloverde {

namespace metrics {
namespace {

template <class K>
constexpr bool assessment_only() {
    if constexpr (requires { K::assessment_only; }) return K::assessment_only;
    return false;
}

// Gathers each element's corners into a small buffer, calls the inlined kernel, and scatters the
// weighted gradient: one virtual call per batch, none per element.
template <class Kernel>
class KernelMetric final : public QualityMetric {
public:
    explicit KernelMetric(Kernel kernel = {}) : kernel_(kernel) {}

    std::string_view name() const override { return Kernel::name; }
    bool supports(ElementKind kind) const override {
        if constexpr (requires { Kernel::only_kind; }) return kind == Kernel::only_kind;
        return true;
    }
    bool has_gradient() const override { return !assessment_only<Kernel>(); }
    double ideal_value() const override {
        if constexpr (requires { Kernel::ideal; }) return Kernel::ideal;
        return 1.0;
    }

    double value(ElementKind kind, const double* corners) const override {
        return kind == ElementKind::Tetrahedron ? kernel_.tet(corners, nullptr, scale_)
                                                : kernel_.tri(corners, nullptr, scale_);
    }
    double value_and_gradient(ElementKind kind, const double* corners, double* gradient) const override {
        require_gradient();
        return kind == ElementKind::Tetrahedron ? kernel_.tet(corners, gradient, scale_)
                                                : kernel_.tri(corners, gradient, scale_);
    }

    void evaluate(const SimplexMesh& mesh, std::span<const double> xyz, ElementId first, ElementId last,
                  double* quality) const override {
        if constexpr (kHasBlocks) {
            if (blocks_pay(mesh, first, last)) return evaluate_blocks(mesh, xyz, first, last, quality);
        }
        if (mesh.kind() == ElementKind::Tetrahedron)
            evaluate_kind<4>(mesh, xyz, first, last, quality);
        else
            evaluate_kind<3>(mesh, xyz, first, last, quality);
    }

    void accumulate_gradient(const SimplexMesh& mesh, std::span<const double> xyz, ElementId first, ElementId last,
                             const GradientTarget& target) const override {
        require_gradient();
        const bool curvature = target.curvature && target.curvature_weight;
        if constexpr (kHasBlocks) {
            if (blocks_pay(mesh, first, last)) {
                if (curvature) accumulate_blocks<true>(mesh, xyz, first, last, target);
                else accumulate_blocks<false>(mesh, xyz, first, last, target);
                return;
            }
        }
        if (mesh.kind() == ElementKind::Tetrahedron) {
            if (curvature) accumulate_kind<4, true>(mesh, xyz, first, last, target);
            else accumulate_kind<4, false>(mesh, xyz, first, last, target);
        } else {
            if (curvature) accumulate_kind<3, true>(mesh, xyz, first, last, target);
            else accumulate_kind<3, false>(mesh, xyz, first, last, target);
        }
    }

private:
    static constexpr bool kHasBlocks = requires(const Kernel k, const TetBlock& x, TetBlock* g) {
        k.tet_block(BlockPath::baseline, x, nullptr, nullptr, g);
    };

    // Blocks for tetrahedra, when the range fills one: the local smoother rates one element at a
    // time, and a block of one would cost 16. (Both paths give the same bits.)
    static bool blocks_pay(const SimplexMesh& mesh, ElementId first, ElementId last) {
        return mesh.kind() == ElementKind::Tetrahedron && last - first >= kTetBlock;
    }

    void require_gradient() const {
        if (assessment_only<Kernel>())
            throw OptionError("metric '" + std::string(Kernel::name) + "' is for assessment only and has no gradient");
    }

    template <int K>
    double kernel(const double* x, double* g, const MetricScale& scale) const {
        if constexpr (K == 4) return kernel_.tet(x, g, scale);
        else return kernel_.tri(x, g, scale);
    }
    // Element e's reference volume: its own when there are some, else the mesh's.
    double reference_volume_of(ElementId e) const {
        return scale_.element_reference_volume.empty() ? scale_.reference_volume
                                                       : scale_.element_reference_volume[static_cast<std::size_t>(e)];
    }
    // The scale of element e: the mesh's, with e's own reference volume.
    const MetricScale& scale_of(ElementId e, MetricScale& local) const {
        if (scale_.element_reference_volume.empty()) return scale_;
        local.reference_volume = reference_volume_of(e);
        return local;
    }

    template <int K>
    void evaluate_kind(const SimplexMesh& mesh, std::span<const double> xyz, ElementId first, ElementId last,
                       double* quality) const {
        const VertexId* conn = mesh.connectivity().data();
        const double* coords = xyz.data();
        double x[3 * K];
        MetricScale local = scale_;
        for (ElementId e = first; e < last; ++e) {
            const VertexId* c = conn + static_cast<std::size_t>(e) * K;
            for (int i = 0; i < K; ++i)
                for (int d = 0; d < 3; ++d) x[3 * i + d] = coords[3 * static_cast<std::size_t>(c[i]) + d];
            quality[e - first] = kernel<K>(x, nullptr, scale_of(e, local));
        }
    }

    template <int K, bool Curvature>
    void accumulate_kind(const SimplexMesh& mesh, std::span<const double> xyz, ElementId first, ElementId last,
                         const GradientTarget& target) const {
        const VertexId* conn = mesh.connectivity().data();
        const double* coords = xyz.data();
        double x[3 * K], g[3 * K];
        MetricScale local = scale_;
        for (ElementId e = first; e < last; ++e) {
            const double w = target.weight[e - first];
            const double cw = Curvature ? target.curvature_weight[e - first] : 0.0;
            if (w == 0.0 && cw == 0.0) continue;
            const VertexId* c = conn + static_cast<std::size_t>(e) * K;
            for (int i = 0; i < K; ++i)
                for (int d = 0; d < 3; ++d) x[3 * i + d] = coords[3 * static_cast<std::size_t>(c[i]) + d];
            kernel<K>(x, g, scale_of(e, local));
            for (int i = 0; i < K; ++i)
                add_corner<Curvature>(target, static_cast<std::size_t>(c[i] - target.base), w, cw, g + 3 * i);
        }
    }

    // Adds one corner's weighted gradient (and curvature) to the target: the one place where both
    // passes add, so that they add alike, bit for bit.
    template <bool Curvature>
    static void add_corner(const GradientTarget& target, std::size_t v, double w, double cw, const double* gi) {
        for (int d = 0; d < 3; ++d) target.gradient[3 * v + d] += w * gi[d];
        if constexpr (Curvature) {
            double* m = target.curvature + 6 * v;
            m[0] += cw * gi[0] * gi[0];
            m[1] += cw * gi[0] * gi[1];
            m[2] += cw * gi[0] * gi[2];
            m[3] += cw * gi[1] * gi[1];
            m[4] += cw * gi[1] * gi[2];
            m[5] += cw * gi[2] * gi[2];
        }
    }

    // Block passes over tetrahedra: gather the corners of kTetBlock elements (and their reference
    // volumes), rate them in one vectorized call, and scatter. Padding lanes of a last, partial
    // block hold a degenerate element at the origin, which rates 0 without trouble.
    void gather_block(const VertexId* conn, const double* coords, ElementId first, int count, TetBlock& x,
                      double* reference_volume) const {
        gather_tets(conn + 4 * static_cast<std::size_t>(first), coords, count, x);
        for (int j = 0; j < count; ++j) reference_volume[j] = reference_volume_of(first + j);
        for (int j = count; j < kTetBlock; ++j) reference_volume[j] = 1.0;
    }

    void evaluate_blocks(const SimplexMesh& mesh, std::span<const double> xyz, ElementId first, ElementId last,
                         double* quality) const {
        const VertexId* conn = mesh.connectivity().data();
        TetBlock x;
        alignas(64) double reference_volume[kTetBlock], q[kTetBlock];
        for (ElementId b = first; b < last; b += kTetBlock) {
            const int count = static_cast<int>(std::min<ElementId>(kTetBlock, last - b));
            gather_block(conn, xyz.data(), b, count, x, reference_volume);
            kernel_.tet_block(path_, x, reference_volume, q, nullptr);
            std::copy(q, q + count, quality + (b - first));
        }
    }

    // Adds to the target in the order accumulate_kind does: bit for bit the same sums.
    template <bool Curvature>
    void accumulate_blocks(const SimplexMesh& mesh, std::span<const double> xyz, ElementId first, ElementId last,
                           const GradientTarget& target) const {
        const VertexId* conn = mesh.connectivity().data();
        TetBlock x, g;
        alignas(64) double reference_volume[kTetBlock], q[kTetBlock];
        for (ElementId b = first; b < last; b += kTetBlock) {
            const int count = static_cast<int>(std::min<ElementId>(kTetBlock, last - b));
            gather_block(conn, xyz.data(), b, count, x, reference_volume);
            kernel_.tet_block(path_, x, reference_volume, q, &g);
            for (int j = 0; j < count; ++j) {
                const ElementId e = b + j;
                const double w = target.weight[e - first];
                const double cw = Curvature ? target.curvature_weight[e - first] : 0.0;
                if (w == 0.0 && cw == 0.0) continue;
                const VertexId* c = conn + 4 * static_cast<std::size_t>(e);
                for (int i = 0; i < 4; ++i) {
                    const double gi[3] = {g.at[3 * i][j], g.at[3 * i + 1][j], g.at[3 * i + 2][j]};
                    add_corner<Curvature>(target, static_cast<std::size_t>(c[i] - target.base), w, cw, gi);
                }
            }
        }
    }

    Kernel kernel_;
    BlockPath path_ = best_block_path();
};

}  // namespace
}  // namespace metrics

MetricScale MetricScale::of(const SimplexMesh& mesh) { return of(mesh, mesh.coordinates()); }

MetricScale MetricScale::of(const SimplexMesh& mesh, std::span<const double> coordinates) {
    MetricScale scale;
    scale.oriented_triangles = mesh.kind() == ElementKind::Tetrahedron || mesh.is_planar();
    scale.plane_normal = mesh.plane_normal();
    const ElementId m = mesh.num_elements();
    if (m == 0) return scale;
    std::vector<double> volume(static_cast<std::size_t>(m));
    scale.reference_volume = 1.0;
    auto unit = make_metric("scaled_volume");
    unit->set_scale(scale);
    unit->evaluate(mesh, coordinates, 0, m, volume.data());
    double sum = 0.0;
    for (double v : volume) sum += std::abs(v);
    // A mesh of only degenerate elements keeps 1: there is no size to measure against.
    if (sum > 0.0 && std::isfinite(sum)) scale.reference_volume = sum / m;
    return scale;
}

void MetricOptions::validate() const {
    if (!(hybrid_sharpness > 0.0) || !std::isfinite(hybrid_sharpness))
        throw OptionError("hybrid_sharpness must be a positive number (got " + std::to_string(hybrid_sharpness) + ")");
}

const std::vector<std::string>& metric_names() {
    static const std::vector<std::string> names{"aspect_ratio", "mean_ratio",      "inverse_condition",
                                                "edge_ratio",   "scaled_volume",   "untangle_hybrid",
                                                "min_dihedral_deg", "min_angle_deg"};
    return names;
}

std::unique_ptr<QualityMetric> make_metric(std::string_view name, const MetricOptions& options) {
    using namespace metrics;
    options.validate();
    if (name == AspectRatio::name) return std::make_unique<KernelMetric<AspectRatio>>();
    if (name == MeanRatio::name) return std::make_unique<KernelMetric<MeanRatio>>();
    if (name == InverseCondition::name) return std::make_unique<KernelMetric<InverseCondition>>();
    if (name == EdgeRatio::name) return std::make_unique<KernelMetric<EdgeRatio>>();
    if (name == ScaledVolume::name) return std::make_unique<KernelMetric<ScaledVolume>>();
    if (name == UntangleHybrid::name)
        return std::make_unique<KernelMetric<UntangleHybrid>>(UntangleHybrid{options.hybrid_sharpness});
    if (name == MinDihedralAngle::name) return std::make_unique<KernelMetric<MinDihedralAngle>>();
    if (name == MinCornerAngle::name) return std::make_unique<KernelMetric<MinCornerAngle>>();
    std::string known;
    for (const auto& n : metric_names()) known += (known.empty() ? "" : ", ") + n;
    throw OptionError("unknown quality metric '" + std::string(name) + "' (known: " + known + ")");
}

std::unique_ptr<QualityMetric> make_untangle_energy(double epsilon, double theta) {
    if (!(epsilon > 0.0) || !std::isfinite(epsilon) || !(theta >= 0.0 && theta <= 1.0))
        throw OptionError("untangle_energy needs epsilon > 0 and theta in [0, 1]");
    return std::make_unique<metrics::KernelMetric<metrics::RegularizedEnergy>>(metrics::RegularizedEnergy{epsilon, theta});
}

}  // namespace paloverde
