#pragma once
// An analytic surface that vertices stay on: a plane, a sphere or a cylinder (Mesquite's
// PlanarDomain, SphericalDomain and CylinderDomain). Where one is given (SurfaceOptions::domain),
// a surface mesh's vertices, and a volume mesh's sliding boundary vertices, are projected onto it
// instead of onto the input's triangles, which only approximate it: a coarse sphere's vertices then
// slide on the sphere, not on its facets, and the surface's normal at a point is the shape's own.
#include <string>

#include "paloverde/core/types.hpp"

namespace paloverde {

struct SurfaceDomain {
    enum class Shape { Mesh, Plane, Sphere, Cylinder };
    // Mesh: the input's own triangles (no analytic shape). The other fields are read for the
    // shape they belong to; their defaults are valid, so that a config may set them in any order.
    Shape shape = Shape::Mesh;
    Vec3 point{0.0, 0.0, 0.0};      // plane: a point on it; sphere: the centre; cylinder: a point on the axis
    Vec3 direction{0.0, 0.0, 1.0};  // plane: its normal; cylinder: its axis (any length)
    double radius = 1.0;            // sphere and cylinder

    bool analytic() const { return shape != Shape::Mesh; }
    // The point of the shape nearest to p. (A point on a sphere's centre or a cylinder's axis,
    // which has no nearest point, goes to a fixed one of them.)
    Vec3 nearest(const Vec3& p) const;
    // The shape's unit normal at its point nearest to p (outward for the sphere and cylinder;
    // `direction`'s side for the plane).
    Vec3 normal(const Vec3& p) const;
    // The distance from p to the shape.
    double distance(const Vec3& p) const;
    std::string name() const;   // "plane", "sphere", "cylinder" or "mesh"
    // "vertex 12 lies 0.1 off the sphere (surface.domain), more than 1e-6 of the bounding-box
    // diagonal": what a mesh that is not on the domain is refused with.
    std::string off_message(GlobalId vertex, double off) const;
    void validate() const;      // throws OptionError: finite fields, a direction, a positive radius
};

}  // namespace paloverde
