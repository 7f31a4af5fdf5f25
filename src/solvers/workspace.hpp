#pragma once
// The arrays a solver works on, in canonical order, and the machinery for passes over them whose
// results do not depend on the number of threads or of processes.
//
// Canonical order: vertices by canonical id (reverse Cuthill-McKee order of the whole mesh, for
// locality), elements by their sorted canonical vertex ids. Elements with a free vertex (movable)
// come first. A process of a distributed run holds a part of the mesh in the same order; every
// vertex sum runs over the vertex's elements in canonical order, grouped in blocks of the
// canonical element order that are the same for every split of the mesh, so the owner of a
// vertex computes bit for bit the gradient the serial run computes.
#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/exact_sums.hpp"
#include "paloverde/mesh/mesh.hpp"
#include "paloverde/metrics/quality_metric.hpp"
#include "paloverde/parallel/halo.hpp"
#include "paloverde/parallel/mesh_part.hpp"
#include "paloverde/parallel/reducer.hpp"

namespace paloverde::detail {

class Workspace {
public:
    // The part in the workspace's order, in place (a copy would cost as much as the mesh): the
    // whole mesh has its vertices renumbered for locality (unless `renumber` is false) and its
    // elements put in the working order; a part of a distributed mesh, in canonical order
    // already, has only its elements reordered. Until hand_back() (or the destructor, when a run
    // throws) the part's mesh is numbered as the workspace's; caller_vertex() names its vertices.
    //
    // With `angle_terms` (tetrahedra without cells), each element is held as kAngleTerms copies,
    // corners permuted (evenly: the orientation stays) so that each of its edges comes first in one
    // of them: a metric of the edge of corners 0 and 1 (make_dihedral_sine_term) then rates each
    // dihedral angle as an element of its own. Copy k of element e is element kAngleTerms e + k,
    // at canonical position kAngleTerms p + k; copy 0 keeps the corners' order.
    Workspace(MeshPart part, bool renumber, bool angle_terms = false);
    static constexpr int kAngleTerms = 6;
    ~Workspace();
    Workspace(const Workspace&) = delete;
    Workspace& operator=(const Workspace&) = delete;

    // The elements a solver works on: the movable elements, or while focused those of the focus.
    const Mesh& mesh() const { return focus_ ? focus_->mesh : mesh_; }
    ElementId movable_elements() const { return focus_ ? static_cast<ElementId>(focus_->elements.size()) : movable_; }
    // Per vertex: this process owns it (computes its gradient and moves it).
    std::span<const std::uint8_t> owned() const { return owned_; }
    // The vertices of mesh() that can move, ghosts included, in increasing order. A vertex field
    // that vanishes elsewhere (a gradient, a direction) needs only these: a focus is a fraction
    // of the mesh, and loops over every vertex would cost what the whole mesh costs.
    std::span<const VertexId> free_vertices() const { return focus_ ? focus_->free : free_; }
    // Vertices owned by other processes.
    std::span<const VertexId> ghosts() const { return ghosts_; }
    double reference_length() const { return reference_length_; }
    const MetricScale& scale() const { return scale_; }
    const Reducer& reducer() const { return *reducer_; }
    const Halo& halo() const { return *halo_; }
    // The part worked on (a distributed run's with its elements in the workspace's order until the
    // workspace is destroyed).
    const MeshPart& part() const { return part_; }
    // Per movable element, as metric scale: the mean size of its corners' neighbourhoods.
    std::vector<double> local_reference_volumes() const;

    // The movable elements' qualities this process counts in global sums (all, serially).
    std::span<const double> counted(std::span<const double> quality, std::vector<double>& buffer) const;
    // Elements per element of the part: kAngleTerms with angle terms, else 1.
    int copies() const { return angle_terms_ ? kAngleTerms : 1; }
    // Number of movable elements over all processes.
    double global_movable() const { return focus_ ? focus_->global_count : global_movable_; }

    // Focus: until unfocus(), the workspace holds only the movable elements with a vertex in
    // `moving` (a flag per vertex, equal at an owner and its ghosts), and only those vertices can
    // move; mesh(), movable_elements(), counted(), evaluate() and gradient() then refer to them.
    // The same vertices and vertex fields; each owned vertex's gradient is bit for bit the whole
    // mesh's (a moving vertex has all its elements in the focus). Collective.
    void focus(std::span<const std::uint8_t> moving);
    void unfocus() {
        focus_.reset();
        ++focus_generation_;
    }
    // Changes with every focus() and unfocus(): whoever keeps vertex fields between passes knows
    // whether the moving vertices are still the same.
    std::uint64_t focus_generation() const { return focus_generation_; }
    bool focused() const { return focus_.has_value(); }
    // While focused: focus element i is movable element focus_elements()[i] of the whole.
    std::span<const ElementId> focus_elements() const { return focus_->elements; }

    // Qualities of the movable elements at positions xyz.
    void evaluate(const QualityMetric& metric, std::span<const double> xyz, std::span<double> quality) const;
    // gradient = sum_e weight[e] * grad q_e over the movable elements, zero at fixed vertices;
    // with curvature weights also curvature = sum_e cw[e] * g g^T per vertex (6 doubles).
    // Complete at owned vertices only; ghosts get their owner's values from the halo. While
    // focused only the focus elements' vertices are written (the rest keeps what it held): a pass
    // costs the focus, not the whole mesh, and callers read the free vertices only.
    void gradient(const QualityMetric& metric, std::span<const double> xyz, std::span<const double> weight,
                  std::span<double> gradient, std::span<const double> curvature_weight = {},
                  std::span<double> curvature = {});

    // The id in the part it was made from of the workspace's vertex v.
    VertexId caller_vertex(VertexId v) const { return old_vertex_.empty() ? v : old_vertex_[v]; }
    // Coordinates xyz (the workspace's) into the part, which gets back its own order: the
    // workspace's last act (its mesh is the part's no longer).
    void hand_back(std::span<const double> xyz);

private:
    struct Lane {
        ElementId first, last;   // elements
        VertexId low, high;      // vertices they touch: [low, high]
        std::size_t offset;      // first vertex of the lane in the lane buffers
        std::size_t size;        // its vertices there: high - low + 1, or the touched ones (compact)
        std::size_t slot_offset; // compact: where its map from v - low to slots starts in `slot`
    };
    struct Lanes {
        std::vector<Lane> list;
        std::size_t vertices = 0;       // total over the lanes
        std::vector<double> gradient;   // 3 per lane vertex
        std::vector<double> curvature;  // 6 per lane vertex, allocated on first use
        // Compact lanes (a focus) keep only the vertices their elements touch: `vertex` lists
        // them per lane in increasing order, and `slot` maps each lane's range to them.
        std::vector<VertexId> vertex;
        std::vector<std::uint32_t> slot;
        bool compact() const { return !vertex.empty(); }
    };
    struct Focus {
        Mesh mesh;                // every vertex, the focus elements; only moving vertices free
        std::vector<ElementId> elements; // the whole's movable element of each focus element
        std::vector<ElementId> counted;  // focus elements counted here (distributed runs)
        double global_count = 0.0;
        Lanes lanes;
        std::vector<VertexId> free;      // its moving vertices
    };
    // Sets up the scale and the lanes of mesh_, whose elements are in the working order (the
    // `movable` ones first, each group canonical), with their canonical positions
    // `element_order` and `counted` (empty: all counted).
    void finish(std::span<const GlobalId> element_order, std::span<const std::uint8_t> counted, GlobalId global_elements,
                ElementId movable);
    // Lanes over elements [0, movable) of `mesh`, whose canonical positions are `element_order`;
    // `compact` for a focus, whose lanes' ranges are mostly vertices they do not touch.
    static Lanes make_lanes(const Mesh& mesh, ElementId movable, std::span<const GlobalId> element_order,
                            GlobalId global_elements, bool compact);
    std::vector<double> absolute_volumes() const;  // per element, at the mesh's coordinates
    static std::vector<VertexId> free_vertices_of(const Mesh& mesh);
    // Gives the part its own order back (once).
    void restore_part();

    Mesh* original_;                     // the part's mesh, in the workspace's order until restored
    Mesh own_;                           // with angle terms: the copies of its elements
    MeshPart part_;
    std::vector<ElementId> part_order_;  // workspace element i is the part's part_order_[i]
    Mesh& mesh_;                         // the part's mesh, or own_ with angle terms
    bool angle_terms_ = false;
    bool restored_ = false;
    bool was_locality_ordered_ = false;       // the whole mesh's mark, given back with its order
    std::vector<std::uint8_t> term_counted_;  // distributed, angle terms: counted, per copy
    std::vector<VertexId> old_vertex_;  // the whole mesh, renumbered: caller's id of each vertex
    ElementId movable_ = 0;
    std::vector<std::uint8_t> owned_;
    std::vector<VertexId> ghosts_;
    std::vector<ElementId> counted_;   // movable elements counted here; empty when all are
    double global_movable_ = 0.0;
    Reducer serial_reducer_;
    Halo serial_halo_;
    const Reducer* reducer_ = &serial_reducer_;
    const Halo* halo_ = &serial_halo_;
    MetricScale scale_;
    double reference_length_ = 1.0;
    Lanes lanes_;
    std::vector<VertexId> free_;
    std::vector<GlobalId> element_order_;  // canonical position of each element (workspace order)
    GlobalId global_elements_ = 0;
    std::uint64_t focus_generation_ = 0;
    std::optional<Focus> focus_;
};

// Exact sums of term(vertex(i), acc) for i < count over the vertices this process owns, then
// over all processes: the same bits for any number of threads and processes, and in any order.
template <int K, class Vertex, class Term>
std::array<double, K> owned_sums_over(const Workspace& work, std::size_t count, Vertex vertex, Term term) {
    const auto owned = work.owned();
    auto sums = exact_sums<K>(count, [&](std::size_t i, auto& acc) {
        const auto v = static_cast<std::size_t>(vertex(i));
        if (owned[v]) term(v, acc);
    });
    work.reducer().sum(sums);
    std::array<double, K> out{};
    for (int k = 0; k < K; ++k) out[k] = sums[k].value();
    return out;
}

// Over every owned vertex.
template <int K, class Term>
std::array<double, K> owned_sums(const Workspace& work, Term term) {
    return owned_sums_over<K>(work, work.owned().size(), [](std::size_t v) { return v; }, term);
}

// Over the free ones only (Workspace::free_vertices): the same sums, bit for bit, for terms that
// vanish at the vertices that cannot move.
template <int K, class Term>
std::array<double, K> free_owned_sums(const Workspace& work, Term term) {
    const auto free = work.free_vertices();
    return owned_sums_over<K>(work, free.size(), [&](std::size_t i) { return free[i]; }, term);
}

// coordinate(i) for the three coordinates i of every free vertex (Workspace::free_vertices), owned
// or ghost, spread over the threads: the loops over vertex fields that cost the focus, not the mesh.
template <class Coordinate>
void for_each_free_coordinate(const Workspace& work, Coordinate coordinate) {
    const auto free = work.free_vertices();
#pragma omp parallel for schedule(static) if (free.size() > kParallelThreshold)
    for (std::size_t k = 0; k < free.size(); ++k)
        for (std::size_t i = 3 * static_cast<std::size_t>(free[k]); i < 3 * static_cast<std::size_t>(free[k]) + 3; ++i)
            coordinate(i);
}

// The dot product of two vertex fields (3 doubles per vertex) over the owned vertices of all
// processes: bounded sums (core/exact_sums.hpp) under the largest term, the same bits for any
// number of threads and processes, with additions only (faster than owned_sums' ExactSum).
double owned_dot(const Workspace& work, std::span<const double> a, std::span<const double> b);
// The same over the free vertices only (Workspace::free_vertices): the same bits for fields that
// vanish at the vertices that cannot move, at the cost of the focus rather than the mesh.
double free_owned_dot(const Workspace& work, std::span<const double> a, std::span<const double> b);

// Every movable element is positively oriented (decided exactly), over all processes.
bool untangled(const Workspace& work, std::span<const double> xyz);

}  // namespace paloverde::detail
