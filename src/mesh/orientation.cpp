#include "paloverde/mesh/orientation.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "core/exact_sums.hpp"
#include "core/prefetch.hpp"

namespace paloverde {

namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
// Unit roundoff of double precision.
constexpr double kRoundoff = 0x1p-53;
// Shewchuk's static error bounds of orient3d and orient2d evaluated from coordinate differences:
// the computed determinant is within this factor times the permanent (the determinant with every
// product made absolute) of the exact one.
constexpr double kTetBound = (7.0 + 56.0 * kRoundoff) * kRoundoff;
constexpr double kTriangleBound = (3.0 + 16.0 * kRoundoff) * kRoundoff;
// Terms that underflow lose their relative accuracy; at unit scale that takes elements some 300
// orders of magnitude smaller than the mesh, and this much per element covers them.
constexpr double kUnderflowSlack = 0x1p-1000;

Kernel::Point_3 point3(std::span<const double> xyz, VertexId v) {
    const std::size_t i = 3 * static_cast<std::size_t>(v);
    return {xyz[i], xyz[i + 1], xyz[i + 2]};
}

// A planar mesh's triangles keep their orientation when projected onto the coordinate plane most
// aligned with the mesh plane, flipped if the normal points down that axis.
int planar_triangle_orientation(const Mesh& mesh, std::span<const double> xyz, std::span<const VertexId> c) {
    const Vec3& n = mesh.plane_normal();
    int axis = 0;
    for (int i = 1; i < 3; ++i)
        if (std::abs(n[i]) > std::abs(n[axis])) axis = i;
    const int u = (axis + 1) % 3, w = (axis + 2) % 3;
    auto p = [&](VertexId v) {
        return Kernel::Point_2(xyz[3 * static_cast<std::size_t>(v) + u], xyz[3 * static_cast<std::size_t>(v) + w]);
    };
    const int sign = static_cast<int>(CGAL::orientation(p(c[0]), p(c[1]), p(c[2])));
    return n[axis] >= 0.0 ? sign : -sign;
}

// det(a, b, c) of the rows a = p1 - p0, b = p2 - p0, c = p3 - p0 (rounded differences), the bound
// on its error where no product underflows, and the largest coordinate of a, the row that
// multiplies the minors. Inlined into loops over blocks of elements, it runs several to an
// instruction.
struct TetDeterminant {
    double det, error, first_row;
};
inline TetDeterminant determinant_of(double a0, double a1, double a2, double b0, double b1, double b2, double c0,
                                     double c1, double c2) {
    const double m0 = b1 * c2, m1 = b2 * c1;
    const double m2 = b0 * c2, m3 = b2 * c0;
    const double m4 = b0 * c1, m5 = b1 * c0;
    const double det = a0 * (m0 - m1) - a1 * (m2 - m3) + a2 * (m4 - m5);
    const double permanent = std::abs(a0) * (std::abs(m0) + std::abs(m1)) + std::abs(a1) * (std::abs(m2) + std::abs(m3)) +
                             std::abs(a2) * (std::abs(m4) + std::abs(m5));
    return {det, kTetBound * permanent, std::max(std::max(std::abs(a0), std::abs(a1)), std::abs(a2))};
}
TetDeterminant tet_determinant(const double* p0, const double* p1, const double* p2, const double* p3) {
    return determinant_of(p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2], p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2],
                          p3[0] - p0[0], p3[1] - p0[1], p3[2] - p0[2]);
}
}  // namespace

int element_orientation(const Mesh& mesh, std::span<const double> xyz, ElementId element) {
    const auto c = mesh.element(element);
    if (mesh.kind() == ElementKind::Tetrahedron) {
        // A filter ahead of CGAL's predicate: a determinant farther from zero than its error bound
        // has the exact sign. Products that underflow lose less than kUnderflowSlack in all while
        // the first row is below 2^64 (below 2 at the unit scale solvers and assessments use);
        // near-flat elements, and coordinates whose products overflow (an infinite bound), get
        // CGAL's exact answer.
        auto at = [&](int i) { return xyz.data() + 3 * static_cast<std::size_t>(c[i]); };
        const TetDeterminant d = tet_determinant(at(0), at(1), at(2), at(3));
        const double margin = d.error + kUnderflowSlack;
        if (d.first_row <= 0x1p64) {
            if (d.det > margin) return 1;
            if (d.det < -margin) return -1;
        }
        return static_cast<int>(CGAL::orientation(point3(xyz, c[0]), point3(xyz, c[1]), point3(xyz, c[2]), point3(xyz, c[3])));
    }
    if (mesh.has_surface_normals()) {
        // The sign of n . (b - a) x (c - a), exactly for the rounded point a + n.
        const Vec3& n = mesh.surface_normals()[static_cast<std::size_t>(element)];
        const Kernel::Point_3 a = point3(xyz, c[0]);
        const Kernel::Point_3 above(a.x() + n[0], a.y() + n[1], a.z() + n[2]);
        return static_cast<int>(CGAL::orientation(a, point3(xyz, c[1]), point3(xyz, c[2]), above));
    }
    if (mesh.is_planar()) return planar_triangle_orientation(mesh, xyz, c);
    return CGAL::collinear(point3(xyz, c[0]), point3(xyz, c[1]), point3(xyz, c[2])) ? 0 : 1;
}

void element_orientations(const Mesh& mesh, std::span<const double> xyz, ElementId first, ElementId last,
                          std::int8_t* out) {
    if (mesh.kind() != ElementKind::Tetrahedron) {
        for (ElementId e = first; e < last; ++e) out[e - first] = static_cast<std::int8_t>(element_orientation(mesh, xyz, e));
        return;
    }
    // The filter of element_orientation() on a block of elements at once: the corners' differences
    // gathered into rows, then the determinants and their bounds in a loop the compiler runs
    // several elements to an instruction. Only where the filter cannot tell is the element asked
    // again, one at a time.
    constexpr int kBlock = 64;
    const VertexId* corners = mesh.connectivity().data();
    for (ElementId start = first; start < last; start += kBlock) {
        const int count = static_cast<int>(std::min<ElementId>(kBlock, last - start));
        alignas(64) double d[9][kBlock];
        for (int i = 0; i < count; ++i) {
            const VertexId* c = corners + 4 * static_cast<std::size_t>(start + i);
            const double* p0 = xyz.data() + 3 * static_cast<std::size_t>(c[0]);
            for (int r = 0; r < 3; ++r) {
                const double* p = xyz.data() + 3 * static_cast<std::size_t>(c[r + 1]);
                for (int j = 0; j < 3; ++j) d[3 * r + j][i] = p[j] - p0[j];
            }
        }
        alignas(64) double det[kBlock], margin[kBlock], first_row[kBlock];
        for (int i = 0; i < count; ++i) {
            const TetDeterminant t = determinant_of(d[0][i], d[1][i], d[2][i], d[3][i], d[4][i], d[5][i], d[6][i],
                                                    d[7][i], d[8][i]);
            det[i] = t.det;
            margin[i] = t.error + kUnderflowSlack;
            first_row[i] = t.first_row;
        }
        for (int i = 0; i < count; ++i) {
            const bool sure = first_row[i] <= 0x1p64 && (det[i] > margin[i] || det[i] < -margin[i]);
            out[start - first + i] = sure ? static_cast<std::int8_t>(det[i] > 0.0 ? 1 : -1)
                                          : static_cast<std::int8_t>(element_orientation(mesh, xyz, start + i));
        }
    }
}

OrientationCounts count_orientations(const Mesh& mesh, std::span<const double> xyz) {
    // A cell is as oriented as its worst corner.
    std::vector<std::int8_t> cell(static_cast<std::size_t>(mesh.num_cells()), 1);
    for (ElementId e = 0; e < mesh.num_elements(); ++e) {
        std::int8_t& o = cell[static_cast<std::size_t>(mesh.cell_of(e))];
        o = std::min(o, static_cast<std::int8_t>(element_orientation(mesh, xyz, e)));
    }
    OrientationCounts counts;
    for (std::int8_t o : cell) {
        counts.inverted += o < 0;
        counts.degenerate += o == 0;
    }
    return counts;
}

std::string_view to_string(OrientationMode mode) {
    switch (mode) {
        case OrientationMode::Auto: return "auto";
        case OrientationMode::AsIs: return "as_is";
        case OrientationMode::Flipped: return "flipped";
    }
    return "unknown";
}


SignedMeasure signed_measure(const Mesh& mesh, std::span<const double> xyz, int scale_exponent,
                             const Vec3& plane_normal, std::span<const std::uint8_t> counted) {
    const bool tets = mesh.kind() == ElementKind::Tetrahedron;
    int axis = 0;
    for (int i = 1; i < 3; ++i)
        if (std::abs(plane_normal[i]) > std::abs(plane_normal[axis])) axis = i;
    const int u = (axis + 1) % 3, w = (axis + 2) % 3;
    const double up = plane_normal[axis] >= 0.0 ? 1.0 : -1.0;
    const auto connectivity = mesh.connectivity();
    const std::size_t k = static_cast<std::size_t>(mesh.corners());
    // The coordinates at the given scale, scaled once rather than at every corner of every element.
    std::vector<double> scaled;
    if (scale_exponent != 0) {
        scaled.assign(xyz.begin(), xyz.end());
        scale_coordinates(scaled, scale_exponent);
        xyz = scaled;
    }
    auto at = [&](VertexId v, int c) { return xyz[3 * static_cast<std::size_t>(v) + c]; };
    const auto sums = detail::exact_sums<3>(static_cast<std::size_t>(mesh.num_elements()), [&](std::size_t e, auto& acc) {
        if (!counted.empty() && !counted[e]) return;
        const VertexId* c = connectivity.data() + e * k;
        if (e + detail::kPrefetchAhead < static_cast<std::size_t>(mesh.num_elements()))
            detail::prefetch_corners(c + detail::kPrefetchAhead * k, static_cast<int>(k), xyz.data());
        double det = 0.0, permanent = 0.0;
        if (tets) {
            auto corner = [&](int i) { return xyz.data() + 3 * static_cast<std::size_t>(c[i]); };
            const TetDeterminant d = tet_determinant(corner(0), corner(1), corner(2), corner(3));
            det = d.det;
            permanent = d.error;
        } else {
            const double a0 = at(c[1], u) - at(c[0], u), a1 = at(c[1], w) - at(c[0], w);
            const double b0 = at(c[2], u) - at(c[0], u), b1 = at(c[2], w) - at(c[0], w);
            const double left = a0 * b1, right = a1 * b0;
            det = up * (left - right);
            permanent = kTriangleBound * (std::abs(left) + std::abs(right));
        }
        acc[0].add(det);
        acc[1].add(std::abs(det));
        acc[2].add(permanent + kUnderflowSlack);
    });
    return {sums[0], sums[1], sums[2]};
}

OrientationDecision decide_orientation(OrientationMode mode, bool oriented, const SignedMeasure& measure) {
    OrientationDecision d;
    d.mode = mode;
    d.oriented = oriented;
    const double total = measure.total.value(), magnitude = measure.magnitude.value();
    // The rounded sums are within an ulp: a margin far above that keeps the comparison safe.
    const double rounding = measure.rounding.value() * (1.0 + 1e-9);
    if (oriented) {
        d.sign = total > rounding ? 1 : total < -rounding ? -1 : 0;
        d.share = magnitude > 0.0 ? total / magnitude : 0.0;
    }
    d.flipped = mode == OrientationMode::Flipped || (mode == OrientationMode::Auto && d.sign < 0);
    return d;
}

OrientationDecision orient(Mesh& mesh, OrientationMode mode) {
    const bool oriented = mesh.kind() == ElementKind::Tetrahedron || mesh.is_planar();
    SignedMeasure measure;
    if (oriented) measure = signed_measure(mesh, mesh.coordinates(), unit_scale_exponent(mesh.coordinates()), mesh.plane_normal());
    const OrientationDecision d = decide_orientation(mode, oriented, measure);
    if (d.flipped) {
        mesh.flip_elements();
        mesh.set_elements_flipped(!mesh.elements_flipped());
    }
    return d;
}

std::string OrientationDecision::describe(ElementKind kind) const {
    const bool tets = kind == ElementKind::Tetrahedron;
    std::ostringstream out;
    out << "orientation " << to_string(mode) << ": ";
    if (flipped)
        out << "elements flipped (corners " << (tets ? "2 and 3" : "1 and 2")
            << " swapped; outputs get the file's order back)";
    else
        out << "elements as in the file";
    if (!oriented) return out.str() + "; triangles not in one plane have no file-wide orientation";
    out << "; total signed " << (tets ? "volume " : "area about the plane normal ");
    if (sign == 0) return out.str() + "zero within rounding: the file's convention cannot be told";
    out << std::showpos << std::fixed << std::setprecision(1) << 100.0 * share << std::noshowpos << "% of the absolute "
        << (tets ? "volume" : "area");
    if (sign < 0) out << " (the mirror convention)";
    return out.str();
}

}  // namespace paloverde
