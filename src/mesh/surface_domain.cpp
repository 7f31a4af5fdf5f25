#include "paloverde/mesh/surface_domain.hpp"

#include <cmath>
#include <cstdio>

#include "paloverde/core/error.hpp"

namespace paloverde {

namespace {

double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3 minus(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3 unit(const Vec3& a) {
    const double length = std::sqrt(dot(a, a));
    return {a[0] / length, a[1] / length, a[2] / length};
}
bool finite(const Vec3& a) { return std::isfinite(a[0]) && std::isfinite(a[1]) && std::isfinite(a[2]); }

// A unit vector perpendicular to the unit vector u: where a point on the axis goes.
Vec3 perpendicular(const Vec3& u) {
    const Vec3 axis = std::abs(u[0]) < 0.9 ? Vec3{1.0, 0.0, 0.0} : Vec3{0.0, 1.0, 0.0};
    const double along = dot(axis, u);
    return unit({axis[0] - along * u[0], axis[1] - along * u[1], axis[2] - along * u[2]});
}

}  // namespace

// The offset from the shape's nearest feature (the plane's point, the sphere's centre, the
// cylinder's axis) to p, perpendicular to it for the plane and cylinder; its unit is the normal.
Vec3 SurfaceDomain::normal(const Vec3& p) const {
    const Vec3 d = minus(p, point);
    const Vec3 u = unit(direction);
    switch (shape) {
        case Shape::Mesh: break;
        case Shape::Plane: return u;
        case Shape::Sphere: return dot(d, d) > 0.0 ? unit(d) : Vec3{1.0, 0.0, 0.0};
        case Shape::Cylinder: {
            const double along = dot(d, u);
            const Vec3 across{d[0] - along * u[0], d[1] - along * u[1], d[2] - along * u[2]};
            return dot(across, across) > 0.0 ? unit(across) : perpendicular(u);
        }
    }
    throw Error("SurfaceDomain::normal: the input mesh is no analytic shape");
}

Vec3 SurfaceDomain::nearest(const Vec3& p) const {
    const Vec3 n = normal(p);
    const double off = dot(minus(p, point), n);
    // The plane's nearest point drops p's offset along the normal; the sphere's and the
    // cylinder's move p along the normal to the radius.
    const double move = shape == Shape::Plane ? -off : radius - off;
    return {p[0] + move * n[0], p[1] + move * n[1], p[2] + move * n[2]};
}

double SurfaceDomain::distance(const Vec3& p) const {
    const double off = dot(minus(p, point), normal(p));
    return shape == Shape::Plane ? std::abs(off) : std::abs(off - radius);
}

std::string SurfaceDomain::name() const {
    switch (shape) {
        case Shape::Mesh: return "mesh";
        case Shape::Plane: return "plane";
        case Shape::Sphere: return "sphere";
        case Shape::Cylinder: return "cylinder";
    }
    return "mesh";
}

std::string SurfaceDomain::off_message(GlobalId vertex, double off) const {
    char number[32];
    std::snprintf(number, sizeof number, "%.3g", off);
    return "vertex " + std::to_string(vertex) + " lies " + number + " off the " + name() +
           " (surface.domain), more than 1e-6 of the bounding-box diagonal";
}

void SurfaceDomain::validate() const {
    if (!finite(point)) throw OptionError("point must be finite");
    if (!finite(direction) || !(dot(direction, direction) > 0.0) || !std::isfinite(dot(direction, direction)))
        throw OptionError("direction must be a finite vector of non-zero length");
    if (!(radius > 0.0) || !std::isfinite(radius))
        throw OptionError("radius must be positive and finite (got " + std::to_string(radius) + ")");
}

}  // namespace paloverde
