#pragma once
// A quality metric rates one element: larger is better, `ideal_value()` (1 for the shape
// metrics) for the regular simplex, <= 0 for inverted elements of the orientation-aware ones.
// Solvers use the batch calls, one virtual call per block of elements; the one-element calls
// are for tests, local patches and users.
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "paloverde/core/types.hpp"

namespace paloverde {

class Mesh;

// What a metric needs to know about the mesh it rates: how triangles are oriented and the
// size that scale-free volumes are measured against.
struct MetricScale {
    // Triangles of a planar mesh are oriented by this normal; in a non-planar (surface) mesh
    // every triangle counts as positively oriented.
    bool oriented_triangles = true;
    Vec3 plane_normal{0.0, 0.0, 1.0};
    // Volume (area for triangles) that scale-free volumes are divided by: the mean absolute
    // element volume of the mesh.
    double reference_volume = 1.0;
    // Optional: a reference volume per element (indexed like the mesh's elements), for meshes
    // whose element sizes vary widely; used by scaled_volume, untangle_hybrid, shape_size and
    // shape_size_orient instead of reference_volume in the batch passes (evaluate,
    // evaluate_listed, accumulate_gradient; value() and element_value() take reference_volume).
    // Not owned: the array must outlive the metric's use of it.
    std::span<const double> element_reference_volume;

    static MetricScale of(const Mesh& mesh);
    static MetricScale of(const Mesh& mesh, std::span<const double> coordinates);
};

class QualityMetric {
public:
    virtual ~QualityMetric() = default;

    virtual std::string_view name() const = 0;
    virtual bool supports(ElementKind) const { return true; }
    // Whether the metric means something on a cell's corners rated through their maps (a shape
    // or size against the ideal cell's corner); angles in degrees do not.
    virtual bool supports_cells() const { return true; }
    virtual bool has_gradient() const { return true; }
    virtual double ideal_value() const { return 1.0; }
    // Whether the ideal value also needs the element's size: true for the metrics that rate an
    // element against its reference volume (shape_size, shape_size_orient), which fall below the
    // ideal when the regular simplex is scaled away from that volume.
    virtual bool rates_size() const { return false; }
    // False for the metrics that rate an element's orientation against its target
    // (shape_size_orient): a rotated element rates differently, and so does one whose corners are
    // permuted (which turns the regular simplex).
    virtual bool rotation_invariant() const { return true; }

    void set_scale(const MetricScale& scale) { scale_ = scale; }
    const MetricScale& scale() const { return scale_; }
    void prepare(const Mesh& mesh) { scale_ = MetricScale::of(mesh); }

    // One element; `corners` holds corner_count(kind) points of 3 doubles.
    virtual double value(ElementKind kind, const double* corners) const = 0;
    // Also writes d(value)/d(corner coordinates), 3 doubles per corner.
    virtual double value_and_gradient(ElementKind kind, const double* corners, double* gradient) const = 0;

    // Element e of `mesh` at the vertex positions `coordinates`, rated as the batch calls rate it
    // (a cell's corner through its corner map); with `gradient` (3 doubles per corner, in the
    // element's corner order) its gradient too. For local patches.
    virtual double element_value(const Mesh& mesh, std::span<const double> coordinates, ElementId e,
                         double* gradient = nullptr) const;

    // The listed elements' values and gradients, in list order: quality[i], and gradient[3 k i ..
    // 3 k (i + 1)) (k corners) for elements[i] (`gradient` null: the values alone); the same bits
    // as element_value(). For a vertex's star: the built-in metrics rate a star of tetrahedra in
    // blocks, not one call per element.
    virtual void element_values(const Mesh& mesh, std::span<const double> coordinates,
                                std::span<const ElementId> elements, double* quality, double* gradient) const;

    // Qualities of elements [first, last) of `mesh` at the vertex positions `coordinates` (the
    // mesh's own or trial positions of the same layout): quality[e - first].
    virtual void evaluate(const Mesh& mesh, std::span<const double> coordinates, ElementId first,
                          ElementId last, double* quality) const = 0;
    // Qualities of the listed elements, scattered by element id: quality[e] for each e in
    // `elements` (the same bits as evaluate()). For the few elements around the vertices a solver
    // just moved: the built-in metrics rate them in blocks too, not one call per element.
    virtual void evaluate_listed(const Mesh& mesh, std::span<const double> coordinates,
                                 std::span<const ElementId> elements, double* quality) const;
    // Where accumulate_gradient() adds its sums over elements [first, last):
    //   gradient[3(v - base) + c]   += weight[e - first] * d q_e / d x_v,c
    //   curvature[6(v - base) + ..] += curvature_weight[e - first] * g g^T,  g = d q_e / d x_v
    // (the 3x3 block stored as xx, xy, xz, yy, yz, zz; only when both pointers are set). A base
    // lets a buffer cover only the vertex range these elements touch; with `slot` as well, vertex v
    // adds at slot[v - base] instead of v - base, so that a buffer holds only the vertices they
    // touch (a focus's few elements spread over the whole range).
    struct GradientTarget {
        const double* weight = nullptr;
        double* gradient = nullptr;
        const double* curvature_weight = nullptr;
        double* curvature = nullptr;
        VertexId base = 0;
        const std::uint32_t* slot = nullptr;
    };
    virtual void accumulate_gradient(const Mesh& mesh, std::span<const double> coordinates, ElementId first,
                                     ElementId last, const GradientTarget& target) const = 0;

protected:
    MetricScale scale_;
};

// A metric written one element at a time, as a program's own metric is: give name(), value()
// and value_and_gradient() (or has_gradient() false, for assessments only); the batch calls go
// through them element by element. The built-in metrics are inlined kernels instead, with one
// virtual call per batch. The scale (set_scale) holds the mesh's reference volume.
class ElementMetric : public QualityMetric {
public:
    void evaluate(const Mesh& mesh, std::span<const double> coordinates, ElementId first, ElementId last,
                  double* quality) const final;
    void accumulate_gradient(const Mesh& mesh, std::span<const double> coordinates, ElementId first,
                             ElementId last, const GradientTarget& target) const final;
};

struct MetricOptions {
    // Steepness of the logistic blend in the untangling metric, per unit of scale-free volume.
    double hybrid_sharpness = 10.0;
    void validate() const;  // throws OptionError
};

// The metric catalogue: every metric a name can choose, in configs, on the command line, in
// assessments and in make_metric(). The built-in ones come first (aspect_ratio, mean_ratio,
// inverse_condition, edge_ratio, scaled_volume, untangle_hybrid, dihedral_sine, shape_size,
// shape_size_orient, min_dihedral_deg for tetrahedra, min_angle_deg for triangles), then those a
// program registered.
struct MetricInfo {
    std::string name;
    std::string help;  // formula, range, ideal value: shown by `paloverde run --describe`
    std::function<std::unique_ptr<QualityMetric>(const MetricOptions&)> make;
};
const std::vector<MetricInfo>& metric_catalogue();
const std::vector<std::string>& metric_names();
// Adds a program's own metric to the catalogue, before the runs that name it (not while a run is
// going on). Throws OptionError for an empty or taken name or a missing factory.
void register_metric(MetricInfo metric);
// The metric of that name; throws OptionError listing the known names.
std::unique_ptr<QualityMetric> make_metric(std::string_view name, const MetricOptions& options = {});
// The regularized untangling energy (docs/metrics.md), negated so that larger is better. Not in
// the catalogue above: it rates every element below zero, and its epsilon belongs to the
// untangling phase, which lowers it as the mesh untangles. theta weighs its volume term.
std::unique_ptr<QualityMetric> make_untangle_energy(double epsilon, double theta);
// One term of dihedral_sine: the sine of the dihedral angle at the edge of corners 0 and 1 (over
// the regular tetrahedron's, signed by the volume). Not in the catalogue: the global solver rates
// the six angles of a tetrahedron with it, each on a copy whose corners put that edge first.
std::unique_ptr<QualityMetric> make_dihedral_sine_term();

}  // namespace paloverde
