#pragma once
// The abstract mesh interface, in Mesquite's spirit: any application mesh can be smoothed by
// exposing it through this interface. Access is by batches (spans of ids), so a solver copies a
// whole mesh in or out with a handful of virtual calls, never one per vertex.
#include <cstddef>
#include <span>

#include "paloverde/core/types.hpp"

namespace paloverde {

class MeshInterface {
public:
    virtual ~MeshInterface() = default;

    virtual ElementKind element_kind() const = 0;
    virtual std::size_t vertex_count() const = 0;
    virtual std::size_t element_count() const = 0;

    // Coordinates of the given vertices, 3 doubles each (z = 0 for planar 2D meshes).
    virtual void get_coordinates(std::span<const VertexId> vertices, std::span<double> xyz) const = 0;
    virtual void set_coordinates(std::span<const VertexId> vertices, std::span<const double> xyz) = 0;
    // Corner vertex ids of the given elements, corner_count(element_kind()) each.
    virtual void get_connectivity(std::span<const ElementId> elements,
                                  std::span<VertexId> corners) const = 0;
    // 1 where the vertex must not move.
    virtual void get_fixed(std::span<const VertexId> vertices, std::span<std::uint8_t> fixed) const = 0;
};

}  // namespace paloverde
