#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include "core/prefetch.hpp"
#include "evaluate_together.hpp"
#include "kernels.hpp"
#include "scaled_jacobian.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/mesh/cell_types.hpp"
#include "paloverde/mesh/mesh.hpp"

namespace paloverde {

namespace metrics {
namespace {

template <class K>
constexpr bool assessment_only() {
    if constexpr (requires { K::assessment_only; }) return K::assessment_only;
    return false;
}

// Where corner vertex v's sums go in the target (GradientTarget).
inline std::size_t corner_slot(const QualityMetric::GradientTarget& target, VertexId v) {
    const auto i = static_cast<std::size_t>(v - target.base);
    return target.slot ? target.slot[i] : i;
}

// Adds one corner's weighted gradient (and curvature) to the target: the one place where every
// pass adds, so that they add alike, bit for bit.
template <bool Curvature>
void add_corner(const QualityMetric::GradientTarget& target, std::size_t v, double w, double cw, const double* gi) {
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

// A cell's corner simplex x (K points) carried to the simplex its map rates in its place
// (cell_types.hpp): y_0 = x_0, y_i = x_0 + sum_j (x_j - x_0) M[j][i].
template <int K>
void map_corner(const CornerMap& m, double* x) {
    double e[K - 1][3];
    for (int j = 1; j < K; ++j)
        for (int d = 0; d < 3; ++d) e[j - 1][d] = x[3 * j + d] - x[d];
    for (int i = 1; i < K; ++i)
        for (int d = 0; d < 3; ++d) {
            double sum = 0.0;
            for (int j = 1; j < K; ++j) sum += e[j - 1][d] * m[j - 1][i - 1];
            x[3 * i + d] = x[d] + sum;
        }
}
// The chain rule back through the map: g_xj = sum_i g_yi M[j][i]; the gradients of a
// translation-invariant metric sum to zero, so g_x0 is what makes both sums equal.
template <int K>
void unmap_gradient(const CornerMap& m, double* g) {
    double gy[K][3], total[3] = {0.0, 0.0, 0.0};
    for (int i = 0; i < K; ++i)
        for (int d = 0; d < 3; ++d) gy[i][d] = g[3 * i + d], total[d] += g[3 * i + d];
    for (int j = 1; j < K; ++j)
        for (int d = 0; d < 3; ++d) {
            double sum = 0.0;
            for (int i = 1; i < K; ++i) sum += gy[i][d] * m[j - 1][i - 1];
            g[3 * j + d] = sum;
            total[d] -= sum;
        }
    for (int d = 0; d < 3; ++d) g[d] = total[d];
}

// Where an element's corners are carried before a kernel rates them: by its map (its target's
// where the mesh has targets, else its cell's corner map; none for a simplex mesh's elements),
// then into its target's metric space (Mesh::target_metric_roots) where it has one.
struct ElementMap {
    const CornerMap* map = nullptr;
    const CornerMap* root = nullptr;
    explicit operator bool() const { return map || root; }
};

// Every corner carried by the metric root n (z = n y; the kernels are translation invariant).
template <int K>
void map_corner(const ElementMap& m, double* x) {
    if (m.map) map_corner<K>(*m.map, x);
    if (!m.root) return;
    const CornerMap& n = *m.root;
    for (int i = 0; i < K; ++i) {
        const double y[3] = {x[3 * i], x[3 * i + 1], x[3 * i + 2]};
        for (int r = 0; r < 3; ++r) x[3 * i + r] = n[r][0] * y[0] + n[r][1] * y[1] + n[r][2] * y[2];
    }
}
template <int K>
void unmap_gradient(const ElementMap& m, double* g) {
    if (m.root) {
        const CornerMap& n = *m.root;
        for (int i = 0; i < K; ++i) {
            const double gz[3] = {g[3 * i], g[3 * i + 1], g[3 * i + 2]};
            for (int c = 0; c < 3; ++c) g[3 * i + c] = n[0][c] * gz[0] + n[1][c] * gz[1] + n[2][c] * gz[2];
        }
    }
    if (m.map) unmap_gradient<K>(*m.map, g);
}

class ElementMaps {
public:
    explicit ElementMaps(const Mesh& mesh)
        : ids_(mesh.corner_maps().empty() ? nullptr : mesh.corner_maps().data()),
          targets_(mesh.has_targets() ? mesh.target_maps().data() : nullptr),
          roots_(mesh.target_metric_roots().empty() ? nullptr : mesh.target_metric_roots().data()) {}
    explicit operator bool() const { return ids_ || targets_; }
    // Every element carried by its target's map (and metric root): a block maps its lanes together
    // (map_block).
    bool has_targets() const { return targets_ != nullptr; }
    bool has_roots() const { return roots_ != nullptr; }
    const CornerMap* target(ElementId e) const { return targets_ + e; }
    const CornerMap* root(ElementId e) const { return roots_ + e; }
    ElementMap of(ElementId e) const {
        if (targets_) return {targets_ + e, roots_ ? roots_ + e : nullptr};
        return {ids_ && ids_[e] ? &corner_map(ids_[e]) : nullptr, nullptr};
    }

private:
    const std::uint8_t* ids_;
    const CornerMap* targets_;
    const CornerMap* roots_;
};

// Gathers element e's K corners into x, mapped when the element has a map.
template <int K>
void gather(const VertexId* c, const double* coords, const ElementMaps& maps, ElementId e, double* x) {
    for (int i = 0; i < K; ++i)
        for (int d = 0; d < 3; ++d) x[3 * i + d] = coords[3 * static_cast<std::size_t>(c[i]) + d];
    if (const ElementMap m = maps.of(e)) map_corner<K>(m, x);
}

// The element-by-element passes, for kernels and for a program's own metrics alike: each
// element's K corners gathered into a small buffer, rated by rate(kind tag, e, corners, gradient
// or nullptr), and its weighted gradient scattered.
template <int K, class Rate>
void rate_each(const Mesh& mesh, std::span<const double> xyz, ElementId first, ElementId last, double* quality,
               Rate& rate) {
    const VertexId* conn = mesh.connectivity().data();
    const double* coords = xyz.data();
    const ElementMaps maps(mesh);
    double x[3 * K];
    const bool ask_ahead = !mesh.locality_ordered();
    for (ElementId e = first; e < last; ++e) {
        if (ask_ahead && e + detail::kPrefetchAhead < last)
            detail::prefetch_corners(conn + static_cast<std::size_t>(e + detail::kPrefetchAhead) * K, K, coords);
        gather<K>(conn + static_cast<std::size_t>(e) * K, coords, maps, e, x);
        quality[e - first] = rate(std::integral_constant<int, K>{}, e, x, nullptr);
    }
}

template <int K, bool Curvature, class Rate>
void accumulate_each(const Mesh& mesh, std::span<const double> xyz, ElementId first, ElementId last,
                     const QualityMetric::GradientTarget& target, Rate& rate) {
    const VertexId* conn = mesh.connectivity().data();
    const double* coords = xyz.data();
    const ElementMaps maps(mesh);
    double x[3 * K], g[3 * K];
    for (ElementId e = first; e < last; ++e) {
        const double w = target.weight[e - first];
        const double cw = Curvature ? target.curvature_weight[e - first] : 0.0;
        if (w == 0.0 && cw == 0.0) continue;
        const VertexId* c = conn + static_cast<std::size_t>(e) * K;
        gather<K>(c, coords, maps, e, x);
        rate(std::integral_constant<int, K>{}, e, x, g);
        if (const ElementMap m = maps.of(e)) unmap_gradient<K>(m, g);
        for (int i = 0; i < K; ++i) add_corner<Curvature>(target, corner_slot(target, c[i]), w, cw, g + 3 * i);
    }
}

// The two passes over any mesh: K from its kind, curvature when the target asks for it.
template <class Rate>
void evaluate_each(const Mesh& mesh, std::span<const double> xyz, ElementId first, ElementId last, double* quality,
                   Rate&& rate) {
    if (mesh.kind() == ElementKind::Tetrahedron) rate_each<4>(mesh, xyz, first, last, quality, rate);
    else rate_each<3>(mesh, xyz, first, last, quality, rate);
}

template <class Rate>
void accumulate_gradient_each(const Mesh& mesh, std::span<const double> xyz, ElementId first, ElementId last,
                              const QualityMetric::GradientTarget& target, Rate&& rate) {
    const bool curvature = target.curvature && target.curvature_weight;
    if (mesh.kind() == ElementKind::Tetrahedron) {
        if (curvature) accumulate_each<4, true>(mesh, xyz, first, last, target, rate);
        else accumulate_each<4, false>(mesh, xyz, first, last, target, rate);
    } else {
        if (curvature) accumulate_each<3, true>(mesh, xyz, first, last, target, rate);
        else accumulate_each<3, false>(mesh, xyz, first, last, target, rate);
    }
}

// Maps the corners of lane j of a gathered block when its element has a map, as gather<4>() maps
// them: the same bits.
inline void map_lane(const ElementMap& m, int j, TetBlock& x) {
    if (!m) return;
    double corner[12];
    for (int i = 0; i < 12; ++i) corner[i] = x.at[i][j];
    map_corner<4>(m, corner);
    for (int i = 0; i < 12; ++i) x.at[i][j] = corner[i];
}

// The targets of a block's lanes, the elements ids(0), ..., ids(count - 1); padding lanes get
// the identity (their corners are at the origin).
struct LaneTargets {
    const CornerMap* map[kTetBlock];
    const CornerMap* root[kTetBlock];
    bool has_roots;
    template <class Ids>
    LaneTargets(const ElementMaps& maps, int count, Ids&& ids) : has_roots(maps.has_roots()) {
        static const CornerMap identity{{{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}}};
        for (int j = 0; j < kTetBlock; ++j) {
            map[j] = j < count ? maps.target(ids(j)) : &identity;
            root[j] = j < count && has_roots ? maps.root(ids(j)) : &identity;
        }
    }
    const CornerMap* const* roots() const { return has_roots ? root : nullptr; }
};

// Maps the corners of a gathered block's lanes, the elements ids(0), ..., ids(count - 1), as
// gather<4>() maps them: by their targets together, else (cells' corner maps) lane by lane.
// Padding lanes stay at the origin.
template <class Ids>
void map_block(const ElementMaps& maps, int count, Ids&& ids, TetBlock& x) {
    if (!maps) return;
    if (maps.has_targets()) {
        const LaneTargets lanes(maps, count, ids);
        return map_tets(best_block_path(), lanes.map, lanes.roots(), x);
    }
    for (int j = 0; j < count; ++j) map_lane(maps.of(ids(j)), j, x);
}

// The chain rule back through map_block() for the lanes' gradients.
template <class Ids>
void unmap_block(const ElementMaps& maps, int count, Ids&& ids, TetBlock& g) {
    if (!maps) return;
    if (maps.has_targets()) {
        const LaneTargets lanes(maps, count, ids);
        return unmap_tets(best_block_path(), lanes.map, lanes.roots(), g);
    }
    for (int j = 0; j < count; ++j) {
        double lane[12];
        for (int i = 0; i < 12; ++i) lane[i] = g.at[i][j];
        unmap_gradient<4>(maps.of(ids(j)), lane);
        for (int i = 0; i < 12; ++i) g.at[i][j] = lane[i];
    }
}

// Gathers the corners of the tetrahedra [first, last) kTetBlock at a time and calls
// rate(corners, b, count) for the block of elements b, ..., b + count - 1. Padding lanes of a
// last, partial block hold a degenerate element at the origin, which rates 0 without trouble. An
// element's corners are mapped as gather<4>() maps them (map_block: the same bits). While a block
// is rated, the next one's corners come in: asked for unless the mesh is in locality order, where
// the 128 prefetch instructions per block cost more than they save (a pass is about a sixth
// faster without them there; on a shuffled mesh, 1-12% slower).
template <class Rate>
void for_each_block(const Mesh& mesh, std::span<const double> xyz, ElementId first, ElementId last, Rate&& rate) {
    const VertexId* conn = mesh.connectivity().data();
    const double* coords = xyz.data();
    const ElementMaps maps(mesh);
    const bool ask_ahead = !mesh.locality_ordered();
    TetBlock x;
    for (ElementId b = first; b < last; b += kTetBlock) {
        const int count = static_cast<int>(std::min<ElementId>(kTetBlock, last - b));
        if (const ElementId next = b + count; ask_ahead && next < last)
            detail::prefetch_corners(conn + 4 * static_cast<std::size_t>(next),
                                     4 * static_cast<int>(std::min<ElementId>(kTetBlock, last - next)), coords);
        gather_tets(conn + 4 * static_cast<std::size_t>(b), coords, count, x);
        map_block(maps, count, [b](int j) { return b + j; }, x);
        rate(std::as_const(x), b, count);
    }
}

// As for_each_block() over the listed tetrahedra, kTetBlock at a time: rate(corners, ids, count)
// for the block of elements ids[0], ..., ids[count - 1].
template <class Rate>
void for_each_listed_block(const Mesh& mesh, std::span<const double> xyz, std::span<const ElementId> elements,
                           Rate&& rate) {
    const VertexId* conn = mesh.connectivity().data();
    const ElementMaps maps(mesh);
    TetBlock x;
    VertexId corners[4 * kTetBlock];
    for (std::size_t b = 0; b < elements.size(); b += kTetBlock) {
        const int count = static_cast<int>(std::min<std::size_t>(kTetBlock, elements.size() - b));
        const ElementId* ids = elements.data() + b;
        for (int j = 0; j < count; ++j)
            std::copy_n(conn + 4 * static_cast<std::size_t>(ids[j]), 4, corners + 4 * j);
        gather_tets(corners, xyz.data(), count, x);
        map_block(maps, count, [ids](int j) { return ids[j]; }, x);
        rate(std::as_const(x), ids, count);
    }
}

// Gathers each element's corners into a small buffer, calls the inlined kernel, and scatters the
// weighted gradient: one virtual call per batch, none per element.
template <class Kernel>
class KernelMetric final : public QualityMetric, public BlockRater {
public:
    explicit KernelMetric(Kernel kernel = {}) : kernel_(kernel) {}

    std::string_view name() const override { return Kernel::name; }
    bool supports(ElementKind kind) const override {
        if constexpr (requires { Kernel::only_kind; }) return kind == Kernel::only_kind;
        return true;
    }
    bool supports_cells() const override {
        if constexpr (requires { Kernel::only_kind; }) return false;  // the angle metrics, in degrees
        return true;
    }
    bool has_gradient() const override { return !assessment_only<Kernel>(); }
    double ideal_value() const override {
        if constexpr (requires { Kernel::ideal; }) return Kernel::ideal;
        return 1.0;
    }
    bool rates_size() const override {
        if constexpr (requires { Kernel::rates_size; }) return Kernel::rates_size;
        return false;
    }
    bool rotation_invariant() const override {
        if constexpr (requires { Kernel::rotation_invariant; }) return Kernel::rotation_invariant;
        return true;
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

    // A size metric rates an element of a mesh with targets against its target's volume, which
    // the one-element calls value() and value_and_gradient() cannot see.
    double element_value(const Mesh& mesh, std::span<const double> xyz, ElementId e,
                         double* gradient = nullptr) const override {
        if (!(kTargetSize && mesh.has_targets()) && !mesh.has_surface_normals() && !has_surface_targets(mesh))
            return QualityMetric::element_value(mesh, xyz, e, gradient);
        if (gradient) require_gradient();
        MetricScale local = scale_;
        const ElementMaps maps(mesh);
        const VertexId* c = mesh.connectivity().data() + static_cast<std::size_t>(e) * mesh.corners();
        double x[12];
        const auto rate = [&]<int K>(std::integral_constant<int, K>) {
            gather<K>(c, xyz.data(), maps, e, x);
            const double q = kernel<K>(x, gradient, scale_of(mesh, e, local));
            if (gradient)
                if (const ElementMap m = maps.of(e)) unmap_gradient<K>(m, gradient);
            return q;
        };
        return mesh.kind() == ElementKind::Tetrahedron ? rate(std::integral_constant<int, 4>{})
                                                       : rate(std::integral_constant<int, 3>{});
    }

    void evaluate(const Mesh& mesh, std::span<const double> xyz, ElementId first, ElementId last,
                  double* quality) const override {
        if constexpr (kHasBlocks || kHasValueBlocks) {
            if (blocks_pay(mesh, first, last)) return evaluate_blocks(mesh, xyz, first, last, quality);
        }
        MetricScale local = scale_;
        evaluate_each(mesh, xyz, first, last, quality, [&](auto k, ElementId e, const double* x, double* g) {
            return kernel<decltype(k)::value>(x, g, scale_of(mesh, e, local));
        });
    }

    void evaluate_listed(const Mesh& mesh, std::span<const double> xyz, std::span<const ElementId> elements,
                         double* quality) const override {
        if constexpr (kHasBlocks || kHasValueBlocks) {
            if (mesh.kind() == ElementKind::Tetrahedron && elements.size() >= static_cast<std::size_t>(kTetBlock)) {
                alignas(64) double reference_volume[kTetBlock], q[kTetBlock];
                for_each_listed_block(mesh, xyz, elements, [&](const TetBlock& x, const ElementId* ids, int count) {
                    for (int j = 0; j < kTetBlock; ++j) reference_volume[j] = j < count ? reference_volume_of(mesh, ids[j]) : 1.0;
                    rate_block_at(x, reference_volume, q);
                    for (int j = 0; j < count; ++j) quality[ids[j]] = q[j];
                });
                return;
            }
        }
        QualityMetric::evaluate_listed(mesh, xyz, elements, quality);
    }

    void element_values(const Mesh& mesh, std::span<const double> xyz, std::span<const ElementId> elements,
                        double* quality, double* gradient) const override {
        if constexpr (kHasBlocks || kHasValueBlocks) {
            if (mesh.kind() == ElementKind::Tetrahedron && elements.size() >= static_cast<std::size_t>(kTetBlock) &&
                (kHasBlocks || !gradient)) {
                if (gradient) require_gradient();
                const ElementMaps maps(mesh);
                // element_value()'s reference volume: a target's for a size metric, else the mesh's.
                const bool targets = kTargetSize && mesh.has_targets();
                alignas(64) double reference_volume[kTetBlock], q[kTetBlock];
                TetBlock g;
                for_each_listed_block(mesh, xyz, elements, [&](const TetBlock& x, const ElementId* ids, int count) {
                    for (int j = 0; j < kTetBlock; ++j)
                        reference_volume[j] = j >= count ? 1.0
                                              : targets ? mesh.target_volumes()[static_cast<std::size_t>(ids[j])]
                                                        : scale_.reference_volume;
                    const auto at = static_cast<std::size_t>(ids - elements.data());
                    if (!gradient) {
                        rate_block_at(x, reference_volume, q);
                    } else if constexpr (kHasBlocks) {  // (a gradient comes here only with a block kernel)
                        kernel_.tet_block(path_, x, reference_volume, q, &g);
                        unmap_block(maps, count, [ids](int j) { return ids[j]; }, g);
                        for (int j = 0; j < count; ++j)
                            for (int i = 0; i < 12; ++i) gradient[12 * (at + j) + i] = g.at[i][j];
                    }
                    std::copy(q, q + count, quality + at);
                });
                return;
            }
        }
        QualityMetric::element_values(mesh, xyz, elements, quality, gradient);
    }

    void accumulate_gradient(const Mesh& mesh, std::span<const double> xyz, ElementId first, ElementId last,
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
        MetricScale local = scale_;
        accumulate_gradient_each(mesh, xyz, first, last, target, [&](auto k, ElementId e, const double* x, double* g) {
            return kernel<decltype(k)::value>(x, g, scale_of(mesh, e, local));
        });
    }

private:
    static constexpr bool kHasBlocks = requires(const Kernel k, const TetBlock& x, TetBlock* g) {
        k.tet_block(BlockPath::baseline, x, nullptr, nullptr, g);
    };
    // Kernels with a block kernel for their values only (the quality report's metrics).
    static constexpr bool kHasValueBlocks = requires(const Kernel k, const TetBlock& x) {
        k.tet_values_block(BlockPath::baseline, x, nullptr, nullptr);
    };

    // Blocks for tetrahedra, when the range fills one: the local smoother rates one element at a
    // time, and a block of one would cost 16. (Both paths give the same bits.)
    static bool blocks_pay(const Mesh& mesh, ElementId first, ElementId last) {
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
    // Size metrics measure an element of a mesh with targets against its target's volume.
    static constexpr bool kTargetSize = [] {
        if constexpr (requires { Kernel::rates_size; }) return Kernel::rates_size;
        return false;
    }();
    // Element e's reference volume: its target's (size metrics), else its own when there are
    // some, else the mesh's.
    double reference_volume_of(const Mesh& mesh, ElementId e) const {
        if (kTargetSize && mesh.has_targets()) return mesh.target_volumes()[static_cast<std::size_t>(e)];
        return scale_.element_reference_volume.empty() ? scale_.reference_volume
                                                       : scale_.element_reference_volume[static_cast<std::size_t>(e)];
    }
    // Triangles with targets on a surface, whether or not a run has set its normals (triangles not
    // in one plane are not oriented without them): each element's root has carried it to the xy
    // plane (targets.cpp, surface_root).
    bool has_surface_targets(const Mesh& mesh) const {
        return mesh.has_targets() && mesh.kind() == ElementKind::Triangle && (mesh.has_surface_normals() || !scale_.oriented_triangles);
    }
    // The scale of element e: the mesh's, with e's own reference volume, and on a surface mesh
    // with e's own normal as its plane's, or with targets the z axis: its metric root has carried
    // it to the xy plane, its target's frame.
    const MetricScale& scale_of(const Mesh& mesh, ElementId e, MetricScale& local) const {
        const bool surface = mesh.has_surface_normals(), surface_targets = has_surface_targets(mesh);
        if (scale_.element_reference_volume.empty() && !(kTargetSize && mesh.has_targets()) && !surface && !surface_targets)
            return scale_;
        local.reference_volume = reference_volume_of(mesh, e);
        if (surface || surface_targets) {
            local.oriented_triangles = true;
            local.plane_normal = surface_targets ? Vec3{0.0, 0.0, 1.0} : mesh.surface_normals()[static_cast<std::size_t>(e)];
        }
        return local;
    }

    // Block passes over tetrahedra: the corners of kTetBlock elements (for_each_block) and their
    // reference volumes rated in one vectorized call, and the gradients scattered.
    void reference_volumes(const Mesh& mesh, ElementId first, int count, double* reference_volume) const {
        for (int j = 0; j < count; ++j) reference_volume[j] = reference_volume_of(mesh, first + j);
        for (int j = count; j < kTetBlock; ++j) reference_volume[j] = 1.0;
    }

    // evaluate_together() hands rate_block() no mesh, and so no targets: a metric that rates size
    // against them takes its blocks in its own passes.
    bool rates_blocks(const Mesh&) const override { return (kHasBlocks || kHasValueBlocks) && !kTargetSize; }
    void rate_block(const TetBlock& x, ElementId first, int count, double* quality) const override {
        alignas(64) double reference_volume[kTetBlock], q[kTetBlock];
        for (int j = 0; j < kTetBlock; ++j)
            reference_volume[j] = j >= count                                  ? 1.0
                                  : scale_.element_reference_volume.empty() ? scale_.reference_volume
                                      : scale_.element_reference_volume[static_cast<std::size_t>(first + j)];
        rate_block_at(x, reference_volume, q);
        std::copy(q, q + count, quality);
    }
    // q[j] for every lane of the block, lane j at reference volume reference_volume[j].
    void rate_block_at(const TetBlock& x, const double* reference_volume, double* q) const {
        if constexpr (kHasBlocks) kernel_.tet_block(path_, x, reference_volume, q, nullptr);
        else if constexpr (kHasValueBlocks) kernel_.tet_values_block(path_, x, reference_volume, q);
        else throw Error("metric '" + std::string(Kernel::name) + "' has no block kernel");
    }

    void evaluate_blocks(const Mesh& mesh, std::span<const double> xyz, ElementId first, ElementId last,
                         double* quality) const {
        alignas(64) double reference_volume[kTetBlock], q[kTetBlock];
        for_each_block(mesh, xyz, first, last, [&](const TetBlock& x, ElementId b, int count) {
            reference_volumes(mesh, b, count, reference_volume);
            rate_block_at(x, reference_volume, q);
            std::copy(q, q + count, quality + (b - first));
        });
    }

    // Adds to the target in the order accumulate_each does: bit for bit the same sums.
    template <bool Curvature>
    void accumulate_blocks(const Mesh& mesh, std::span<const double> xyz, ElementId first, ElementId last,
                           const GradientTarget& target) const {
        const VertexId* conn = mesh.connectivity().data();
        const ElementMaps maps(mesh);
        TetBlock g;
        alignas(64) double reference_volume[kTetBlock], q[kTetBlock];
        for_each_block(mesh, xyz, first, last, [&](const TetBlock& x, ElementId b, int count) {
            reference_volumes(mesh, b, count, reference_volume);
            kernel_.tet_block(path_, x, reference_volume, q, &g);
            const bool targets = maps.has_targets();
            if (targets) {
                const LaneTargets lanes(maps, count, [b](int j) { return b + j; });
                unmap_tets(path_, lanes.map, lanes.roots(), g);
            }
            for (int j = 0; j < count; ++j) {
                const ElementId e = b + j;
                const double w = target.weight[e - first];
                const double cw = Curvature ? target.curvature_weight[e - first] : 0.0;
                if (w == 0.0 && cw == 0.0) continue;
                const VertexId* c = conn + 4 * static_cast<std::size_t>(e);
                double gradient[12];
                for (int i = 0; i < 12; ++i) gradient[i] = g.at[i][j];
                if (const ElementMap m = maps.of(e); m && !targets) unmap_gradient<4>(m, gradient);
                for (int i = 0; i < 4; ++i)
                    add_corner<Curvature>(target, corner_slot(target, c[i]), w, cw, gradient + 3 * i);
            }
        });
    }

    Kernel kernel_;
    BlockPath path_ = best_block_path();
};

}  // namespace

void evaluate_together(std::span<const QualityMetric* const> metrics, const Mesh& mesh, std::span<const double> xyz,
                       ElementId first, ElementId last, std::span<double* const> quality) {
    std::vector<const BlockRater*> raters(metrics.size(), nullptr);
    if (mesh.kind() == ElementKind::Tetrahedron && last - first >= kTetBlock)
        for (std::size_t i = 0; i < metrics.size(); ++i)
            if (const auto* r = dynamic_cast<const BlockRater*>(metrics[i]); r && r->rates_blocks(mesh)) raters[i] = r;
    for (std::size_t i = 0; i < metrics.size(); ++i)
        if (!raters[i]) metrics[i]->evaluate(mesh, xyz, first, last, quality[i]);
    if (std::none_of(raters.begin(), raters.end(), [](const BlockRater* r) { return r != nullptr; })) return;
    for_each_block(mesh, xyz, first, last, [&](const TetBlock& x, ElementId b, int count) {
        for (std::size_t i = 0; i < metrics.size(); ++i)
            if (raters[i]) raters[i]->rate_block(x, b, count, quality[i] + (b - first));
    });
}

}  // namespace metrics

MetricScale MetricScale::of(const Mesh& mesh) { return of(mesh, mesh.coordinates()); }

MetricScale MetricScale::of(const Mesh& mesh, std::span<const double> coordinates) {
    MetricScale scale;
    scale.oriented_triangles = mesh.kind() == ElementKind::Tetrahedron || mesh.is_planar() || mesh.has_surface_normals();
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

double QualityMetric::element_value(const Mesh& mesh, std::span<const double> xyz, ElementId e,
                                   double* gradient) const {
    const metrics::ElementMaps maps(mesh);
    const VertexId* c = mesh.connectivity().data() + static_cast<std::size_t>(e) * mesh.corners();
    double x[12];
    const auto rate = [&]<int K>(std::integral_constant<int, K>) {
        metrics::gather<K>(c, xyz.data(), maps, e, x);
        if (!gradient) return value(mesh.kind(), x);
        const double q = value_and_gradient(mesh.kind(), x, gradient);
        if (const metrics::ElementMap m = maps.of(e)) metrics::unmap_gradient<K>(m, gradient);
        return q;
    };
    return mesh.kind() == ElementKind::Tetrahedron ? rate(std::integral_constant<int, 4>{})
                                                   : rate(std::integral_constant<int, 3>{});
}

void QualityMetric::element_values(const Mesh& mesh, std::span<const double> xyz, std::span<const ElementId> elements,
                                   double* quality, double* gradient) const {
    const std::size_t stride = 3 * static_cast<std::size_t>(mesh.corners());
    for (std::size_t i = 0; i < elements.size(); ++i)
        quality[i] = element_value(mesh, xyz, elements[i], gradient ? gradient + stride * i : nullptr);
}

void QualityMetric::evaluate_listed(const Mesh& mesh, std::span<const double> xyz, std::span<const ElementId> elements,
                                    double* quality) const {
    for (ElementId e : elements) evaluate(mesh, xyz, e, e + 1, quality + e);
}

void ElementMetric::evaluate(const Mesh& mesh, std::span<const double> xyz, ElementId first, ElementId last,
                             double* quality) const {
    const ElementKind kind = mesh.kind();
    metrics::evaluate_each(mesh, xyz, first, last, quality,
                           [&](auto, ElementId, const double* x, double*) { return value(kind, x); });
}

void ElementMetric::accumulate_gradient(const Mesh& mesh, std::span<const double> xyz, ElementId first,
                                        ElementId last, const GradientTarget& target) const {
    if (!has_gradient()) throw OptionError("metric '" + std::string(name()) + "' has no gradient");
    const ElementKind kind = mesh.kind();
    metrics::accumulate_gradient_each(mesh, xyz, first, last, target, [&](auto, ElementId, const double* x, double* g) {
        return value_and_gradient(kind, x, g);
    });
}

namespace {

// A kernel without options of its own, by its name.
template <class Kernel>
MetricInfo built_in(std::string help) {
    return {std::string(Kernel::name), std::move(help), [](const MetricOptions&) -> std::unique_ptr<QualityMetric> {
                return std::make_unique<metrics::KernelMetric<Kernel>>();
            }};
}

// The catalogue and its names, kept side by side: metric_names() hands out a reference.
struct Catalogue {
    std::vector<MetricInfo> metrics;
    std::vector<std::string> names;
};

Catalogue& catalogue() {
    using namespace metrics;
    static Catalogue c = [] {
        Catalogue out;
        out.metrics = {
            built_in<AspectRatio>("72 sqrt(3) V / L^(3/2) (triangles: 4 sqrt(3) A / L), L the sum of squared edge lengths; "
                                  "range [-1, 1], ideal 1 (regular simplex), <= 0 when inverted. The seed paper's metric."),
            built_in<MeanRatio>("sign(V) 12 (3|V|)^(2/3) / L (triangles: as aspect_ratio); range [-1, 1], ideal 1."),
            built_in<InverseCondition>(
                "3 det S / (|S|_F |adj S|_F), S the map from the regular element; range [-1, 1], ideal 1."),
            built_in<EdgeRatio>("sign(V) l_min / l_max; range [-1, 1], ideal 1; not smooth where two edges tie."),
            built_in<ScaledVolume>("V / V_ref, V_ref the mean absolute element volume (area) of the mesh; any value, no "
                                   "ideal (1: an element of average size)."),
            {std::string(UntangleHybrid::name),
             "w v + (1 - w) q, v = V / V_ref, q the aspect ratio, w = 1 / (1 + e^(hybrid_sharpness v)); > 0 exactly when "
             "valid, 1 for the regular element of reference size. The untangling metric.",
             [](const MetricOptions& o) -> std::unique_ptr<QualityMetric> {
                 return std::make_unique<KernelMetric<UntangleHybrid>>(UntangleHybrid{o.hybrid_sharpness});
             }},
            built_in<DihedralSine>("smallest sine of the dihedral angles (tetrahedra; corner angles for triangles) over the "
                                   "regular element's; an inverted element rates minus its largest sine; range [-1.06, 1], ideal "
                                   "1; small for angles near 0 and near 180 degrees alike. Its gradient is the smallest angle's."),
            built_in<ShapeSize>("m s(tau), m the mean ratio, tau = V / V_ref, s(tau) = 2|tau| / (1 + tau^2); range [-1, 1], "
                                "ideal 1 (the regular simplex of volume V_ref), <= 0 when inverted. Relative to the "
                                "element's target: docs/metrics.md."),
            built_in<ShapeSizeOrient>(
                "m (1 + o) / 2 s(tau), as shape_size with o = tr S / (sqrt(d) |S|_F), S the map from the regular "
                "element; range [-1, 1], ideal 1 (the regular simplex of volume V_ref in its target's orientation), <= 0 "
                "when inverted. Relative to the element's target: docs/metrics.md."),
            built_in<MinDihedralAngle>("smallest dihedral angle in degrees, negative if inverted; tetrahedra; range "
                                       "[-70.53, 70.53], ideal 70.53. No gradient: for assessments and smart Laplace."),
            built_in<MinCornerAngle>("smallest angle in degrees, negative if inverted; triangles; range [-60, 60], ideal "
                                     "60. No gradient: for assessments and smart Laplace."),
            MetricInfo{"scaled_jacobian",
                       "smallest corner scaled Jacobian det(e1, e2, e3) / (|e1| |e2| |e3|) (in 2D the sine of the corner "
                       "angle) over the ideal element's, taken on the element's own corners whatever its target; "
                       "range [-1, 1], ideal 1 (any box, any rectangle); negative if inverted. No gradient: for "
                       "assessments and the guard that keeps a mesh of cells from losing it (docs/targets.md).",
                       [](const MetricOptions&) { return make_scaled_jacobian(); }},
        };
        for (const auto& m : out.metrics) out.names.push_back(m.name);
        return out;
    }();
    return c;
}

}  // namespace

const std::vector<MetricInfo>& metric_catalogue() { return catalogue().metrics; }
const std::vector<std::string>& metric_names() { return catalogue().names; }

void register_metric(MetricInfo metric) {
    if (metric.name.empty()) throw OptionError("a registered metric needs a name");
    if (!metric.make) throw OptionError("metric '" + metric.name + "' has no factory");
    Catalogue& c = catalogue();
    if (std::find(c.names.begin(), c.names.end(), metric.name) != c.names.end())
        throw OptionError("a metric named '" + metric.name + "' is already in the catalogue");
    c.names.push_back(metric.name);
    c.metrics.push_back(std::move(metric));
}

std::unique_ptr<QualityMetric> make_metric(std::string_view name, const MetricOptions& options) {
    options.validate();
    for (const auto& m : metric_catalogue())
        if (m.name == name) {
            auto metric = m.make(options);
            if (!metric) throw OptionError("metric '" + m.name + "': its factory made nothing");
            return metric;
        }
    std::string known;
    for (const auto& n : metric_names()) known += (known.empty() ? "" : ", ") + n;
    throw OptionError("unknown quality metric '" + std::string(name) + "' (known: " + known + ")");
}

std::unique_ptr<QualityMetric> make_dihedral_sine_term() {
    return std::make_unique<metrics::KernelMetric<metrics::DihedralSineTerm>>();
}

std::unique_ptr<QualityMetric> make_untangle_energy(double epsilon, double theta) {
    if (!(epsilon > 0.0) || !std::isfinite(epsilon) || !(theta >= 0.0 && theta <= 1.0))
        throw OptionError("untangle_energy needs epsilon > 0 and theta in [0, 1]");
    return std::make_unique<metrics::KernelMetric<metrics::RegularizedEnergy>>(metrics::RegularizedEnergy{epsilon, theta});
}

}  // namespace paloverde
