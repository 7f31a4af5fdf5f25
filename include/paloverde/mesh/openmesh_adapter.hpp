#pragma once
// Exposes an OpenMesh triangle mesh through paloverde::MeshInterface, so an OpenMesh application can
// assess and smooth its mesh in place. Vertices on the boundary, or locked in OpenMesh's status
// flags, are fixed. Works with any OpenMesh TriMesh whose points have 2 or 3 coordinates.
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <span>
#include <stdexcept>

#include "paloverde/mesh/mesh_interface.hpp"

namespace paloverde {

// OpenMesh's default point type is single precision; smoothing wants doubles.
struct OpenMeshDoubleTraits : public OpenMesh::DefaultTraits {
    using Point = OpenMesh::Vec3d;
    using Normal = OpenMesh::Vec3d;
    VertexAttributes(OpenMesh::Attributes::Status);
    FaceAttributes(OpenMesh::Attributes::Status);
    EdgeAttributes(OpenMesh::Attributes::Status);
};
using OpenMeshTriangles = OpenMesh::TriMesh_ArrayKernelT<OpenMeshDoubleTraits>;

template <class TriMesh>
class OpenMeshAdapter final : public MeshInterface {
public:
    // The adapter refers to `mesh`; it must outlive the adapter. Deleted elements are not
    // supported: call garbage_collection() first.
    explicit OpenMeshAdapter(TriMesh& mesh) : mesh_(mesh) {}

    ElementKind element_kind() const override { return ElementKind::Triangle; }
    std::size_t vertex_count() const override { return mesh_.n_vertices(); }
    std::size_t element_count() const override { return mesh_.n_faces(); }

    void get_coordinates(std::span<const VertexId> vertices, std::span<double> xyz) const override {
        for (std::size_t i = 0; i < vertices.size(); ++i) {
            const auto& p = mesh_.point(vertex(vertices[i]));
            for (int c = 0; c < 3; ++c) xyz[3 * i + c] = c < static_cast<int>(p.size()) ? static_cast<double>(p[c]) : 0.0;
        }
    }
    void set_coordinates(std::span<const VertexId> vertices, std::span<const double> xyz) override {
        for (std::size_t i = 0; i < vertices.size(); ++i) {
            auto& p = mesh_.point(vertex(vertices[i]));
            for (int c = 0; c < static_cast<int>(p.size()) && c < 3; ++c)
                p[c] = static_cast<typename TriMesh::Scalar>(xyz[3 * i + c]);
        }
    }
    void get_connectivity(std::span<const ElementId> elements, std::span<VertexId> corners) const override {
        for (std::size_t i = 0; i < elements.size(); ++i) {
            int c = 0;
            for (auto v : mesh_.fv_range(typename TriMesh::FaceHandle(elements[i])))
                corners[3 * i + c++] = static_cast<VertexId>(v.idx());
        }
    }
    void get_fixed(std::span<const VertexId> vertices, std::span<std::uint8_t> fixed) const override {
        for (std::size_t i = 0; i < vertices.size(); ++i) {
            const auto v = vertex(vertices[i]);
            const bool locked = mesh_.has_vertex_status() && mesh_.status(v).locked();
            fixed[i] = mesh_.is_boundary(v) || locked;
        }
    }

private:
    typename TriMesh::VertexHandle vertex(VertexId v) const {
        if (v < 0 || static_cast<std::size_t>(v) >= mesh_.n_vertices())
            throw std::out_of_range("OpenMeshAdapter: vertex id out of range");
        return typename TriMesh::VertexHandle(v);
    }
    TriMesh& mesh_;
};

}  // namespace paloverde
