#pragma once
// Local untangling of one vertex (Freitag & Plassmann): move the vertex, its neighbours held
// still, to where the smallest signed volume of its elements is largest. Signed volume is linear
// in the vertex's position, so this is a small linear program (3 unknowns and the minimum; 2
// for planar triangles), solved here by a primal barrier method with Newton steps.
//
// The second way (VertexEnergy) is the per-vertex form of the global solver's regularized
// energy (Garanzha et al. 2021, docs/metrics.md): the vertex goes where the sum of its elements'
// energies is smallest, by a few Newton steps, which works where no single position makes every
// element valid.
#include <array>
#include <memory>
#include <span>
#include <vector>

#include "paloverde/mesh/mesh.hpp"
#include "paloverde/metrics/quality_metric.hpp"
#include "paloverde/parallel/halo.hpp"
#include "vertex_slide.hpp"

namespace paloverde::detail {

struct VertexUntangle {
    double before = 0.0;  // smallest scaled volume of the vertex's elements, before
    double after = 0.0;   // and at the new position (== before if not moved)
    bool moved = false;
};

// Moves vertex v in xyz only if afterwards every one of its elements has positive volume, so a
// valid element is never inverted. `scale` gives the plane of triangle meshes and the volume
// unit (scaled_volume). A vertex that slides (Mesh::slides, with `slide`) moves in its tangent
// plane or along its curve, and its new place is projected back onto them before it is judged.
VertexUntangle untangle_vertex(const Mesh& mesh, std::span<double> xyz, VertexId v, const MetricScale& scale,
                               const VertexSlide* slide = nullptr);

// A local, scale-free size for each of the first `count` elements: the mean over its corners of
// the mean absolute volume of each corner's elements (ghost corners take their owners' means).
// Flat neighbourhoods fall back on scale.reference_volume.
std::vector<double> local_reference_volumes(const Mesh& mesh, std::span<const double> xyz,
                                            const MetricScale& scale, const Halo& halo, ElementId count);

// The weight of the energy's volume term, in the global and the local solver (Garanzha et al. use
// a small one: shape dominates).
inline constexpr double kUntangleTheta = 1.0 / 128.0;
// The schedule's first epsilon, in units of the reference volume: large enough that inverted
// elements of any depth pull their neighbours along, small enough that a tangle does not
// collapse instead (global solver, of 1, 0.3, 0.1 and 0.01 on 39 perturbed shared meshes: 0.1
// and 0.3 untangled all with the best worst quality, 1 left elements barely valid, 0.01 took a
// third longer).
inline constexpr double kFirstUntangleEpsilon = 0.1;

// chi(v, eps) = (v + sqrt(eps^2 + v^2)) / 2, in the form that keeps its digits for v << 0.
double regularized_volume(double v, double epsilon);

// The next epsilon of the schedule of Garanzha et al.: the smallest element's chi shrinks by the
// factor 1 - sigma, sigma the relative decrease of the energy at this epsilon (at least 0.1).
double next_epsilon(double epsilon, double energy_start, double energy_end, double worst);

// Minimizes, for one free vertex with its neighbours held still, the sum of the regularized
// energy over its elements (element e measured against reference[e]). Only v's coordinates are
// written and only v's elements read: vertices of one color can run this at the same time.
class VertexEnergy {
public:
    VertexEnergy(const Mesh& mesh, std::span<const double> reference, const MetricScale& scale, double epsilon,
                 const VertexSlide* slide = nullptr);
    // Damped Newton steps (the 3x3 Hessian, 2x2 for planar triangles, by forward differences of
    // the analytic gradient) with a backtracking line search. A step is taken only if it lowers
    // the energy and leaves no more of v's elements inverted than before (decided exactly). A
    // vertex that slides steps in its tangent plane (or along its curve), each trial projected.
    bool improve(std::span<double> xyz, VertexId v);

private:
    double energy(std::span<const double> xyz, VertexId v, std::array<double, 3>* gradient);
    int inverted(std::span<const double> xyz, VertexId v) const;

    const Mesh& mesh_;
    std::span<const double> reference_;
    MetricScale scale_;
    std::unique_ptr<QualityMetric> metric_;
    const VertexSlide* slide_;
    std::vector<std::array<double, 3>> basis_;  // unit directions a free vertex may move in
    std::vector<std::array<double, 3>> slide_basis_;  // scratch: those of the sliding vertex visited
};

}  // namespace paloverde::detail
