#include "workspace.hpp"

#include "core/blocked_sum.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace paloverde::detail {

namespace {
constexpr ElementId kEvaluateChunk = 2048;

std::vector<std::uint8_t> frozen_elements(const SimplexMesh& mesh) {
    std::vector<std::uint8_t> frozen(static_cast<std::size_t>(mesh.num_elements()), 1);
    for (ElementId e = 0; e < mesh.num_elements(); ++e)
        for (VertexId v : mesh.element(e))
            if (!mesh.fixed()[v]) frozen[e] = 0;
    return frozen;
}
}  // namespace

Workspace::Workspace(const SimplexMesh& mesh, bool renumber) {
    const std::vector<std::uint8_t> frozen = frozen_elements(mesh);
    if (renumber) {
        Renumbering order = locality_order(mesh, frozen);
        mesh_ = renumbered(mesh, order);
        old_vertex_ = std::move(order.old_vertex);
    } else {
        // Still put the frozen elements last, keeping the vertex numbering.
        Renumbering order;
        order.old_vertex.resize(static_cast<std::size_t>(mesh.num_vertices()));
        for (VertexId v = 0; v < mesh.num_vertices(); ++v) order.old_vertex[v] = v;
        for (int group = 0; group < 2; ++group)
            for (ElementId e = 0; e < mesh.num_elements(); ++e)
                if (frozen[e] == group) order.old_element.push_back(e);
        mesh_ = renumbered(mesh, order);
    }
    movable_ = static_cast<ElementId>(std::count(frozen.begin(), frozen.end(), 0));
    scale_ = MetricScale::of(mesh_);
    // The edge of the regular simplex of the reference volume.
    reference_length_ = mesh_.kind() == ElementKind::Tetrahedron
                            ? std::cbrt(6.0 * std::numbers::sqrt2 * scale_.reference_volume)
                            : std::sqrt(4.0 * scale_.reference_volume / std::numbers::sqrt3);
    build_lanes();
}

void Workspace::build_lanes() {
    // Fixed lanes (not one per thread) keep the gradient's summation order independent of the
    // thread count. In locality order a lane touches a narrow band of vertices, so the lane
    // buffers together are not much larger than one gradient; halve the lane count until so.
    for (ElementId count = 64;; count /= 2) {
        lanes_.clear();
        std::size_t total = 0;
        const ElementId per_lane = std::max<ElementId>(1, (movable_ + count - 1) / count);
        for (ElementId first = 0; first < movable_; first += per_lane) {
            const ElementId last = std::min(movable_, first + per_lane);
            VertexId low = mesh_.num_vertices(), high = 0;
            for (VertexId v : mesh_.connectivity().subspan(static_cast<std::size_t>(first) * mesh_.corners(),
                                                           static_cast<std::size_t>(last - first) * mesh_.corners())) {
                low = std::min(low, v);
                high = std::max(high, v);
            }
            lanes_.push_back({first, last, low, high, total});
            total += static_cast<std::size_t>(high - low + 1);
        }
        if (count == 1 || total <= 2 * static_cast<std::size_t>(mesh_.num_vertices())) {
            lane_vertices_ = total;
            lane_gradient_.assign(3 * total, 0.0);
            return;
        }
    }
}

void Workspace::evaluate(const QualityMetric& metric, std::span<const double> xyz, std::span<double> quality) const {
    const ElementId chunks = (movable_ + kEvaluateChunk - 1) / kEvaluateChunk;
#pragma omp parallel for schedule(static) if (static_cast<std::size_t>(movable_) > kParallelThreshold)
    for (ElementId c = 0; c < chunks; ++c) {
        const ElementId first = c * kEvaluateChunk, last = std::min(movable_, first + kEvaluateChunk);
        metric.evaluate(mesh_, xyz, first, last, quality.data() + first);
    }
}

void Workspace::gradient(const QualityMetric& metric, std::span<const double> xyz, std::span<const double> weight,
                         std::span<double> gradient, std::span<const double> curvature_weight,
                         std::span<double> curvature) {
    const bool with_curvature = !curvature.empty();
    if (with_curvature && lane_curvature_.empty()) lane_curvature_.assign(6 * lane_vertices_, 0.0);
    const auto lanes = static_cast<std::ptrdiff_t>(lanes_.size());
#pragma omp parallel for schedule(dynamic, 1) if (static_cast<std::size_t>(movable_) > kParallelThreshold)
    for (std::ptrdiff_t l = 0; l < lanes; ++l) {
        const Lane& lane = lanes_[static_cast<std::size_t>(l)];
        const auto count = static_cast<std::size_t>(lane.high - lane.low + 1);
        QualityMetric::GradientTarget target;
        target.weight = weight.data() + lane.first;
        target.gradient = lane_gradient_.data() + 3 * lane.offset;
        std::fill(target.gradient, target.gradient + 3 * count, 0.0);
        if (with_curvature) {
            target.curvature_weight = curvature_weight.data() + lane.first;
            target.curvature = lane_curvature_.data() + 6 * lane.offset;
            std::fill(target.curvature, target.curvature + 6 * count, 0.0);
        }
        target.base = lane.low;
        metric.accumulate_gradient(mesh_, xyz, lane.first, lane.last, target);
    }
    // Each vertex sums the lanes that touch it in lane order; vertex blocks run in parallel.
    const VertexId n = mesh_.num_vertices();
    const VertexId block = 4096;
    const auto fixed = mesh_.fixed();
    auto gather = [&](std::span<double> out, const std::vector<double>& buffer, int width, VertexId low, VertexId high) {
        std::fill(out.begin() + width * static_cast<std::size_t>(low), out.begin() + width * (static_cast<std::size_t>(high) + 1), 0.0);
        for (const Lane& lane : lanes_) {
            const VertexId from = std::max(low, lane.low), to = std::min(high, lane.high);
            const double* source = buffer.data() + width * lane.offset;
            for (VertexId v = from; v <= to; ++v)
                for (int c = 0; c < width; ++c)
                    out[width * static_cast<std::size_t>(v) + c] += source[width * static_cast<std::size_t>(v - lane.low) + c];
        }
        for (VertexId v = low; v <= high; ++v)
            if (fixed[v])
                for (int c = 0; c < width; ++c) out[width * static_cast<std::size_t>(v) + c] = 0.0;
    };
#pragma omp parallel for schedule(static) if (static_cast<std::size_t>(movable_) > kParallelThreshold)
    for (VertexId b = 0; b < (n + block - 1) / block; ++b) {
        const VertexId low = b * block, high = std::min(n, low + block) - 1;
        gather(gradient, lane_gradient_, 3, low, high);
        if (with_curvature) gather(curvature, lane_curvature_, 6, low, high);
    }
}

void Workspace::copy_back(std::span<const double> xyz, SimplexMesh& original) const {
    auto out = original.coordinates();
    for (VertexId v = 0; v < mesh_.num_vertices(); ++v) {
        const VertexId old = old_vertex_.empty() ? v : old_vertex_[v];
        for (int c = 0; c < 3; ++c) out[3 * static_cast<std::size_t>(old) + c] = xyz[3 * static_cast<std::size_t>(v) + c];
    }
}

}  // namespace paloverde::detail
