#include "workspace.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>

#include "core/blocked_sum.hpp"
#include "core/exact_sums.hpp"
#include "core/permutation.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/mesh/orientation.hpp"
#include "paloverde/mesh/renumber.hpp"
#include "local_untangle.hpp"

namespace paloverde::detail {

namespace {
constexpr ElementId kEvaluateChunk = 2048;
// The canonical element order is cut into this many blocks; each vertex sums its elements'
// contributions block by block. The blocks depend only on the whole mesh.
constexpr GlobalId kGradientBlocks = 64;

// The elements' working order: the movable ones first, each group in canonical order (the
// elements placed by their positions when these number them from 0, as serially; else sorted,
// then split stably).
struct MovableFirst {
    std::vector<ElementId> order;
    ElementId movable = 0;
};
MovableFirst movable_first(const Mesh& mesh, std::span<const GlobalId> element_order) {
    const auto m = static_cast<std::size_t>(mesh.num_elements());
    std::vector<ElementId> canonical(m);
    const bool numbered = std::all_of(element_order.begin(), element_order.end(),
                                      [m](GlobalId position) { return position >= 0 && static_cast<std::size_t>(position) < m; });
    if (numbered) {
        for (std::size_t e = 0; e < m; ++e) canonical[static_cast<std::size_t>(element_order[e])] = static_cast<ElementId>(e);
    } else {
        std::iota(canonical.begin(), canonical.end(), ElementId{0});
        std::sort(canonical.begin(), canonical.end(), [&](ElementId a, ElementId b) { return element_order[a] < element_order[b]; });
    }
    // Split stably: whether each element moves is asked in the mesh's own order (its corners
    // read in turn), then each goes to its group's next place.
    std::vector<std::uint8_t> moves(m);
    for (std::size_t e = 0; e < m; ++e) moves[e] = mesh.element_can_move(static_cast<ElementId>(e));
    MovableFirst result;
    result.movable = static_cast<ElementId>(std::count(moves.begin(), moves.end(), std::uint8_t{1}));
    result.order.resize(m);
    auto movable = result.order.begin(), frozen = movable + result.movable;
    for (ElementId e : canonical) *(moves[static_cast<std::size_t>(e)] ? movable++ : frozen++) = e;
    return result;
}

// The corners of copy k of a tetrahedron: edge k of (0 1), (0 2), (0 3), (1 2), (1 3), (2 3) first,
// the other two after them in the order that keeps the permutation even.
constexpr int kTermCorners[Workspace::kAngleTerms][4] = {{0, 1, 2, 3}, {0, 2, 3, 1}, {0, 3, 1, 2},
                                                         {1, 2, 0, 3}, {1, 3, 2, 0}, {2, 3, 0, 1}};

// The mesh with each tetrahedron as its kAngleTerms copies (Workspace's angle terms).
Mesh with_angle_terms(const Mesh& mesh) {
    std::vector<VertexId> connectivity;
    connectivity.reserve(Workspace::kAngleTerms * mesh.connectivity().size());
    for (ElementId e = 0; e < mesh.num_elements(); ++e) {
        const auto corners = mesh.element(e);
        for (const auto& order : kTermCorners)
            for (int i : order) connectivity.push_back(corners[i]);
    }
    Mesh out(mesh.kind(), std::vector<double>(mesh.coordinates().begin(), mesh.coordinates().end()), std::move(connectivity));
    std::vector<std::uint8_t> freedom(static_cast<std::size_t>(mesh.num_vertices()));
    for (VertexId v = 0; v < mesh.num_vertices(); ++v) freedom[v] = static_cast<std::uint8_t>(mesh.degrees_of_freedom(v));
    out.set_degrees_of_freedom(std::move(freedom));
    out.set_global_ids(std::vector<GlobalId>(mesh.global_ids().begin(), mesh.global_ids().end()));
    out.set_elements_flipped(mesh.elements_flipped());
    out.set_locality_ordered(mesh.locality_ordered());  // each element's copies side by side
    return out;
}

// Canonical positions of the copies: copy k of the element at p is at kAngleTerms p + k.
std::vector<GlobalId> term_positions(std::span<const GlobalId> positions) {
    std::vector<GlobalId> out;
    out.reserve(Workspace::kAngleTerms * positions.size());
    for (GlobalId p : positions)
        for (int k = 0; k < Workspace::kAngleTerms; ++k) out.push_back(Workspace::kAngleTerms * p + k);
    return out;
}
}  // namespace

Workspace::Workspace(MeshPart part, bool renumber, bool angle_terms)
    : original_(&part.mesh()), part_(part), mesh_(angle_terms ? own_ : part.mesh()), angle_terms_(angle_terms) {
    if (angle_terms && (part.mesh().kind() != ElementKind::Tetrahedron || part.mesh().has_cells()))
        throw OptionError("angle terms are for meshes of tetrahedra only");
    // Each copy permutes its element's corners, which a target's map is written for.
    if (angle_terms && part.mesh().has_targets())
        throw OptionError("the dihedral angles are rated against the regular tetrahedron: they take no targets");
    Mesh& held = part.mesh();
    const auto n = static_cast<std::size_t>(held.num_vertices());
    std::vector<GlobalId> whole_positions;  // a part's are its own
    std::span<const GlobalId> positions = part.element_positions();
    ElementId movable = 0;
    if (!part.whole()) {
        reducer_ = &part.reducer();
        halo_ = &part.halo();
        owned_.resize(n);
        for (VertexId v = 0; v < static_cast<VertexId>(n); ++v) {
            owned_[v] = part.owns(v);
            if (!owned_[v]) ghosts_.push_back(v);
        }
        // A part's vertices are in canonical order already: only its elements are reordered.
        auto [order, movable_count] = movable_first(held, part.element_positions());
        part.reorder_elements(order);
        part_order_ = std::move(order);
        movable = movable_count;
        positions = part.element_positions();  // reordered with the elements
    } else {
        // The whole mesh: its vertices in locality order (or as given) too.
        std::vector<VertexId> old_vertex;
        if (renumber) old_vertex = locality_vertex_order(held);
        std::vector<GlobalId> new_id(n);
        for (std::size_t i = 0; i < n; ++i)
            new_id[renumber ? static_cast<std::size_t>(old_vertex[i]) : i] = static_cast<GlobalId>(i);
        whole_positions = canonical_element_positions(held, new_id);
        auto [order, movable_count] = movable_first(held, whole_positions);
        whole_positions = gathered(whole_positions, std::span<const ElementId>(order));
        positions = whole_positions;
        held.permute(old_vertex, order);
        part_order_ = std::move(order);
        old_vertex_ = std::move(old_vertex);
        movable = movable_count;
        was_locality_ordered_ = held.locality_ordered();
        held.set_locality_ordered(renumber);
        owned_.assign(n, 1);
    }
    // From here on the part is in the workspace's order: should the rest fail, it gets its own back.
    try {
        const GlobalId global_elements = part.whole() ? held.num_elements() : part.global_elements();
        if (angle_terms_) {  // the copies in a mesh of the workspace's own, the part as it is
            own_ = with_angle_terms(held);
            if (!part.whole())
                for (std::uint8_t c : part.counted()) term_counted_.insert(term_counted_.end(), kAngleTerms, c);
            finish(term_positions(positions), term_counted_, kAngleTerms * global_elements, kAngleTerms * movable);
        } else {
            finish(positions, part.counted(), global_elements, movable);
        }
        if (!part.whole() && held.kind() == ElementKind::Triangle) scale_.plane_normal = part.plane_normal();
    } catch (...) {
        restore_part();
        throw;
    }
}

Workspace::~Workspace() {
    // Unwinding: the part is put back as hand_back() would. All or nothing: should memory run out
    // here, the part stays in the workspace's order.
    try {
        restore_part();
    } catch (const std::exception&) {
    }
}

void Workspace::restore_part() {
    if (restored_) return;
    if (part_.whole()) {
        original_->permute(inverse(std::span<const VertexId>(old_vertex_)), inverse(std::span<const ElementId>(part_order_)));
        original_->set_locality_ordered(was_locality_ordered_);
    } else {
        // The local smoother's sums follow the part's element order: it gets that order back.
        part_.reorder_elements(inverse(std::span<const ElementId>(part_order_)));
    }
    restored_ = true;
}

void Workspace::hand_back(std::span<const double> xyz) {
    std::copy(xyz.begin(), xyz.end(), original_->coordinates().begin());
    restore_part();
}

void Workspace::finish(std::span<const GlobalId> element_order, std::span<const std::uint8_t> counted,
                       GlobalId global_elements, ElementId movable) {
    const ElementId m = mesh_.num_elements();
    movable_ = movable;
    const auto is_counted = [&](ElementId e) { return counted.empty() || counted[e] != 0; };
    if (!counted.empty())
        for (ElementId e = 0; e < movable_; ++e)
            if (counted[e]) counted_.push_back(e);
    global_movable_ = reducer_->total(static_cast<double>(counted.empty() ? movable_ : counted_.size()));

    // The metric scale: the mean absolute element volume over the whole mesh, summed exactly
    // (the reference volume is this sum's, so MetricScale::of's rounded one need not be made).
    scale_.oriented_triangles = mesh_.kind() == ElementKind::Tetrahedron || mesh_.is_planar() || mesh_.has_surface_normals();
    scale_.plane_normal = mesh_.plane_normal();
    {
        std::vector<double> volume = absolute_volumes();
        for (ElementId e = 0; e < m; ++e)
            if (!is_counted(e)) volume[e] = 0.0;
        const double total = reducer_->total(exact_sum(volume));
        const double count =
            reducer_->total(static_cast<double>(counted.empty() ? m : std::count(counted.begin(), counted.end(), 1)));
        scale_.reference_volume = total > 0.0 && std::isfinite(total) && count > 0.0 ? total / count : 1.0;
    }
    // The edge of the regular simplex of the reference volume.
    reference_length_ = mesh_.kind() == ElementKind::Tetrahedron
                            ? std::cbrt(6.0 * std::numbers::sqrt2 * scale_.reference_volume)
                            : std::sqrt(4.0 * scale_.reference_volume / std::numbers::sqrt3);
    lanes_ = make_lanes(mesh_, movable_, element_order, global_elements, false);
    free_ = free_vertices_of(mesh_);
    element_order_.assign(element_order.begin(), element_order.end());
    global_elements_ = global_elements;
}

Workspace::Lanes Workspace::make_lanes(const Mesh& mesh, ElementId movable, std::span<const GlobalId> element_order,
                                       GlobalId global_elements, bool compact) {
    // A lane is a run of movable elements in one block of the canonical order. Lane partials are
    // added in lane order, elements within a lane in order: for an owned vertex, the same sums in
    // the same order as in the serial run.
    const GlobalId block = std::max<GlobalId>(1, (global_elements + kGradientBlocks - 1) / kGradientBlocks);
    Lanes lanes;
    std::size_t slots = 0;
    for (ElementId first = 0; first < movable;) {
        // The lane runs while the positions stay in its first element's block [end - block, end):
        // one division per lane, not one per element.
        const GlobalId end = (element_order[first] / block + 1) * block;
        ElementId last = first + 1;
        while (last < movable && element_order[last] < end && element_order[last] >= end - block) ++last;
        const auto corners = mesh.connectivity().subspan(static_cast<std::size_t>(first) * mesh.corners(),
                                                         static_cast<std::size_t>(last - first) * mesh.corners());
        const auto [low, high] = std::minmax_element(corners.begin(), corners.end());
        const auto range = static_cast<std::size_t>(*high - *low + 1);
        lanes.list.push_back({first, last, *low, *high, 0, range, slots});
        if (compact) slots += range;
        first = last;
    }
    // Compact lanes number their touched vertices in increasing order: marked in the lane's
    // slots, then numbered in one scan of its range (which the slots span anyway; faster than
    // sorting them). The slots of all lanes are allocated at once: growing them lane by lane
    // copied them over and over.
    lanes.slot.assign(slots, 0);
    std::size_t total = 0;
    for (Lane& lane : lanes.list) {
        lane.offset = total;
        if (compact) {
            std::uint32_t* slot = lanes.slot.data() + lane.slot_offset;
            const auto corners =
                mesh.connectivity().subspan(static_cast<std::size_t>(lane.first) * mesh.corners(),
                                            static_cast<std::size_t>(lane.last - lane.first) * mesh.corners());
            for (VertexId v : corners) slot[v - lane.low] = 1;
            std::uint32_t k = 0;
            for (std::size_t i = 0; i < lane.size; ++i)
                if (slot[i] != 0) {
                    slot[i] = k++;
                    lanes.vertex.push_back(lane.low + static_cast<VertexId>(i));
                }
            lane.size = k;
        }
        total += lane.size;
    }
    lanes.vertices = total;
    lanes.gradient.assign(3 * total, 0.0);
    return lanes;
}

std::vector<VertexId> Workspace::free_vertices_of(const Mesh& mesh) {
    std::vector<VertexId> free;
    for (VertexId v = 0; v < mesh.num_vertices(); ++v)
        if (mesh.can_move(v)) free.push_back(v);
    return free;
}

void Workspace::focus(std::span<const std::uint8_t> moving) {
    unfocus();
    const VertexId n = mesh_.num_vertices();
    const int k = mesh_.corners();
    Focus f;
    std::vector<std::uint8_t> freedom(static_cast<std::size_t>(n));  // nonzero: the vertex moves
    for (VertexId v = 0; v < n; ++v)
        freedom[v] = moving[v] != 0 ? static_cast<std::uint8_t>(mesh_.degrees_of_freedom(v)) : 0;
    // The elements of the moving vertices, in order: marked through the vertices (a focus is a
    // small part of a large mesh), then listed.
    std::vector<std::uint8_t> in_focus(static_cast<std::size_t>(movable_), 0);
    for (VertexId v = 0; v < n; ++v)
        if (freedom[v] != 0)
            for (ElementId e : mesh_.elements_of(v))
                if (e < movable_) in_focus[e] = 1;
    for (ElementId e = 0; e < movable_; ++e)
        if (in_focus[e]) f.elements.push_back(e);
    std::vector<VertexId> connectivity(f.elements.size() * static_cast<std::size_t>(k));
    std::vector<GlobalId> positions(f.elements.size());
    for (std::size_t i = 0; i < f.elements.size(); ++i) {
        const auto corners = mesh_.element(f.elements[i]);
        for (int c = 0; c < k; ++c) connectivity[i * k + c] = corners[c];  // std::copy calls memmove
        positions[i] = element_order_[f.elements[i]];
    }
    f.mesh = Mesh(mesh_.kind(), std::vector<double>(mesh_.coordinates().begin(), mesh_.coordinates().end()),
                  std::move(connectivity));
    f.mesh.set_degrees_of_freedom(std::move(freedom));
    f.mesh.set_locality_ordered(mesh_.locality_ordered());  // the whole's elements, in their order
    if (mesh_.has_cells() || mesh_.has_targets() || mesh_.has_surface_normals()) {  // maps, targets, normals
        std::vector<VertexId> same(static_cast<std::size_t>(n));
        std::iota(same.begin(), same.end(), VertexId{0});
        f.mesh.carry_element_data_from(mesh_, same, f.elements);
    }
    const auto size = static_cast<ElementId>(f.elements.size());
    if (!part_.whole()) {
        const std::span<const std::uint8_t> counted = angle_terms_ ? std::span<const std::uint8_t>(term_counted_) : part_.counted();
        for (ElementId i = 0; i < size; ++i)
            if (counted[f.elements[i]]) f.counted.push_back(i);
    }
    f.global_count = reducer_->total(static_cast<double>(part_.whole() ? f.elements.size() : f.counted.size()));
    f.lanes = make_lanes(f.mesh, size, positions, global_elements_, true);
    f.free = free_vertices_of(f.mesh);
    focus_ = std::move(f);
}

std::span<const double> Workspace::counted(std::span<const double> quality, std::vector<double>& buffer) const {
    if (part_.whole()) return quality;
    const std::vector<ElementId>& counted = focus_ ? focus_->counted : counted_;
    buffer.resize(counted.size());
    for (std::size_t i = 0; i < counted.size(); ++i) buffer[i] = quality[counted[i]];
    return buffer;
}

std::vector<double> Workspace::absolute_volumes() const {
    std::vector<double> volume(static_cast<std::size_t>(mesh_.num_elements()));
    MetricScale unit = scale_;
    unit.reference_volume = 1.0;
    auto measure = make_metric("scaled_volume");
    measure->set_scale(unit);
    measure->evaluate(mesh_, mesh_.coordinates(), 0, mesh_.num_elements(), volume.data());
    for (double& v : volume) v = std::abs(v);
    return volume;
}

// Per vertex the mean absolute volume of its elements; per element the mean of that over its
// corners: a local, scale-free size.
std::vector<double> Workspace::local_reference_volumes() const {
    return detail::local_reference_volumes(mesh_, mesh_.coordinates(), scale_, *halo_, movable_);
}

void Workspace::evaluate(const QualityMetric& metric, std::span<const double> xyz, std::span<double> quality) const {
    const Mesh& mesh = this->mesh();
    const ElementId movable = movable_elements();
    const ElementId chunks = (movable + kEvaluateChunk - 1) / kEvaluateChunk;
#pragma omp parallel for schedule(static) if (static_cast<std::size_t>(movable) > kParallelThreshold)
    for (ElementId c = 0; c < chunks; ++c) {
        const ElementId first = c * kEvaluateChunk, last = std::min(movable, first + kEvaluateChunk);
        metric.evaluate(mesh, xyz, first, last, quality.data() + first);
    }
}

void Workspace::gradient(const QualityMetric& metric, std::span<const double> xyz, std::span<const double> weight,
                         std::span<double> gradient, std::span<const double> curvature_weight,
                         std::span<double> curvature) {
    const Mesh& mesh = this->mesh();
    const ElementId movable = movable_elements();
    Lanes& lanes = focus_ ? focus_->lanes : lanes_;
    const bool with_curvature = !curvature.empty();
    if (with_curvature && lanes.curvature.empty()) lanes.curvature.assign(6 * lanes.vertices, 0.0);
    const auto count = static_cast<std::ptrdiff_t>(lanes.list.size());
#pragma omp parallel for schedule(dynamic, 1) if (static_cast<std::size_t>(movable) > kParallelThreshold)
    for (std::ptrdiff_t l = 0; l < count; ++l) {
        const Lane& lane = lanes.list[static_cast<std::size_t>(l)];
        QualityMetric::GradientTarget target;
        target.weight = weight.data() + lane.first;
        target.gradient = lanes.gradient.data() + 3 * lane.offset;
        std::fill(target.gradient, target.gradient + 3 * lane.size, 0.0);
        if (with_curvature) {
            target.curvature_weight = curvature_weight.data() + lane.first;
            target.curvature = lanes.curvature.data() + 6 * lane.offset;
            std::fill(target.curvature, target.curvature + 6 * lane.size, 0.0);
        }
        target.base = lane.low;
        if (lanes.compact()) target.slot = lanes.slot.data() + lane.slot_offset;
        metric.accumulate_gradient(mesh, xyz, lane.first, lane.last, target);
    }
    // Each vertex sums the lanes that touch it in lane order; vertex blocks run in parallel.
    // Fixed vertices get zero; ghosts too, until the halo brings their owners' values.
    const VertexId n = mesh.num_vertices();
    const VertexId block = 4096;
    auto unless_free_and_owned = [&](std::span<double> out, int width, VertexId v) {
        if (!mesh.can_move(v) || !owned_[v])
            for (int c = 0; c < width; ++c) out[width * static_cast<std::size_t>(v) + c] = 0.0;
    };
    auto gather = [&](std::span<double> out, const std::vector<double>& buffer, int width, VertexId low, VertexId high) {
        std::fill(out.begin() + width * static_cast<std::size_t>(low), out.begin() + width * (static_cast<std::size_t>(high) + 1), 0.0);
        for (const Lane& lane : lanes.list) {
            const VertexId from = std::max(low, lane.low), to = std::min(high, lane.high);
            if (from > to) continue;
            // One flat run of doubles, which the compiler vectorizes.
            const double* source = buffer.data() + width * (lane.offset + static_cast<std::size_t>(from - lane.low));
            double* target = out.data() + width * static_cast<std::size_t>(from);
            const std::size_t run = width * static_cast<std::size_t>(to - from + 1);
            for (std::size_t i = 0; i < run; ++i) target[i] += source[i];
        }
        for (VertexId v = low; v <= high; ++v) unless_free_and_owned(out, width, v);
    };
    // Compact lanes: the same sums in the same order, over the touched vertices only.
    auto gather_compact = [&](std::span<double> out, const std::vector<double>& buffer, int width, VertexId low,
                              VertexId high) {
        // visit(k, v) for each slot k of a lane, lane by lane, whose vertex v lies in [low, high].
        auto each_in_block = [&](auto visit) {
            for (const Lane& lane : lanes.list) {
                if (lane.high < low || lane.low > high) continue;
                const auto begin = lanes.vertex.begin() + static_cast<std::ptrdiff_t>(lane.offset);
                const auto end = begin + static_cast<std::ptrdiff_t>(lane.size);
                for (auto it = std::lower_bound(begin, end, low); it != end && *it <= high; ++it)
                    visit(static_cast<std::size_t>(it - lanes.vertex.begin()), *it);
            }
        };
        each_in_block([&](std::size_t, VertexId v) {
            for (int c = 0; c < width; ++c) out[width * static_cast<std::size_t>(v) + c] = 0.0;
        });
        each_in_block([&](std::size_t k, VertexId v) {
            for (int c = 0; c < width; ++c) out[width * static_cast<std::size_t>(v) + c] += buffer[width * k + c];
        });
        each_in_block([&](std::size_t, VertexId v) { unless_free_and_owned(out, width, v); });
    };
#pragma omp parallel for schedule(static) if (static_cast<std::size_t>(movable) > kParallelThreshold)
    for (VertexId b = 0; b < (n + block - 1) / block; ++b) {
        const VertexId low = b * block, high = std::min(n, low + block) - 1;
        if (lanes.compact()) {
            gather_compact(gradient, lanes.gradient, 3, low, high);
            if (with_curvature) gather_compact(curvature, lanes.curvature, 6, low, high);
        } else {
            gather(gradient, lanes.gradient, 3, low, high);
            if (with_curvature) gather(curvature, lanes.curvature, 6, low, high);
        }
    }
}

namespace {

// Bounded sums of a[v] . b[v] over the owned vertices vertex(i), i < count, over all processes.
template <class Vertex>
double dot_over(const Workspace& work, std::size_t count, Vertex vertex, std::span<const double> a,
                std::span<const double> b) {
    const auto owned = work.owned();
    auto term = [&](std::size_t v) { return a[3 * v] * b[3 * v] + a[3 * v + 1] * b[3 * v + 1] + a[3 * v + 2] * b[3 * v + 2]; };
    double largest = 0.0;
    for (std::size_t i = 0; i < count; ++i)
        if (const auto v = static_cast<std::size_t>(vertex(i)); owned[v]) largest = std::max(largest, std::abs(term(v)));
    largest = work.reducer().max(largest);
    auto sums = bounded_sums<1>(count, {largest}, [&](std::size_t i, auto& acc) {
        if (const auto v = static_cast<std::size_t>(vertex(i)); owned[v]) acc[0].add(term(v));
    });
    work.reducer().sum(sums);
    return sums[0].value();
}

}  // namespace

double owned_dot(const Workspace& work, std::span<const double> a, std::span<const double> b) {
    return dot_over(work, work.owned().size(), [](std::size_t v) { return v; }, a, b);
}

double free_owned_dot(const Workspace& work, std::span<const double> a, std::span<const double> b) {
    const auto free = work.free_vertices();
    return dot_over(work, free.size(), [&](std::size_t i) { return free[i]; }, a, b);
}

bool untangled(const Workspace& work, std::span<const double> xyz) {
    double tangled = 0.0;
    for (ElementId e = 0; e < work.movable_elements() && tangled == 0.0; ++e)
        if (element_orientation(work.mesh(), xyz, e) <= 0) tangled = 1.0;
    return work.reducer().max(tangled) == 0.0;
}

}  // namespace paloverde::detail
