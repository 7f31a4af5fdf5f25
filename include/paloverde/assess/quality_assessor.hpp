#pragma once
// Statistics of one or more metrics over a mesh, split between elements that a smoother can
// move (at least one free vertex) and those it cannot (all vertices fixed).
#include <memory>
#include <span>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "paloverde/metrics/quality_metric.hpp"
#include "paloverde/mesh/mesh.hpp"
#include "paloverde/parallel/mesh_part.hpp"
#include "paloverde/parallel/reducer.hpp"

namespace paloverde {

struct QualityStatistics {
    ElementId count = 0;
    double min = 0.0, max = 0.0, mean = 0.0, rms = 0.0;
    ElementId worst_element = -1;  // where min is attained
    // Equal-width bins over [min, max].
    std::vector<ElementId> histogram;
};

struct MetricReport {
    std::string name;
    QualityStatistics all;
    QualityStatistics movable;  // elements with at least one free vertex
    QualityStatistics frozen;   // elements whose vertices are all fixed
};

struct QualityReport {
    VertexId vertices = 0;
    VertexId free_vertices = 0;
    ElementId elements = 0;
    ElementId frozen_elements = 0;  // all vertices fixed
    ElementId inverted = 0;         // decided by an exact orientation predicate
    ElementId inverted_frozen = 0;  // of those, how many no smoother can fix
    ElementId degenerate = 0;       // exactly zero volume
    std::vector<MetricReport> metrics;
    // A mesh with cells (quadrilaterals, hexahedra, wedges, pyramids) is reported by cell (its
    // quality the worst corner's, inverted when any corner is), and by cell type here.
    struct TypeReport {
        std::string type;
        ElementId count = 0, inverted = 0;
        std::vector<std::pair<std::string, double>> worst;  // per metric: the type's smallest value
    };
    std::vector<TypeReport> by_type;

    const MetricReport* metric(std::string_view name) const;
    std::string to_text() const;
    // {"vertices", "elements", "inverted", ..., "metrics": {"<name>": {"min","max","mean","rms",...}}}
    std::string to_json() const;
};

class QualityAssessor {
public:
    // The default set (default_metrics()): the shape metrics, scaled volume, the minimum corner
    // scaled Jacobian, and the minimum dihedral angle (tetrahedra) or minimum angle (triangles),
    // each where the mesh's kind has it.
    QualityAssessor();
    static const std::vector<std::string>& default_metrics();
    explicit QualityAssessor(const std::vector<std::string>& metric_names, int histogram_bins = 10);

    // Metrics that do not support the mesh's element kind are left out of the report.
    QualityReport assess(const Mesh& mesh) const { return assess(mesh, mesh.coordinates()); }
    QualityReport assess(const Mesh& mesh, std::span<const double> coordinates) const;
    // The report of the whole mesh the part belongs to. A distributed part's is collective, the
    // same on every rank, and equal to the serial report except that worst_element is -1.
    QualityReport assess(const MeshPart& part) const;
    // This assessor's report of a mesh, taken from a report `other` made of the same mesh (the same
    // coordinates, fixed vertices and targets; the scale aside): what assess() would give, without
    // a pass over the elements. Empty unless `other` rates every metric this one rates, in as many
    // histogram bins.
    std::optional<QualityReport> taken_from(const QualityReport& report, const QualityAssessor& other) const;
    const std::vector<std::string>& metric_names() const { return names_; }
    int histogram_bins() const { return bins_; }

private:
    // Elements with counted[e] (all when empty) and vertices with owned[v] enter the report;
    // sums go through the reducer.
    QualityReport assess(const Mesh& mesh, std::span<const double> coordinates,
                         std::span<const std::uint8_t> counted, std::span<const std::uint8_t> owned,
                         const Reducer& reducer, const Vec3& plane_normal) const;

    std::vector<std::string> names_;
    int bins_ = 10;
};

}  // namespace paloverde
