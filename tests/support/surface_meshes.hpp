#pragma once
// Surface meshes made in code for the tests: a torus and a sphere of triangles and a graded
// cylinder of quadrilaterals, made poorer along themselves.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "paloverde/mesh/cell_types.hpp"
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

// The z of the rings of a cylinder's rows: `along` rows from z = 0, the first `first` high and
// each next `growth` times the last.
inline std::vector<double> graded_rings(int along, double first, double growth) {
    std::vector<double> z{0.0};
    for (int j = 0; j < along; ++j) z.push_back(z.back() + first * std::pow(growth, j));
    return z;
}

// An open cylinder of radius 1 of quadrilaterals facing outward, `around` of them in each of the
// rows of graded_rings(along, first, growth); with `amount` > 0 each vertex off the two rims is
// moved along the cylinder, around it and along its axis, by up to that fraction of its shortest edge.
inline Mesh graded_cylinder(int around, int along, double first, double growth, double amount) {
    constexpr double pi = std::numbers::pi;
    std::mt19937 random(11);
    const std::vector<double> z = graded_rings(along, first, growth);
    std::vector<double> xyz;
    for (int j = 0; j <= along; ++j)
        for (int i = 0; i < around; ++i) {
            double u = i, h = z[j];
            if (j > 0 && j < along) {
                const double width = 2 * pi / around, shortest = std::min({width, z[j] - z[j - 1], z[j + 1] - z[j]});
                u += amount * jitter(random) * shortest / width;
                h += amount * jitter(random) * shortest;
            }
            xyz.insert(xyz.end(), {std::cos(2 * pi * u / around), std::sin(2 * pi * u / around), h});
        }
    std::vector<VertexId> quads;
    auto id = [&](int i, int j) { return static_cast<VertexId>(j * around + i % around); };
    for (int j = 0; j < along; ++j)
        for (int i = 0; i < around; ++i) quads.insert(quads.end(), {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
    const std::vector<CellType> types(static_cast<std::size_t>(around * along), CellType::Quadrilateral);
    return Mesh::from_cells(std::move(xyz), types, std::move(quads));
}

}  // namespace paloverde::test
