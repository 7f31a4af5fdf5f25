#pragma once
// The arrays a solver works on: the mesh renumbered for locality with the movable elements
// (those with a free vertex) first, and the machinery for passes over them that give the same
// result for any number of threads.
#include <cstdint>
#include <span>
#include <vector>

#include "paloverde/mesh/renumber.hpp"
#include "paloverde/mesh/simplex_mesh.hpp"
#include "paloverde/metrics/quality_metric.hpp"
#include "paloverde/parallel/reducer.hpp"

namespace paloverde::detail {

class Workspace {
public:
    Workspace(const SimplexMesh& mesh, bool renumber);

    const SimplexMesh& mesh() const { return mesh_; }
    ElementId movable_elements() const { return movable_; }
    std::span<const std::uint8_t> fixed() const { return mesh_.fixed(); }
    double reference_length() const { return reference_length_; }
    const MetricScale& scale() const { return scale_; }

    // Qualities of the movable elements at positions xyz.
    void evaluate(const QualityMetric& metric, std::span<const double> xyz, std::span<double> quality) const;
    // gradient = sum_e weight[e] * grad q_e over the movable elements, zero at fixed vertices;
    // with curvature weights also curvature = sum_e cw[e] * g g^T per vertex (6 doubles).
    // Elements are split into fixed lanes whose partial sums are added in lane order, so the
    // result does not depend on the number of threads.
    void gradient(const QualityMetric& metric, std::span<const double> xyz, std::span<const double> weight,
                  std::span<double> gradient, std::span<const double> curvature_weight = {},
                  std::span<double> curvature = {});

    // Coordinates in the caller's numbering.
    void copy_back(std::span<const double> xyz, SimplexMesh& original) const;

private:
    struct Lane {
        ElementId first, last;   // elements
        VertexId low, high;      // vertices they touch: [low, high]
        std::size_t offset;      // first vertex of the lane in the lane buffers
    };
    void build_lanes();

    SimplexMesh mesh_;
    std::vector<VertexId> old_vertex_;  // empty when not renumbered
    ElementId movable_ = 0;
    MetricScale scale_;
    double reference_length_ = 1.0;
    std::vector<Lane> lanes_;
    std::size_t lane_vertices_ = 0;       // total over the lanes
    std::vector<double> lane_gradient_;   // 3 per lane vertex
    std::vector<double> lane_curvature_;  // 6 per lane vertex, allocated on first use
};

}  // namespace paloverde::detail
