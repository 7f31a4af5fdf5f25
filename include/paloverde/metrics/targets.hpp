#pragma once
// Targets: what each element of a mesh should look like (Knupp's target-matrix paradigm). At each
// corner (a tetrahedron or a triangle is its own corner; a cell has one per frame, cell_types.hpp)
// the target Jacobian W factors as W = lambda V Q D: size lambda (det W = lambda^d), orientation
// V (a rotation), skew Q (the angles between the corner's edges, det Q = 1) and aspect D (the
// edges' relative lengths, diagonal, det D = 1). Each factor comes from one source: the ideal
// element's corner, the input mesh's own corner (kept), a reference mesh's corner, or (size) the
// edge lengths a size field asks for at the element's vertices. Quality is
// then measured on T = A W^-1 (A the corner's edge matrix): an element equal to its target rates
// 1 in every shape metric, whatever its size or stretch; size metrics (shape_size) compare det T
// with 1, orientation metrics (shape_size_orient) T with a multiple of the identity.
//
// The factors come from a QR factorization of a corner's edge matrix, A = V R (R upper triangular
// with a positive diagonal): lambda = det(R)^(1/d), D from R's column lengths, Q from R with its
// columns normalized. An input or reference corner that is inverted gives its size, aspect and
// skew (those of its mirror image) but not its orientation, which is then ideal; a degenerate
// one gives nothing (its target is the ideal element at the mesh's mean size). A surface mesh's
// element is read in its own input plane (set_targets).
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "paloverde/core/exact_sum.hpp"
#include "paloverde/mesh/mesh.hpp"

namespace paloverde {

// Field: the size from the mesh's target edge lengths (Mesh::target_edge_lengths, a size field of
// the file); for the size factor only. Metric: size, aspect and orientation together from the
// mesh's target metrics (Mesh::target_metrics, a metric field of the file): each element is the
// ideal element in the mean of its vertices' metrics (a simplex rated in that metric, a cell's
// corner against its ideal corner carried into it), turned within it as the element is.
enum class TargetSource { Ideal, Input, Reference, Field, Metric };

struct TargetOptions {
    TargetSource size = TargetSource::Ideal;
    TargetSource orientation = TargetSource::Ideal;
    TargetSource aspect = TargetSource::Ideal;
    TargetSource skew = TargetSource::Ideal;

    // The factors named in `list` ("size,aspect"; any of size, orientation, aspect, skew, or
    // "all"; empty: none) from `source`, the rest ideal. Throws OptionError naming a word it does
    // not know and the known ones.
    static TargetOptions from(std::string_view list, TargetSource source = TargetSource::Input);
    // Some factor is not ideal: the mesh needs targets.
    bool any() const;
    bool uses(TargetSource source) const;
    // The factors from `source`, as from() reads them ("size,aspect"; "" for none).
    std::string list(TargetSource source) const;
    // The metric that rates what these targets ask for: shape_size_orient where orientation is
    // not ideal (shape_size where it comes with the size from a metric field, which turns each
    // target as its element is), shape_size where size is not ideal, else `shape_metric`.
    std::string metric(std::string_view shape_metric) const;
};

// The ideal size is the ideal element's, scaled so that the elements' mean |det A| / det W_ideal
// is 1: this sums |det A| / det W_ideal over the elements with counted[e] (all when empty), for
// a distributed mesh to add over its parts before it divides by the number of elements.
ExactSum ideal_size_sum(const Mesh& mesh, std::span<const std::uint8_t> counted = {});
// Each overload with `surface` is told whether the mesh is a surface mesh (is_surface_mesh), which a
// part of one cannot tell when its own triangles happen to lie in one plane; the others ask the mesh.
ExactSum ideal_size_sum(const Mesh& mesh, std::span<const std::uint8_t> counted, bool surface);

// A simplex (tetrahedron, triangle) is a single corner, and its aspect alone cannot tell the
// stretch a mesh means (a boundary layer's) from the distortion to remove, nor from the stretch
// its cut pattern gives it (a box cut into tetrahedra). So where the aspect is kept (from the input
// or a reference) and the skew made ideal, a simplex is rated in its neighbourhood's metric
// against the regular simplex: each simplex's metric M (the symmetric matrix in which it is the
// regular simplex, at determinant 1) is averaged over each vertex's simplices, then over the
// element's vertices, and the element's corners are carried by M^1/2 (Mesh::target_metric_roots)
// before they are rated; with orientation kept, the regular simplex is turned in M as the source
// corner is. The means are arithmetic, so a linear map of the mesh maps its metrics alike. Cells
// keep their corners' own factors.
bool stretches_from_neighbourhood(const TargetOptions& options);
// Per vertex, Mesh::kMetricValues values (the mean metric, in Mesh::target_metrics' order)
// over the vertex's simplices at the aspect's source, summed exactly (the same whatever the order
// of the vertex's elements). Empty unless stretches_from_neighbourhood(options). A part's values
// at its ghost vertices miss elements it does not hold: replace them with their owners'.
std::vector<double> vertex_metrics(const Mesh& mesh, const TargetOptions& options, const Mesh* reference);
std::vector<double> vertex_metrics(const Mesh& mesh, const TargetOptions& options, const Mesh* reference, bool surface);

// Sets every element's target on `mesh` (Mesh::set_targets) from its coordinates now (Input) and
// from `reference`'s (Reference): the same element kind, cells and connectivity, vertex for
// vertex. `ideal_scale` is the mean of ideal_size_sum()'s terms over the whole mesh (the
// overload without it computes it from `mesh`). With no factor other than ideal it clears the
// targets. Throws MeshError naming the first difference of a reference that does not match,
// OptionError when a factor asks for a reference and none is given, or for field edge lengths or
// metrics the mesh does not carry, or for a factor other than size from a field, or for metric
// factors other than size, aspect and orientation together, or for a reference or a metric field on
// a surface mesh, and MeshError for an element whose mean metric is not positive definite (in its
// plane). `metrics` are vertex_metrics(mesh, options, reference), complete at every vertex.
// A surface mesh's element takes its target in its own input plane (the basis of its corners' own
// normal), and its metric root (Mesh::target_metric_roots) carries that plane to the xy plane,
// where the metrics rate it: the input element against its own target is exactly the target.
void set_targets(Mesh& mesh, const TargetOptions& options, const Mesh* reference, double ideal_scale,
                 std::span<const double> metrics);
void set_targets(Mesh& mesh, const TargetOptions& options, const Mesh* reference, double ideal_scale,
                 std::span<const double> metrics, bool surface);
void set_targets(Mesh& mesh, const TargetOptions& options, const Mesh* reference = nullptr);
// Throws MeshError unless `reference` has the mesh's element kind, counts and connectivity.
void check_reference(const Mesh& mesh, const Mesh& reference);

}  // namespace paloverde
