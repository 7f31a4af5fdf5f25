#include "paloverde/mesh/mesh.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "paloverde/core/error.hpp"
#include "core/permutation.hpp"
#include "core/prefetch.hpp"
#include "mesh/small_matrix.hpp"

namespace paloverde {

Mesh::Mesh(ElementKind kind, std::vector<double> coordinates, std::vector<VertexId> connectivity)
    : kind_(kind), coordinates_(std::move(coordinates)), connectivity_(std::move(connectivity)) {
    const int k = corners();
    if (coordinates_.size() % 3 != 0) throw MeshError("coordinate array length is not a multiple of 3");
    if (connectivity_.size() % static_cast<std::size_t>(k) != 0)
        throw MeshError("connectivity length is not a multiple of " + std::to_string(k));
    if (coordinates_.size() / 3 > static_cast<std::size_t>(std::numeric_limits<VertexId>::max()) ||
        connectivity_.size() / k > static_cast<std::size_t>(std::numeric_limits<ElementId>::max()))
        throw MeshError("mesh too large for one process: partition it across more ranks");
    const VertexId n = num_vertices();
    for (VertexId v = 0; v < n; ++v)
        for (int c = 0; c < 3; ++c)
            if (!std::isfinite(coordinates_[3 * v + c]))
                throw MeshError("vertex " + std::to_string(v) + " has a non-finite coordinate");
    const ElementId m = num_elements();
    for (ElementId e = 0; e < m; ++e) {
        const VertexId* c = connectivity_.data() + static_cast<std::size_t>(e) * k;
        for (int i = 0; i < k; ++i) {
            if (c[i] < 0 || c[i] >= n)
                throw MeshError("element " + std::to_string(e) + " refers to vertex " + std::to_string(c[i]) +
                                ", outside 0.." + std::to_string(n - 1));
            for (int j = 0; j < i; ++j)
                if (c[i] == c[j])
                    throw MeshError("element " + std::to_string(e) + " repeats vertex " + std::to_string(c[i]));
        }
    }
    fixed_.assign(static_cast<std::size_t>(n), 0);
    global_ids_.resize(static_cast<std::size_t>(n));
    std::iota(global_ids_.begin(), global_ids_.end(), GlobalId{0});
    build_adjacency();
    find_plane();
}

Mesh Mesh::from_cells(std::vector<double> coordinates, std::span<const CellType> types,
                      std::vector<VertexId> cells, bool keep_cells) {
    if (types.empty()) return Mesh(ElementKind::Tetrahedron, std::move(coordinates), std::move(cells));
    const CellInfo& first = cell_info(types[0]);
    std::vector<std::int64_t> offsets(types.size() + 1, 0);
    bool simplices = true;
    for (std::size_t c = 0; c < types.size(); ++c) {
        const CellInfo& info = cell_info(types[c]);
        if (info.dimension != first.dimension)
            throw MeshError("cell " + std::to_string(c) + " is a " + std::string(info.name) + " among " +
                            std::to_string(first.dimension) + "D cells: a mesh holds cells of one dimension");
        simplices = simplices && types[c] == types[0] && is_simplex(types[c]);
        offsets[c + 1] = offsets[c] + info.corners;
    }
    if (static_cast<std::size_t>(offsets.back()) != cells.size())
        throw MeshError("cell connectivity holds " + std::to_string(cells.size()) + " ids for cells of " +
                        std::to_string(offsets.back()) + " corners");
    if (simplices && !keep_cells) return Mesh(first.simplex, std::move(coordinates), std::move(cells));
    const auto n = static_cast<std::int64_t>(coordinates.size() / 3);
    std::size_t corners_total = 0;
    for (std::size_t c = 0; c < types.size(); ++c) {
        const CellInfo& info = cell_info(types[c]);
        const VertexId* v = cells.data() + offsets[c];
        for (int i = 0; i < info.corners; ++i) {
            if (v[i] < 0 || v[i] >= n)
                throw MeshError("cell " + std::to_string(c) + " (" + std::string(info.name) + ") refers to vertex " +
                                std::to_string(v[i]) + ", outside 0.." + std::to_string(n - 1));
            for (int j = 0; j < i; ++j)
                if (v[i] == v[j])
                    throw MeshError("cell " + std::to_string(c) + " (" + std::string(info.name) + ") repeats vertex " +
                                    std::to_string(v[i]));
        }
        corners_total += info.frames.size();
    }
    if (corners_total > static_cast<std::size_t>(std::numeric_limits<ElementId>::max()))
        throw MeshError("mesh too large for one process: partition it across more ranks");
    const int k = corner_count(first.simplex);
    std::vector<VertexId> corners;
    corners.reserve(corners_total * static_cast<std::size_t>(k));
    std::vector<ElementId> element_cell;
    std::vector<std::uint8_t> corner_map;
    element_cell.reserve(corners_total);
    corner_map.reserve(corners_total);
    for (std::size_t c = 0; c < types.size(); ++c) {
        const CellInfo& info = cell_info(types[c]);
        const VertexId* v = cells.data() + offsets[c];
        for (std::size_t f = 0; f < info.frames.size(); ++f) {
            for (int i = 0; i < k; ++i) corners.push_back(v[info.frames[f][i]]);
            element_cell.push_back(static_cast<ElementId>(c));
            corner_map.push_back(corner_map_id(types[c], static_cast<int>(f)));
        }
    }
    Mesh mesh(first.simplex, std::move(coordinates), std::move(corners));
    mesh.cell_types_.assign(types.begin(), types.end());
    mesh.cell_offsets_ = std::move(offsets);
    mesh.cell_connectivity_ = std::move(cells);
    mesh.element_cell_ = std::move(element_cell);
    mesh.corner_map_ = std::move(corner_map);
    return mesh;
}

std::vector<double> Mesh::cell_minimum(std::span<const double> per_element) const {
    if (!has_cells()) return {per_element.begin(), per_element.end()};
    std::vector<double> out(cell_types_.size(), INFINITY);
    for (std::size_t e = 0; e < per_element.size(); ++e) {
        double& m = out[static_cast<std::size_t>(element_cell_[e])];
        if (!(per_element[e] >= m)) m = per_element[e];  // NaN wins: it must show
    }
    return out;
}

void Mesh::carry_element_data_from(const Mesh& source, std::span<const VertexId> new_id,
                                   std::span<const ElementId> old_element) {
    cell_types_ = source.cell_types_;
    cell_offsets_ = source.cell_offsets_;
    cell_connectivity_.resize(source.cell_connectivity_.size());
    for (std::size_t i = 0; i < cell_connectivity_.size(); ++i)
        cell_connectivity_[i] = new_id[static_cast<std::size_t>(source.cell_connectivity_[i])];
    element_cell_.clear();
    corner_map_.clear();
    clear_targets();
    if (source.has_cells()) {
        element_cell_.resize(old_element.size());
        corner_map_.resize(old_element.size());
        for (std::size_t i = 0; i < old_element.size(); ++i) {
            element_cell_[i] = source.element_cell_[static_cast<std::size_t>(old_element[i])];
            corner_map_[i] = source.corner_map_[static_cast<std::size_t>(old_element[i])];
        }
    }
    surface_normals_.clear();
    if (source.has_surface_normals()) {
        surface_normals_.resize(old_element.size());
        for (std::size_t i = 0; i < old_element.size(); ++i)
            surface_normals_[i] = source.surface_normals_[static_cast<std::size_t>(old_element[i])];
    }
    if (source.has_targets()) {
        target_maps_.resize(old_element.size());
        target_volumes_.resize(old_element.size());
        for (std::size_t i = 0; i < old_element.size(); ++i) {
            target_maps_[i] = source.target_maps_[static_cast<std::size_t>(old_element[i])];
            target_volumes_[i] = source.target_volumes_[static_cast<std::size_t>(old_element[i])];
        }
        if (!source.target_metric_roots_.empty()) {
            target_metric_roots_.resize(old_element.size());
            for (std::size_t i = 0; i < old_element.size(); ++i)
                target_metric_roots_[i] = source.target_metric_roots_[static_cast<std::size_t>(old_element[i])];
        }
    }
}

namespace {
// Vertex -> incident elements of `connectivity` (k corners per element, n vertices), compressed
// rows, each row in increasing element order.
void element_rows(std::span<const VertexId> connectivity, std::size_t n, int k, std::vector<std::int64_t>& offsets,
                  std::vector<ElementId>& elements) {
    offsets.assign(n + 1, 0);
    for (VertexId v : connectivity) ++offsets[static_cast<std::size_t>(v) + 1];
    std::partial_sum(offsets.begin(), offsets.end(), offsets.begin());
    elements.resize(connectivity.size());
    std::vector<std::int64_t> next(offsets.begin(), offsets.end() - 1);
    const auto m = static_cast<ElementId>(connectivity.size() / static_cast<std::size_t>(k));
    const VertexId* corner = connectivity.data();
    for (ElementId e = 0; e < m; ++e)
        for (int c = 0; c < k; ++c) elements[static_cast<std::size_t>(next[*corner++]++)] = e;
}

// Throws MeshError unless `order` lists each of 0..size-1 once.
template <class Id>
void check_permutation(std::span<const Id> order, std::size_t size, const char* what) {
    if (order.size() != size)
        throw MeshError("renumbering: " + std::to_string(order.size()) + " " + what + " given for " + std::to_string(size));
    std::vector<std::uint8_t> seen(size, 0);
    for (std::size_t i = 0; i < size; ++i) {
        const Id id = order[i];
        if (id < 0 || static_cast<std::size_t>(id) >= size || seen[static_cast<std::size_t>(id)])
            throw MeshError(std::string("renumbering: the new ") + what + " are not a permutation of the old (" +
                            std::to_string(id) + " at " + std::to_string(i) + ")");
        seen[static_cast<std::size_t>(id)] = 1;
    }
}

}  // namespace

void Mesh::permute(std::span<const VertexId> old_vertex, std::span<const ElementId> old_element) {
    const auto n = static_cast<std::size_t>(num_vertices());
    const auto m = static_cast<std::size_t>(num_elements());
    const bool renumbers = !old_vertex.empty();
    if (renumbers) check_permutation(old_vertex, n, "vertices");
    check_permutation(old_element, m, "elements");
    const std::vector<VertexId> new_id = detail::inverse(old_vertex);  // empty when the ids stay
    const auto name = [&](VertexId v) { return renumbers ? new_id[static_cast<std::size_t>(v)] : v; };
    // Everything new is made before anything is replaced (all or nothing).
    const auto k = static_cast<std::size_t>(corners());
    std::vector<VertexId> connectivity(connectivity_.size());
    {
        // The elements in their new order lie scattered in the old: each is asked for a few ahead.
        const auto ahead = static_cast<std::size_t>(detail::kPrefetchAroundAhead);
        const VertexId* corners = connectivity_.data();
        for (std::size_t i = 0; i < m; ++i) {
            if (i + ahead < m) __builtin_prefetch(corners + k * static_cast<std::size_t>(old_element[i + ahead]));
            const VertexId* old = corners + k * static_cast<std::size_t>(old_element[i]);
            for (std::size_t c = 0; c < k; ++c) connectivity[k * i + c] = name(old[c]);
        }
    }
    std::vector<VertexId> cell_connectivity(cell_connectivity_.size());
    for (std::size_t i = 0; i < cell_connectivity.size(); ++i) cell_connectivity[i] = name(cell_connectivity_[i]);
    auto element_cell = detail::gathered(element_cell_, old_element);
    auto corner_map = detail::gathered(corner_map_, old_element);
    auto target_maps = detail::gathered(target_maps_, old_element);
    auto target_volumes = detail::gathered(target_volumes_, old_element);
    auto target_metric_roots = detail::gathered(target_metric_roots_, old_element);
    auto surface_normals = detail::gathered(surface_normals_, old_element);
    std::vector<double> coordinates, reference_coordinates, target_edge_lengths, target_metrics;
    std::vector<std::uint8_t> fixed, freedom;
    std::vector<GlobalId> global_ids;
    if (renumbers) {
        coordinates = detail::gathered(coordinates_, old_vertex, 3);
        fixed = detail::gathered(fixed_, old_vertex);
        freedom = detail::gathered(freedom_, old_vertex);
        global_ids = detail::gathered(global_ids_, old_vertex);
        reference_coordinates = detail::gathered(reference_coordinates_, old_vertex, 3);
        target_edge_lengths = detail::gathered(target_edge_lengths_, old_vertex);
        target_metrics = detail::gathered(target_metrics_, old_vertex, kMetricValues);
    }
    std::vector<std::int64_t> offsets;
    std::vector<ElementId> around;
    element_rows(connectivity, n, corners(), offsets, around);

    connectivity_ = std::move(connectivity);
    vertex_element_offsets_ = std::move(offsets);
    vertex_elements_ = std::move(around);
    cell_connectivity_ = std::move(cell_connectivity);
    element_cell_ = std::move(element_cell);
    corner_map_ = std::move(corner_map);
    target_maps_ = std::move(target_maps);
    target_volumes_ = std::move(target_volumes);
    target_metric_roots_ = std::move(target_metric_roots);
    surface_normals_ = std::move(surface_normals);
    if (renumbers) {
        coordinates_ = std::move(coordinates);
        fixed_ = std::move(fixed);
        freedom_ = std::move(freedom);
        global_ids_ = std::move(global_ids);
        reference_coordinates_ = std::move(reference_coordinates);
        target_edge_lengths_ = std::move(target_edge_lengths);
        target_metrics_ = std::move(target_metrics);
    }
}

namespace {
bool finite(const CornerMap& a) {
    for (const auto& row : a)
        for (double x : row)
            if (!std::isfinite(x)) return false;
    return true;
}
}  // namespace

void Mesh::set_targets(std::vector<CornerMap> maps, std::vector<double> volumes, std::vector<CornerMap> metric_roots) {
    const auto m = static_cast<std::size_t>(num_elements());
    if (maps.size() != m || volumes.size() != m || (!metric_roots.empty() && metric_roots.size() != m))
        throw MeshError("targets: " + std::to_string(maps.size()) + " maps, " + std::to_string(volumes.size()) +
                        " volumes and " + std::to_string(metric_roots.size()) + " metric roots given for " +
                        std::to_string(m) + " elements");
    const int d = kind_ == ElementKind::Tetrahedron ? 3 : 2;
    for (std::size_t e = 0; e < m; ++e) {
        const CornerMap& a = maps[e];
        const double det = detail::determinant(a, d);
        if (!finite(a) || !(det > 0.0))
            throw MeshError("target of element " + std::to_string(e) + ": its map is " +
                            (finite(a) ? "not orientation-preserving" : "not finite"));
        if (!metric_roots.empty() && !(finite(metric_roots[e]) && detail::determinant(metric_roots[e], 3) > 0.0))
            throw MeshError("target of element " + std::to_string(e) + ": its metric root is not finite and orientation-preserving");
        if (!(volumes[e] > 0.0) || !std::isfinite(volumes[e]))
            throw MeshError("target of element " + std::to_string(e) + ": its volume " + std::to_string(volumes[e]) +
                            " is not a finite positive number");
    }
    target_maps_ = std::move(maps);
    target_volumes_ = std::move(volumes);
    target_metric_roots_ = std::move(metric_roots);
}

void Mesh::clear_targets() noexcept {
    target_maps_.clear();
    target_volumes_.clear();
    target_metric_roots_.clear();
}

void Mesh::set_surface_normals(std::vector<Vec3> normals) {
    if (kind_ != ElementKind::Triangle) throw MeshError("surface normals are for triangle meshes");
    if (normals.size() != static_cast<std::size_t>(num_elements()))
        throw MeshError("surface normals: " + std::to_string(normals.size()) + " given for " +
                        std::to_string(num_elements()) + " triangles");
    for (std::size_t e = 0; e < normals.size(); ++e) {
        const Vec3& n = normals[e];
        const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!std::isfinite(length) || std::abs(length - 1.0) > 1e-9)
            throw MeshError("surface normals: triangle " + std::to_string(e) + "'s normal is not a unit vector");
    }
    surface_normals_ = std::move(normals);
}

void Mesh::set_reference_coordinates(std::vector<double> xyz) {
    if (xyz.size() != coordinates_.size())
        throw MeshError("reference coordinates: " + std::to_string(xyz.size() / 3) + " points given for " +
                        std::to_string(num_vertices()) + " vertices");
    for (std::size_t i = 0; i < xyz.size(); ++i)
        if (!std::isfinite(xyz[i]))
            throw MeshError("reference coordinates: vertex " + std::to_string(i / 3) + " has a coordinate that is not finite");
    reference_coordinates_ = std::move(xyz);
}

void Mesh::set_target_edge_lengths(std::vector<double> lengths) {
    if (lengths.size() != static_cast<std::size_t>(num_vertices()))
        throw MeshError("target edge lengths: " + std::to_string(lengths.size()) + " given for " +
                        std::to_string(num_vertices()) + " vertices");
    for (std::size_t v = 0; v < lengths.size(); ++v)
        if (!(lengths[v] > 0.0) || !std::isfinite(lengths[v]))
            throw MeshError("target edge lengths: vertex " + std::to_string(v) + " has " + std::to_string(lengths[v]) +
                            ", not a finite positive length");
    target_edge_lengths_ = std::move(lengths);
}

void Mesh::set_target_metrics(std::vector<double> metrics) {
    if (metrics.size() != static_cast<std::size_t>(num_vertices()) * kMetricValues)
        throw MeshError("target metrics: " + std::to_string(metrics.size()) + " values given for " +
                        std::to_string(num_vertices()) + " vertices (6 each: xx, yy, zz, xy, yz, xz)");
    for (std::size_t v = 0; v < metrics.size() / kMetricValues; ++v) {
        const double* m = metrics.data() + kMetricValues * v;
        const bool finite = std::all_of(m, m + kMetricValues, [](double x) { return std::isfinite(x); });
        // Sylvester's criterion on [[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]. A planar mesh's
        // metric is checked in its plane when targets are set.
        const double minor2 = m[0] * m[1] - m[3] * m[3];
        const double det = m[0] * (m[1] * m[2] - m[4] * m[4]) - m[3] * (m[3] * m[2] - m[4] * m[5]) +
                           m[5] * (m[3] * m[4] - m[1] * m[5]);
        if (!finite || (kind_ == ElementKind::Tetrahedron && !(m[0] > 0.0 && minor2 > 0.0 && det > 0.0)))
            throw MeshError("target metrics: vertex " + std::to_string(v) + " has a matrix that is not " +
                            (finite ? "positive definite" : "finite"));
    }
    target_metrics_ = std::move(metrics);
}

void Mesh::scale(int exponent) {
    scale_coordinates(coordinates_, exponent);
    scale_coordinates(reference_coordinates_, exponent);
    for (double& h : target_edge_lengths_) h = std::ldexp(h, exponent);
    for (double& m : target_metrics_) m = std::ldexp(m, -2 * exponent);  // lengths scale, M by 1 / length^2
    const int d = kind_ == ElementKind::Tetrahedron ? 3 : 2;
    for (double& v : target_volumes_) v = std::ldexp(v, d * exponent);
}

Mesh Mesh::copy_of(const MeshInterface& source) {
    const auto n = static_cast<VertexId>(source.vertex_count());
    const auto m = static_cast<ElementId>(source.element_count());
    std::vector<VertexId> vertices(static_cast<std::size_t>(n));
    std::iota(vertices.begin(), vertices.end(), VertexId{0});
    std::vector<ElementId> elements(static_cast<std::size_t>(m));
    std::iota(elements.begin(), elements.end(), ElementId{0});
    std::vector<double> xyz(3 * vertices.size());
    source.get_coordinates(vertices, xyz);
    std::vector<VertexId> connectivity(elements.size() * corner_count(source.element_kind()));
    source.get_connectivity(elements, connectivity);
    std::vector<std::uint8_t> fixed(vertices.size());
    source.get_fixed(vertices, fixed);
    Mesh mesh(source.element_kind(), std::move(xyz), std::move(connectivity));
    mesh.set_fixed(std::move(fixed));
    return mesh;
}

void Mesh::build_adjacency() {
    element_rows(connectivity_, static_cast<std::size_t>(num_vertices()), corners(), vertex_element_offsets_,
                 vertex_elements_);
}

void Mesh::find_plane() {
    planar_ = false;
    plane_normal_ = {0.0, 0.0, 1.0};
    if (kind_ != ElementKind::Triangle || num_elements() == 0) return;
    // At unit scale (an exact power-of-two rescaling, which changes no direction): near 1e300 the
    // cross products would overflow, near 1e-300 underflow to zero.
    const int scale = unit_scale_exponent(coordinates_);
    auto scaled = [&](VertexId v) {
        const Vec3 p = point(v);
        return Vec3{std::ldexp(p[0], scale), std::ldexp(p[1], scale), std::ldexp(p[2], scale)};
    };
    // The area-weighted normal: inverted triangles subtract, so a tangled but mostly valid planar
    // mesh keeps the orientation of its majority.
    Vec3 sum{0.0, 0.0, 0.0};
    for (ElementId e = 0; e < num_elements(); ++e) {
        const auto c = element(e);
        const Vec3 a = scaled(c[0]), b = scaled(c[1]), d = scaled(c[2]);
        const Vec3 u{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w{d[0] - a[0], d[1] - a[1], d[2] - a[2]};
        sum[0] += u[1] * w[2] - u[2] * w[1];
        sum[1] += u[2] * w[0] - u[0] * w[2];
        sum[2] += u[0] * w[1] - u[1] * w[0];
    }
    // The sum is normalized at unit scale too: when the coordinates span a wide range, the areas
    // of the small triangles are tiny even at unit scale, and their squares would underflow.
    scale_coordinates(sum, unit_scale_exponent(sum));
    const double length = std::sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
    Vec3 lo = scaled(0), hi = lo;
    for (VertexId v = 0; v < num_vertices(); ++v) {
        const Vec3 p = scaled(v);
        for (int i = 0; i < 3; ++i) {
            lo[i] = std::min(lo[i], p[i]);
            hi[i] = std::max(hi[i], p[i]);
        }
    }
    const double diagonal = std::hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
    if (!(length > 0.0) || !(diagonal > 0.0)) return;
    Vec3 normal{sum[0] / length, sum[1] / length, sum[2] / length};
    // Snap to an axis when the mesh lies in a coordinate plane, so orientation there is exact.
    for (int i = 0; i < 3; ++i)
        if (std::abs(normal[i]) > 1.0 - 1e-12) {
            normal = {0.0, 0.0, 0.0};
            normal[i] = sum[i] > 0 ? 1.0 : -1.0;
        }
    const Vec3 origin = scaled(connectivity_[0]);
    // Coordinates often come from single-precision files: allow float rounding, nothing more.
    const double tolerance = 1e-6 * diagonal;
    for (VertexId v = 0; v < num_vertices(); ++v) {
        if (vertex_element_offsets_[v] == vertex_element_offsets_[v + 1]) continue;
        const Vec3 p = scaled(v);
        double distance = 0.0;
        for (int i = 0; i < 3; ++i) distance += (p[i] - origin[i]) * normal[i];
        if (std::abs(distance) > tolerance) return;
    }
    planar_ = true;
    plane_normal_ = normal;
}

void Mesh::flip_elements() {
    // A target is a map of the corners in their order: flipped corners would need other maps.
    if (has_targets()) throw MeshError("the elements of a mesh with targets cannot be flipped: orient it first");
    const auto k = static_cast<std::size_t>(corners());
    if (has_cells()) {
        for (std::size_t c = 0; c < cell_types_.size(); ++c) {
            const CellInfo& info = cell_info(cell_types_[c]);
            VertexId* v = cell_connectivity_.data() + cell_offsets_[c];
            std::array<VertexId, kMaxCellCorners> old{};
            std::copy_n(v, info.corners, old.begin());
            for (int i = 0; i < info.corners; ++i) v[i] = old[info.mirror[i]];
        }
        for (std::size_t e = 0; e < element_cell_.size(); ++e) {
            const auto c = static_cast<std::size_t>(element_cell_[e]);
            const CellType type = cell_types_[c];
            const auto& frame = cell_info(type).frames[corner_map_[e] - corner_map_id(type, 0)];
            for (std::size_t i = 0; i < k; ++i)
                connectivity_[e * k + i] = cell_connectivity_[static_cast<std::size_t>(cell_offsets_[c]) + frame[i]];
        }
        build_adjacency();
    } else {
        for (std::size_t first = 0; first < connectivity_.size(); first += k)
            std::swap(connectivity_[first + k - 2], connectivity_[first + k - 1]);
    }
    // Every cross product of find_plane() changes sign, exactly, and so does their sum.
    if (planar_)
        for (double& c : plane_normal_) c = -c;
    // Likewise each triangle's surface normal, so that every triangle keeps its orientation.
    for (Vec3& n : surface_normals_)
        for (double& c : n) c = -c;
}

void Mesh::set_fixed(std::vector<std::uint8_t> fixed) {
    if (fixed.size() != static_cast<std::size_t>(num_vertices()))
        throw MeshError("fixed flags: " + std::to_string(fixed.size()) + " given for " +
                        std::to_string(num_vertices()) + " vertices");
    fixed_ = std::move(fixed);
    freedom_.clear();
}

void Mesh::set_degrees_of_freedom(std::vector<std::uint8_t> freedom) {
    if (freedom.size() != static_cast<std::size_t>(num_vertices()))
        throw MeshError("degrees of freedom: " + std::to_string(freedom.size()) + " given for " +
                        std::to_string(num_vertices()) + " vertices");
    std::vector<std::uint8_t> fixed(freedom.size());
    for (std::size_t v = 0; v < freedom.size(); ++v) {
        if (freedom[v] > 3)
            throw MeshError("vertex " + std::to_string(v) + ": " + std::to_string(freedom[v]) +
                            " degrees of freedom (at most 3)");
        fixed[v] = freedom[v] == 0;
    }
    set_fixed(std::move(fixed));
    if (std::any_of(freedom.begin(), freedom.end(), [](std::uint8_t d) { return d == 1 || d == 2; }))
        freedom_ = std::move(freedom);
}

void Mesh::fix_boundary() { set_fixed(boundary_vertices(*this)); }

VertexId Mesh::num_free_vertices() const noexcept {
    VertexId count = 0;
    for (VertexId v = 0; v < num_vertices(); ++v) count += can_move(v);
    return count;
}

void Mesh::set_global_ids(std::vector<GlobalId> ids) {
    if (ids.size() != static_cast<std::size_t>(num_vertices()))
        throw MeshError("global ids: " + std::to_string(ids.size()) + " given for " + std::to_string(num_vertices()) +
                        " vertices");
    global_ids_ = std::move(ids);
}

void Mesh::get_coordinates(std::span<const VertexId> vertices, std::span<double> xyz) const {
    for (std::size_t i = 0; i < vertices.size(); ++i)
        for (int c = 0; c < 3; ++c) xyz[3 * i + c] = coordinates_[3 * static_cast<std::size_t>(vertices[i]) + c];
}

void Mesh::set_coordinates(std::span<const VertexId> vertices, std::span<const double> xyz) {
    for (std::size_t i = 0; i < vertices.size(); ++i)
        for (int c = 0; c < 3; ++c) coordinates_[3 * static_cast<std::size_t>(vertices[i]) + c] = xyz[3 * i + c];
}

void Mesh::get_connectivity(std::span<const ElementId> elements, std::span<VertexId> out) const {
    const int k = corners();
    for (std::size_t i = 0; i < elements.size(); ++i)
        for (int c = 0; c < k; ++c) out[i * k + c] = connectivity_[static_cast<std::size_t>(elements[i]) * k + c];
}

void Mesh::get_fixed(std::span<const VertexId> vertices, std::span<std::uint8_t> out) const {
    for (std::size_t i = 0; i < vertices.size(); ++i) out[i] = fixed_[static_cast<std::size_t>(vertices[i])];
}

int unit_scale_exponent(std::span<const double> xyz) {
    double largest = 0.0;
    for (double x : xyz) largest = std::max(largest, std::abs(x));
    return largest > 0.0 && std::isfinite(largest) ? -std::ilogb(largest) : 0;
}

void scale_coordinates(std::span<double> xyz, int exponent) {
    if (exponent == 0) return;
    for (double& x : xyz) x = std::ldexp(x, exponent);
}

namespace {
// check_no_duplicate_elements for a mesh of triangles or tetrahedra: the same rows, each key the
// row's other corners (increasing) and the element packed into two words, so a row sorts as pairs
// of integers in the general keys' order, and a tetrahedron's corners sort by a fixed network of
// compare-and-swaps rather than by branches that mispredict at nearly every element.
void check_no_duplicate_simplices(const Mesh& mesh) {
    const auto n = static_cast<std::size_t>(mesh.num_vertices());
    const auto m = static_cast<std::size_t>(mesh.num_elements());
    const auto k = static_cast<std::size_t>(mesh.corners());
    const VertexId* corners = mesh.connectivity().data();
    auto sorted = [&](std::size_t e) {
        std::array<VertexId, 4> c{0, 0, 0, 0};
        std::copy(corners + k * e, corners + k * e + k, c.begin());
        auto order = [&](std::size_t a, std::size_t b) {
            const VertexId low = std::min(c[a], c[b]), high = std::max(c[a], c[b]);
            c[a] = low, c[b] = high;
        };
        if (k == 4) order(0, 1), order(2, 3), order(0, 2), order(1, 3), order(1, 2);
        else order(0, 1), order(1, 2), order(0, 1);
        return c;
    };
    auto smallest = [&](std::size_t e) {
        VertexId low = corners[k * e];
        for (std::size_t j = 1; j < k; ++j) low = std::min(low, corners[k * e + j]);
        return static_cast<std::size_t>(low);
    };
    std::vector<std::int64_t> row(n + 1, 0);
    for (std::size_t e = 0; e < m; ++e) ++row[smallest(e) + 1];
    std::partial_sum(row.begin(), row.end(), row.begin());
    std::vector<ElementId> listed(m);
    std::vector<std::int64_t> next(row.begin(), row.end() - 1);
    for (std::size_t e = 0; e < m; ++e) listed[static_cast<std::size_t>(next[smallest(e)]++)] = static_cast<ElementId>(e);
    auto word = [](VertexId high, std::int64_t low) {
        return static_cast<std::uint64_t>(static_cast<std::uint32_t>(high)) << 32 | static_cast<std::uint32_t>(low);
    };
    std::vector<std::pair<std::uint64_t, std::uint64_t>> keys;
    const auto ahead = static_cast<std::size_t>(detail::kPrefetchAroundAhead);
    for (std::size_t v = 0; v < n; ++v) {
        if (row[v + 1] - row[v] < 2) continue;
        keys.clear();
        for (std::int64_t i = row[v]; i < row[v + 1]; ++i) {
            const auto at = static_cast<std::size_t>(i);
            if (at + ahead < m) __builtin_prefetch(corners + k * static_cast<std::size_t>(listed[at + ahead]));
            const ElementId e = listed[at];
            const auto c = sorted(static_cast<std::size_t>(e));  // c[0] is v
            keys.emplace_back(word(c[1], c[2]), word(k == 4 ? c[3] : 0, e));
        }
        std::sort(keys.begin(), keys.end());
        for (std::size_t i = 0; i + 1 < keys.size(); ++i)
            if (keys[i + 1].first == keys[i].first && keys[i + 1].second >> 32 == keys[i].second >> 32)
                throw MeshError("elements " + std::to_string(keys[i].second & 0xFFFFFFFFu) + " and " +
                                std::to_string(keys[i + 1].second & 0xFFFFFFFFu) +
                                " have the same vertices (duplicate element)");
    }
}
}  // namespace

void check_no_duplicate_elements(const Mesh& mesh) {
    if (!mesh.has_cells()) return check_no_duplicate_simplices(mesh);
    struct Key {
        std::array<VertexId, kMaxCellCorners> corners;
        ElementId element;
    };
    // Cells with the same vertices have the same smallest one: each cell is listed at its smallest
    // vertex (rows counted first) and only these short rows are compared, their keys built and
    // sorted one row at a time. That orders them as one sort of all keys would, so the pair named
    // is the same; and only the row's keys, not all of them, pass through memory.
    const auto n = static_cast<std::size_t>(mesh.num_vertices());
    const ElementId m = mesh.num_cells();
    auto smallest = [&](ElementId e) {
        const auto cell = mesh.cell(e);
        return static_cast<std::size_t>(*std::min_element(cell.begin(), cell.end()));
    };
    std::vector<std::int64_t> row(n + 1, 0);
    for (ElementId e = 0; e < m; ++e) ++row[smallest(e) + 1];
    std::partial_sum(row.begin(), row.end(), row.begin());
    std::vector<ElementId> listed(static_cast<std::size_t>(m));
    std::vector<std::int64_t> next(row.begin(), row.end() - 1);
    for (ElementId e = 0; e < m; ++e) listed[static_cast<std::size_t>(next[smallest(e)]++)] = e;
    std::vector<Key> keys;
    for (std::size_t v = 0; v < n; ++v) {
        if (row[v + 1] - row[v] < 2) continue;
        keys.clear();
        for (std::int64_t i = row[v]; i < row[v + 1]; ++i) {
            const ElementId e = listed[static_cast<std::size_t>(i)];
            const auto cell = mesh.cell(e);
            Key& key = keys.emplace_back();
            key.corners.fill(-1);
            std::copy(cell.begin(), cell.end(), key.corners.begin());
            std::sort(key.corners.begin(), key.corners.begin() + static_cast<std::ptrdiff_t>(cell.size()));
            key.element = e;
        }
        std::sort(keys.begin(), keys.end(), [](const Key& a, const Key& b) {
            return a.corners != b.corners ? a.corners < b.corners : a.element < b.element;
        });
        for (std::size_t i = 0; i + 1 < keys.size(); ++i)
            if (keys[i + 1].corners == keys[i].corners)
                throw MeshError(std::string(mesh.has_cells() ? "cells " : "elements ") + std::to_string(keys[i].element) +
                                " and " + std::to_string(keys[i + 1].element) + " have the same vertices (duplicate element)");
    }
}

std::vector<std::uint8_t> boundary_vertices(ElementKind kind, std::span<const VertexId> connectivity,
                                            VertexId num_vertices) {
    std::vector<std::uint8_t> boundary(static_cast<std::size_t>(num_vertices), 0);
    const int k = corner_count(kind);
    const int face_size = k - 1;
    // Each face (the element minus one corner) as a sorted tuple; a face seen once is on the boundary.
    std::vector<std::array<VertexId, 3>> faces;
    faces.reserve(connectivity.size());
    for (std::size_t e = 0; e < connectivity.size(); e += k)
        for (int skip = 0; skip < k; ++skip) {
            std::array<VertexId, 3> face{0, 0, -1};
            int f = 0;
            for (int i = 0; i < k; ++i)
                if (i != skip) face[f++] = connectivity[e + i];
            // Sort the 2 or 3 ids in place (a triangle's edge keeps -1 last).
            if (face[0] > face[1]) std::swap(face[0], face[1]);
            if (face_size == 3) {
                if (face[1] > face[2]) std::swap(face[1], face[2]);
                if (face[0] > face[1]) std::swap(face[0], face[1]);
            }
            faces.push_back(face);
        }
    std::sort(faces.begin(), faces.end());
    for (std::size_t i = 0; i < faces.size();) {
        std::size_t j = i + 1;
        while (j < faces.size() && faces[j] == faces[i]) ++j;
        if (j - i == 1)
            for (int c = 0; c < face_size; ++c) boundary[faces[i][c]] = 1;
        i = j;
    }
    return boundary;
}

std::vector<CellFace> sorted_cell_faces(const Mesh& mesh) {
    std::vector<CellFace> faces;
    for (ElementId c = 0; c < mesh.num_cells(); ++c) {
        const auto cell = mesh.cell(c);
        for (const auto& local : cell_info(mesh.cell_type(c)).faces) {
            CellFace face{{-1, -1, -1, -1}, c};
            auto& v = face.vertices;
            int size = 0;
            while (size < 4 && local[size] >= 0) v[size] = cell[local[size]], ++size;
            for (int i = 1; i < size; ++i)  // insertion sort of 2 to 4 ids
                for (int j = i; j > 0 && v[j - 1] > v[j]; --j) std::swap(v[j - 1], v[j]);
            faces.push_back(face);
        }
    }
    std::sort(faces.begin(), faces.end());
    return faces;
}

std::vector<std::uint8_t> boundary_vertices(const Mesh& mesh) {
    if (!mesh.has_cells()) return boundary_vertices(mesh.kind(), mesh.connectivity(), mesh.num_vertices());
    // A face of one cell is on the boundary.
    const std::vector<CellFace> faces = sorted_cell_faces(mesh);
    std::vector<std::uint8_t> boundary(static_cast<std::size_t>(mesh.num_vertices()), 0);
    for (std::size_t i = 0; i < faces.size();) {
        std::size_t j = i + 1;
        while (j < faces.size() && faces[j].vertices == faces[i].vertices) ++j;
        if (j - i == 1)
            for (VertexId v : faces[i].vertices)
                if (v >= 0) boundary[v] = 1;
        i = j;
    }
    return boundary;
}

std::string describe_cells(const Mesh& mesh) {
    std::array<ElementId, kCellTypeCount> count{};
    for (ElementId c = 0; c < mesh.num_cells(); ++c) ++count[static_cast<std::size_t>(mesh.cell_type(c))];
    const auto types = std::count_if(count.begin(), count.end(), [](ElementId n) { return n > 0; });
    if (types <= 1) return std::string(cell_info(mesh.cell_type(0)).name) + " mesh";
    std::string out = "mixed mesh:";
    for (const CellInfo& info : all_cell_infos()) {
        const ElementId n = count[static_cast<std::size_t>(info.type)];
        if (n == 0) continue;
        // Every name takes an s but the two Greek ones: hexahedra, tetrahedra.
        std::string name(info.name);
        if (n > 1 && name.ends_with("hedron")) name.replace(name.size() - 2, 2, "a");
        else if (n > 1) name += "s";
        out += (out.back() == ':' ? " " : ", ") + std::to_string(n) + " " + name;
    }
    return out;
}

}  // namespace paloverde
