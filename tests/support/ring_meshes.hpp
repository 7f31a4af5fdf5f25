#pragma once
// The morphing tests' mesh: a planar ring of triangles between two circles, its boundary fixed,
// whose inner circle moves away from the reference coordinates (solvers/boundary_motion.hpp).
#include <cmath>
#include <numbers>
#include <vector>

#include "paloverde/mesh/mesh.hpp"

namespace paloverde::test {

constexpr int kSectors = 24, kRings = 6;
constexpr double kInner = 0.5, kOuter = 1.5;

// A planar ring of triangles between two circles, the boundary fixed.
inline Mesh ring() {
    std::vector<double> xyz;
    for (int r = 0; r <= kRings; ++r)
        for (int s = 0; s < kSectors; ++s) {
            const double radius = kInner + (kOuter - kInner) * r / kRings;
            const double angle = 2.0 * std::numbers::pi * s / kSectors;
            xyz.insert(xyz.end(), {radius * std::cos(angle), radius * std::sin(angle), 0.0});
        }
    auto id = [](int r, int s) { return static_cast<VertexId>(r * kSectors + (s % kSectors)); };
    std::vector<VertexId> triangles;
    for (int r = 0; r < kRings; ++r)
        for (int s = 0; s < kSectors; ++s)
            triangles.insert(triangles.end(), {id(r, s), id(r, s + 1), id(r + 1, s + 1), id(r, s), id(r + 1, s + 1), id(r + 1, s)});
    Mesh mesh(ElementKind::Triangle, std::move(xyz), std::move(triangles));
    mesh.fix_boundary();
    return mesh;
}

// The ring with its reference coordinates, the inner circle's vertices moved by `move`.
template <class Move>
Mesh moved_ring(Move move) {
    Mesh mesh = ring();
    mesh.set_reference_coordinates({mesh.coordinates().begin(), mesh.coordinates().end()});
    auto xyz = mesh.coordinates();
    for (int s = 0; s < kSectors; ++s) move(&xyz[3 * static_cast<std::size_t>(s)]);
    return mesh;
}

inline Mesh turned_ring(double degrees) {
    const double a = degrees * std::numbers::pi / 180.0;
    return moved_ring([a](double* p) {
        const double x = p[0], y = p[1];
        p[0] = std::cos(a) * x - std::sin(a) * y;
        p[1] = std::sin(a) * x + std::cos(a) * y;
    });
}

}  // namespace paloverde::test
