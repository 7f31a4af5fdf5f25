#pragma once
// Surface meshes made in code for the tests: a torus and a sphere of triangles, made poorer along
// themselves.
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "paloverde/mesh/mesh.hpp"

namespace paloverde::test {

// A number in [-1, 1] from the generator, the same on every standard library.
inline double jitter(std::mt19937& random) { return 2.0 * (random() / 4294967295.0) - 1.0; }

// A torus of nu x nv quads cut into triangles, facing outward; with `amount` > 0 each vertex is
// moved in the torus's parameters by up to that fraction of a cell, and so stays on the torus.
inline Mesh torus(int nu, int nv, double amount) {
    constexpr double R = 1.0, r = 0.4, pi = std::numbers::pi;
    std::mt19937 random(7);
    std::vector<double> xyz;
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            const double u = 2 * pi * (i + amount * jitter(random)) / nu, v = 2 * pi * (j + amount * jitter(random)) / nv;
            xyz.insert(xyz.end(), {(R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v)});
        }
    std::vector<VertexId> triangles;
    auto id = [&](int i, int j) { return static_cast<VertexId>((i % nu) * nv + j % nv); };
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            triangles.insert(triangles.end(), {id(i, j), id(i + 1, j), id(i + 1, j + 1)});
            triangles.insert(triangles.end(), {id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        }
    return Mesh(ElementKind::Triangle, std::move(xyz), std::move(triangles));
}

// A sphere of triangles about `centre` (rings of latitude, a vertex at each pole), facing outward;
// with `amount` > 0 every vertex but the poles moves in latitude and longitude by up to that
// fraction of a cell, so it stays on the sphere.
inline Mesh sphere(int around, int rings, double amount, const Vec3& centre = {0.0, 0.0, 0.0}, double radius = 1.0) {
    std::mt19937 random(11);
    std::vector<double> xyz;
    auto add = [&](double theta, double phi) {
        xyz.insert(xyz.end(), {centre[0] + radius * std::sin(theta) * std::cos(phi),
                               centre[1] + radius * std::sin(theta) * std::sin(phi), centre[2] + radius * std::cos(theta)});
    };
    add(0.0, 0.0);
    for (int j = 1; j < rings; ++j)
        for (int i = 0; i < around; ++i)
            add(std::numbers::pi * (j + amount * jitter(random)) / rings, 2 * std::numbers::pi * (i + amount * jitter(random)) / around);
    add(std::numbers::pi, 0.0);
    const auto south = static_cast<VertexId>(1 + (rings - 1) * around);
    auto id = [&](int j, int i) { return static_cast<VertexId>(1 + (j - 1) * around + i % around); };
    std::vector<VertexId> triangles;
    for (int i = 0; i < around; ++i) {
        triangles.insert(triangles.end(), {0, id(1, i), id(1, i + 1)});
        triangles.insert(triangles.end(), {south, id(rings - 1, i + 1), id(rings - 1, i)});
        for (int j = 1; j + 1 < rings; ++j) {
            triangles.insert(triangles.end(), {id(j, i), id(j + 1, i), id(j + 1, i + 1)});
            triangles.insert(triangles.end(), {id(j, i), id(j + 1, i + 1), id(j, i + 1)});
        }
    }
    return Mesh(ElementKind::Triangle, std::move(xyz), std::move(triangles));
}

}  // namespace paloverde::test
