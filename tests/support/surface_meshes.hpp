#pragma once
// Surface meshes made in code for the tests: a torus and a sphere of triangles and a graded
// cylinder of quadrilaterals, made poorer along themselves, and tangled tori (vertices slid along
// it past their neighbours).
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "paloverde/mesh/cell_types.hpp"
#include "paloverde/mesh/mesh.hpp"

namespace paloverde::test {

// A number in [-1, 1] from the generator, the same on every standard library.
inline double jitter(std::mt19937& random) { return 2.0 * (random() / 4294967295.0) - 1.0; }

// The torus's radii: of the centre circle and of the tube.
inline constexpr double kTorusR = 1.0, kTorusTube = 0.4;

// The torus's point at cell coordinates (i, j) of an nu x nv grid.
inline std::array<double, 3> torus_point(double i, double j, int nu, int nv) {
    constexpr double R = kTorusR, r = kTorusTube, pi = std::numbers::pi;
    const double u = 2 * pi * i / nu, v = 2 * pi * j / nv;
    return {(R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v)};
}

// The torus's outward normal (not of unit length) at p, a point on it or near it.
inline std::array<double, 3> torus_normal(const std::array<double, 3>& p) {
    const double around = std::hypot(p[0], p[1]);
    return {p[0] - kTorusR * p[0] / around, p[1] - kTorusR * p[1] / around, p[2]};
}

// Cells (i, j) of an nu x nv torus grid as quadrilaterals, counterclockwise seen from outside.
inline std::vector<VertexId> torus_quads(int nu, int nv) {
    std::vector<VertexId> quads;
    auto id = [&](int i, int j) { return static_cast<VertexId>((i % nu) * nv + j % nv); };
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) quads.insert(quads.end(), {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
    return quads;
}

// A torus of nu x nv quads cut into triangles, facing outward; with `amount` > 0 each vertex is
// moved in the torus's parameters by up to that fraction of a cell, and so stays on the torus.
inline Mesh torus(int nu, int nv, double amount) {
    std::mt19937 random(7);
    std::vector<double> xyz;
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            const double di = amount * jitter(random), dj = amount * jitter(random);
            const auto p = torus_point(i + di, j + dj, nu, nv);
            xyz.insert(xyz.end(), p.begin(), p.end());
        }
    std::vector<VertexId> triangles;
    const std::vector<VertexId> quads = torus_quads(nu, nv);
    for (std::size_t q = 0; q < quads.size(); q += 4)
        triangles.insert(triangles.end(), {quads[q], quads[q + 1], quads[q + 2], quads[q], quads[q + 2], quads[q + 3]});
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

// Vertices (i, j) of the nu x nv torus grid that the tangled tori slide: apart, so that each
// tangle is its own.
inline std::vector<std::array<int, 2>> torus_slides(int nu, int nv) {
    return {{nu / 8, nv / 5}, {3 * nu / 8, nv / 2}, {5 * nu / 8, 4 * nv / 5}, {7 * nu / 8, nv / 3}};
}

// The regular torus's points with each vertex of torus_slides() moved along the torus by 1.5
// cells in i, past its neighbour (i + 1, j): a tangle of the input whose points are all on the
// torus. As triangles (torus()'s cut), two triangles at each such vertex turn over; as
// quadrilaterals (`quads`), the two cells at the edge it crossed.
inline Mesh tangled_torus(int nu, int nv, bool quads = false) {
    std::vector<double> xyz;
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            const auto slid = torus_slides(nu, nv);
            const bool moves = std::find(slid.begin(), slid.end(), std::array<int, 2>{i, j}) != slid.end();
            const auto p = torus_point(i + (moves ? 1.5 : 0.0), j, nu, nv);
            xyz.insert(xyz.end(), p.begin(), p.end());
        }
    if (!quads) {
        Mesh mesh = torus(nu, nv, 0.0);
        return Mesh(ElementKind::Triangle, std::move(xyz), {mesh.connectivity().begin(), mesh.connectivity().end()});
    }
    std::vector<VertexId> cells = torus_quads(nu, nv);
    std::vector<CellType> types(cells.size() / 4, CellType::Quadrilateral);
    return Mesh::from_cells(std::move(xyz), types, std::move(cells));
}

// Elements of a mesh on the torus (its cells' corner elements too) whose normal faces into the
// torus: turned over.
inline int turned_over_on_torus(const Mesh& mesh) {
    int count = 0;
    for (ElementId e = 0; e < mesh.num_elements(); ++e) {
        const auto c = mesh.element(e);
        const auto a = mesh.point(c[0]), b = mesh.point(c[1]), d = mesh.point(c[2]);
        const std::array<double, 3> u{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w{d[0] - a[0], d[1] - a[1], d[2] - a[2]};
        const std::array<double, 3> n{u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
        const auto out = torus_normal({(a[0] + b[0] + d[0]) / 3, (a[1] + b[1] + d[1]) / 3, (a[2] + b[2] + d[2]) / 3});
        count += n[0] * out[0] + n[1] * out[1] + n[2] * out[2] <= 0.0;
    }
    return count;
}

}  // namespace paloverde::test
