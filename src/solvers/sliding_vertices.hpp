#pragma once
// The workspace's vertices that slide on the input's boundary (boundary: slide), and how their
// moves stay on it: gradients and directions keep their tangential part, trial positions are
// projected back onto each vertex's patch or curve. The SlidingBoundary speaks the caller's ids.
#include <span>
#include <vector>

#include "sliding_boundary.hpp"
#include "workspace.hpp"

namespace paloverde::detail {

class SlidingVertices final : public VertexSlide {
public:
    SlidingVertices(const Workspace& work, const SlidingBoundary& boundary) : boundary_(boundary) {
        const VertexId n = work.mesh().num_vertices();
        caller_.assign(static_cast<std::size_t>(n), -1);
        for (VertexId v = 0; v < n; ++v)
            if (work.mesh().slides(v)) {
                caller_[v] = work.caller_vertex(v);
                vertices_.push_back(v);
            }
    }

    // Replaces each sliding vertex's part of `field` (3 doubles per vertex) by its tangential part.
    void tangent(std::span<double> field) const {
#pragma omp parallel for schedule(static) if (vertices_.size() > kParallelThreshold)
        for (std::size_t i = 0; i < vertices_.size(); ++i) {
            double* d = &field[3 * static_cast<std::size_t>(vertices_[i])];
            const Vec3 t = boundary_.tangent(caller_[vertices_[i]], {d[0], d[1], d[2]});
            for (int c = 0; c < 3; ++c) d[c] = t[c];
        }
    }
    // Every sliding vertex that `mesh` lets move, back onto its patch or curve.
    void project(const Mesh& mesh, std::span<double> xyz) const {
#pragma omp parallel for schedule(static) if (vertices_.size() > kParallelThreshold / 16)
        for (std::size_t i = 0; i < vertices_.size(); ++i)
            if (mesh.can_move(vertices_[i])) project(vertices_[i], xyz);
    }
    // Vertex v back onto its patch or curve, if it slides.
    void project(VertexId v, std::span<double> xyz) const {
        const VertexId id = caller_[v];
        if (id < 0) return;
        double* p = &xyz[3 * static_cast<std::size_t>(v)];
        const Vec3 q = boundary_.project(id, {p[0], p[1], p[2]});
        for (int c = 0; c < 3; ++c) p[c] = q[c];
    }

    // The same for one vertex of the workspace that slides, a move or a point apart.
    Vec3 tangent(VertexId v, const Vec3& d) const override { return boundary_.tangent(caller_[v], d); }
    Vec3 project(VertexId v, const Vec3& p) const override { return boundary_.project(caller_[v], p); }

private:
    const SlidingBoundary& boundary_;
    std::vector<VertexId> caller_;    // per workspace vertex: its id in the caller's mesh if it slides, else -1
    std::vector<VertexId> vertices_;  // the workspace's sliding vertices
};

}  // namespace paloverde::detail
