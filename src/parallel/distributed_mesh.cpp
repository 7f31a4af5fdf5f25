#include "paloverde/parallel/distributed_mesh.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>
#include <type_traits>

#include "paloverde/core/error.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/renumber.hpp"
#include "paloverde/parallel/partition.hpp"
#include "core/permutation.hpp"
#include "parallel/collective.hpp"
#include "parallel/exchange.hpp"
#include "parallel/mpi_support.hpp"
#include "parallel/parts.hpp"
#include "parallel/pieces.hpp"

namespace paloverde {

namespace {

using namespace parallel;
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// The whole mesh's canonical orders, for split().
struct CanonicalOrders {
    std::vector<GlobalId> vertex;   // per vertex: its canonical id
    // Per element its canonical position; for a mesh with cells, per corner in from_cells order
    // (cell by cell, frame by frame), whatever order the mesh holds its elements in.
    std::vector<GlobalId> element;
    std::vector<GlobalId> cell;               // a mesh with cells: per cell, its canonical position
    std::vector<std::int64_t> first_corner;   // a mesh with cells: per cell, its first corner in `element`
};

CanonicalOrders canonical_orders(const Mesh& whole, std::vector<GlobalId> canonical) {
    CanonicalOrders orders;
    orders.element = canonical_element_positions(whole, canonical);
    if (whole.has_cells()) {
        const ElementId cells = whole.num_cells();
        orders.first_corner.assign(static_cast<std::size_t>(cells) + 1, 0);
        for (ElementId c = 0; c < cells; ++c)
            orders.first_corner[c + 1] = orders.first_corner[c] + static_cast<std::int64_t>(cell_info(whole.cell_type(c)).frames.size());
        std::vector<GlobalId> by_corner(orders.element.size());
        for (ElementId e = 0; e < whole.num_elements(); ++e) {
            const ElementId c = whole.cell_of(e);
            const CellType type = whole.cell_type(c);
            const int frame = whole.corner_maps()[e] - corner_map_id(type, 0);
            by_corner[static_cast<std::size_t>(orders.first_corner[c] + frame)] = orders.element[e];
        }
        orders.element = std::move(by_corner);
        std::vector<std::int64_t> keys;
        keys.reserve(static_cast<std::size_t>(cells) * kCellKeyWidth);
        for (ElementId c = 0; c < cells; ++c) append_cell_key(whole.cell_type(c), whole.cell(c), canonical, keys);
        std::int64_t distinct = 0;
        orders.cell = key_positions(keys, kCellKeyWidth, distinct);
    }
    orders.vertex = std::move(canonical);
    return orders;
}

// Rank 0: splits the whole mesh into the ranks' parts. Each part holds the cells (the elements,
// without cells) that touch a vertex it owns.
std::vector<PartArrays> split(const Mesh& whole, const CanonicalOrders& orders, std::span<const int> part, int ranks) {
    const bool with_cells = whole.has_cells();
    const std::span<const GlobalId> canonical = orders.vertex;
    // Each part's cells, counted first so that each list is allocated once.
    std::vector<int> touching;
    auto parts_touching = [&](ElementId c) {
        touching.clear();
        for (VertexId v : whole.cell(c)) touching.push_back(part[v]);
        std::sort(touching.begin(), touching.end());
        touching.erase(std::unique(touching.begin(), touching.end()), touching.end());
        return std::span<const int>(touching);
    };
    struct Sizes {
        std::size_t cells = 0, ids = 0, corners = 0;
    };
    std::vector<Sizes> sizes(static_cast<std::size_t>(ranks));
    for (ElementId c = 0; c < whole.num_cells(); ++c)
        for (int p : parts_touching(c)) {
            ++sizes[p].cells;
            sizes[p].ids += whole.cell(c).size();
            sizes[p].corners += with_cells ? cell_info(whole.cell_type(c)).frames.size() : 1;
        }
    std::vector<std::vector<ElementId>> cells(static_cast<std::size_t>(ranks));
    for (int p = 0; p < ranks; ++p) cells[p].reserve(sizes[p].cells);
    for (ElementId c = 0; c < whole.num_cells(); ++c)
        for (int p : parts_touching(c)) cells[p].push_back(c);
    std::vector<PartArrays> parts(static_cast<std::size_t>(ranks));
    std::vector<VertexId> local(static_cast<std::size_t>(whole.num_vertices()), -1);
    for (int p = 0; p < ranks; ++p) {
        std::vector<VertexId> vertices;  // each once (marked in `local`), then in canonical order
        for (ElementId c : cells[p])
            for (VertexId v : whole.cell(c))
                if (local[v] < 0) local[v] = 0, vertices.push_back(v);
        for (VertexId v = 0; v < whole.num_vertices(); ++v)
            if (part[v] == p && whole.elements_of(v).empty()) vertices.push_back(v);  // isolated vertices
        std::sort(vertices.begin(), vertices.end(), [&](VertexId a, VertexId b) { return canonical[a] < canonical[b]; });
        PartArrays& out = parts[p];
        // Sized up front: growing them would leave freed blocks behind on rank 0, which holds
        // the whole mesh too.
        out.coordinates.reserve(3 * vertices.size());
        out.fixed.reserve(vertices.size());
        if (!whole.reference_coordinates().empty()) out.reference.reserve(3 * vertices.size());
        if (!whole.target_edge_lengths().empty()) out.edge_lengths.reserve(vertices.size());
        if (!whole.target_metrics().empty()) out.metrics.reserve(Mesh::kMetricValues * vertices.size());
        out.canonical.reserve(vertices.size());
        out.owner.reserve(vertices.size());
        (with_cells ? out.cell_connectivity : out.connectivity).reserve(sizes[p].ids);
        out.element_order.reserve(sizes[p].corners);
        if (with_cells) out.cell_types.reserve(sizes[p].cells), out.cell_order.reserve(sizes[p].cells);
        for (std::size_t i = 0; i < vertices.size(); ++i) {
            const VertexId v = vertices[i];
            local[v] = static_cast<VertexId>(i);
            for (int c = 0; c < 3; ++c) out.coordinates.push_back(whole.coordinates()[3 * static_cast<std::size_t>(v) + c]);
            out.fixed.push_back(whole.fixed()[v]);
            if (!whole.reference_coordinates().empty())
                for (int c = 0; c < 3; ++c) out.reference.push_back(whole.reference_coordinates()[3 * static_cast<std::size_t>(v) + c]);
            if (!whole.target_edge_lengths().empty()) out.edge_lengths.push_back(whole.target_edge_lengths()[static_cast<std::size_t>(v)]);
            if (!whole.target_metrics().empty())
                for (int c = 0; c < Mesh::kMetricValues; ++c)
                    out.metrics.push_back(whole.target_metrics()[Mesh::kMetricValues * static_cast<std::size_t>(v) + c]);
            out.canonical.push_back(canonical[v]);
            out.owner.push_back(part[v]);
        }
        for (ElementId c : cells[p]) {
            for (VertexId v : whole.cell(c)) (with_cells ? out.cell_connectivity : out.connectivity).push_back(local[v]);
            if (!with_cells) {
                out.element_order.push_back(orders.element[c]);
                continue;
            }
            out.cell_types.push_back(static_cast<std::uint8_t>(whole.cell_type(c)));
            out.cell_order.push_back(orders.cell[c]);
            out.element_order.insert(out.element_order.end(), orders.element.begin() + orders.first_corner[c],
                                     orders.element.begin() + orders.first_corner[c + 1]);
        }
        for (VertexId v : vertices) local[v] = -1;
        std::vector<ElementId>().swap(cells[p]);
    }
    return parts;
}

// The whole mesh cut into parts: canonical order, METIS, the parts' arrays.
struct WholeSplit {
    std::vector<PartArrays> parts;
    std::vector<VertexId> original_vertex;  // canonical id -> index in the whole mesh
};

WholeSplit split_whole(const Mesh& whole, int ranks) {
    if (whole.num_vertices() < ranks)
        throw OptionError("cannot distribute a mesh of " + std::to_string(whole.num_vertices()) + " vertices over " +
                          std::to_string(ranks) + " processes: use at most as many processes as vertices");
    std::vector<VertexId> old_vertex = locality_vertex_order(whole);  // elements get the canonical order
    std::vector<GlobalId> canonical(static_cast<std::size_t>(whole.num_vertices()));
    for (VertexId i = 0; i < whole.num_vertices(); ++i) canonical[old_vertex[i]] = i;
    const CanonicalOrders orders = canonical_orders(whole, std::move(canonical));
    const auto part = partition_vertices(whole, ranks);
    return {split(whole, orders, part, ranks), std::move(old_vertex)};
}


// Collective: each of this rank's keys' canonical position among the keys of all ranks (copies
// merged), and the number of distinct keys, on every rank.
std::vector<GlobalId> canonical_positions(MPI_Comm comm, const std::vector<std::int64_t>& keys, int width, GlobalId& distinct) {
    int rank = 0;
    MPI_Comm_rank(comm, &rank);
    std::vector<std::int64_t> positions;
    std::vector<int> counts;
    distinct = 0;
    {
        const auto all = gather_to_root(comm, keys);
        if (rank == 0) {
            positions = key_positions(all.values, width, distinct);
            for (int c : all.counts) counts.push_back(c / width);
        }
    }
    MPI_Bcast(&distinct, 1, MPI_INT64_T, 0, comm);
    return scatter_from_root(comm, positions, counts, keys.size() / static_cast<std::size_t>(width));
}

// The orientation decision over all pieces: each rank measures the elements it counts, at one
// scale for all, and the exact sums are added across ranks, so every rank decides the same.
OrientationDecision orient_pieces(DistributedMesh& part, OrientationMode mode) {
    const Reducer& reducer = part.reducer();
    const bool oriented =
        part.mesh().kind() == ElementKind::Tetrahedron || reducer.min(part.mesh().is_planar() ? 1.0 : 0.0) > 0.0;
    double largest = 0.0;
    for (double x : part.mesh().coordinates()) largest = std::max(largest, std::abs(x));
    largest = reducer.max(largest);
    SignedMeasure measure;
    if (oriented)
        measure = signed_measure(part.mesh(), part.mesh().coordinates(), unit_scale_exponent(std::span<const double>(&largest, 1)),
                                 part.plane_normal(), part.counted());
    std::array<ExactSum, 3> sums{measure.total, measure.magnitude, measure.rounding};
    reducer.sum(sums);
    const OrientationDecision d = decide_orientation(mode, oriented, {sums[0], sums[1], sums[2]});
    if (d.flipped) {
        part.mesh().flip_elements();
        part.mesh().set_elements_flipped(true);
    }
    return d;
}

}  // namespace

DistributedMesh::DistributedMesh()
    : schedule_(std::make_unique<ExchangeSchedule>()), reducer_(std::make_unique<Reducer>()), halo_(std::make_unique<Halo>()) {}
DistributedMesh::~DistributedMesh() = default;
DistributedMesh::DistributedMesh(DistributedMesh&&) noexcept = default;
DistributedMesh& DistributedMesh::operator=(DistributedMesh&&) noexcept = default;

DistributedMesh DistributedMesh::scatter(MPI_Comm comm, const Mesh* whole, const DistributeOptions& options) {
    options.validate();
    DistributedMesh out;
    out.comm_ = comm;
    MPI_Comm_rank(comm, &out.rank_);
    MPI_Comm_size(comm, &out.ranks_);
    const int ranks = out.ranks_;

    auto start = Clock::now();
    WholeSplit split;
    std::int64_t header[5] = {0, 0, 0, 0, 0};  // kind, global vertices, elements, elements flipped, cells
    double normal[3] = {0.0, 0.0, 1.0};
    parallel::together(comm, out.rank_ == 0, [&] {
        if (!whole) throw OptionError("DistributedMesh::scatter: rank 0 must pass the mesh");
        split = split_whole(*whole, ranks);
        out.original_vertex_ = std::move(split.original_vertex);
        header[0] = static_cast<std::int64_t>(whole->kind());
        header[1] = whole->num_vertices();
        header[2] = whole->num_elements();
        header[3] = whole->elements_flipped() ? 1 : 0;
        header[4] = whole->num_cells();
        normal[0] = whole->plane_normal()[0], normal[1] = whole->plane_normal()[1], normal[2] = whole->plane_normal()[2];
    });
    out.timings_.partition = seconds_since(start);
    start = Clock::now();
    MPI_Bcast(header, 5, MPI_INT64_T, 0, comm);
    MPI_Bcast(normal, 3, MPI_DOUBLE, 0, comm);
    out.global_vertices_ = header[1];
    out.global_elements_ = header[2];
    out.global_cells_ = header[4];
    out.plane_normal_ = {normal[0], normal[1], normal[2]};

    PartArrays mine;
    if (out.rank_ == 0) {
        for (int p = 1; p < ranks; ++p) {
            PartArrays& part = split.parts[p];
            send_vector(part.coordinates, p, 1, comm);
            send_vector(part.fixed, p, 2, comm);
            send_vector(part.canonical, p, 3, comm);
            send_vector(part.owner, p, 4, comm);
            send_vector(part.connectivity, p, 5, comm);
            send_vector(part.element_order, p, 6, comm);
            send_vector(part.cell_types, p, 7, comm);
            send_vector(part.cell_connectivity, p, 8, comm);
            send_vector(part.cell_order, p, 9, comm);
            send_vector(part.reference, p, 10, comm);
            send_vector(part.edge_lengths, p, 11, comm);
            send_vector(part.metrics, p, 12, comm);
            part = {};
        }
        mine = std::move(split.parts[0]);
    } else {
        mine.coordinates = receive_vector<double>(0, 1, comm);
        mine.fixed = receive_vector<std::uint8_t>(0, 2, comm);
        mine.canonical = receive_vector<std::int64_t>(0, 3, comm);
        mine.owner = receive_vector<std::int32_t>(0, 4, comm);
        mine.connectivity = receive_vector<std::int32_t>(0, 5, comm);
        mine.element_order = receive_vector<std::int64_t>(0, 6, comm);
        mine.cell_types = receive_vector<std::uint8_t>(0, 7, comm);
        mine.cell_connectivity = receive_vector<std::int32_t>(0, 8, comm);
        mine.cell_order = receive_vector<std::int64_t>(0, 9, comm);
        mine.reference = receive_vector<double>(0, 10, comm);
        mine.edge_lengths = receive_vector<double>(0, 11, comm);
        mine.metrics = receive_vector<double>(0, 12, comm);
    }
    out.assemble(&mine, static_cast<ElementKind>(header[0]), options.exchange);
    out.mesh_.set_elements_flipped(header[3] != 0);
    out.timings_.distribute = seconds_since(start);
    return out;
}

DistributedMesh DistributedMesh::read_pieces(MPI_Comm comm, const std::filesystem::path& path,
                                             const DistributeOptions& options) {
    options.validate();
    DistributedMesh out;
    out.comm_ = comm;
    MPI_Comm_rank(comm, &out.rank_);
    MPI_Comm_size(comm, &out.ranks_);
    const auto start = Clock::now();
    PartArrays mine;
    ElementKind kind = ElementKind::Tetrahedron;
    parallel::together(comm, true, [&] {
        const auto files = piece_files(path, out.ranks_);
        if (static_cast<int>(files.size()) != out.ranks_)
            throw OptionError(path.string() + " has " + std::to_string(files.size()) + " pieces; run it on as many " +
                              "processes (got " + std::to_string(out.ranks_) + ")");
        mine = read_piece(files[static_cast<std::size_t>(out.rank_)], out.ranks_, kind);
    });
    int kinds[3] = {static_cast<int>(kind), -static_cast<int>(kind), mine.cell_types.empty() ? 0 : 1};
    MPI_Allreduce(MPI_IN_PLACE, kinds, 3, MPI_INT, MPI_MAX, comm);
    agree(comm, kinds[0] != -kinds[1] ? "the pieces of " + path.string() + " mix triangles and tetrahedra" : "");
    const bool cells = kinds[2] != 0;
    // A piece of a mesh with cells that holds only triangles or tetrahedra reads as a simplex
    // mesh: its elements become cells, as the other pieces' are.
    if (cells && mine.cell_types.empty()) {
        mine.cell_types.assign(mine.connectivity.size() / static_cast<std::size_t>(corner_count(kind)),
                               static_cast<std::uint8_t>(simplex_cell(kind)));
        mine.cell_connectivity = std::move(mine.connectivity);
        mine.connectivity.clear();
    }

    // Every global id must be owned exactly once, by the rank whose piece says so.
    std::vector<std::int64_t> owned;
    for (std::size_t v = 0; v < mine.owner.size(); ++v)
        if (mine.owner[v] == out.rank_) owned.push_back(mine.canonical[v]);
    std::string failure;
    {
        const auto all_owned = gather_to_root(comm, owned);
        std::vector<std::int64_t> ids = all_owned.values;
        std::sort(ids.begin(), ids.end());
        for (std::size_t i = 0; i < ids.size() && failure.empty(); ++i)
            if (ids[i] != static_cast<std::int64_t>(i))
                failure = path.string() + ": global vertex id " + std::to_string(i < ids.size() && ids[i] < static_cast<std::int64_t>(i) ? ids[i] : static_cast<std::int64_t>(i)) +
                          (ids[i] < static_cast<std::int64_t>(i) ? " is owned by more than one piece" : " is owned by no piece");
        out.global_vertices_ = static_cast<GlobalId>(ids.size());
    }
    agree(comm, out.rank_ == 0 ? failure : "");
    MPI_Bcast(&out.global_vertices_, 1, MPI_INT64_T, 0, comm);
    out.assemble(&mine, kind, options.exchange);
    // Ghosts must sit where their owners put them.
    std::vector<double> xyz(out.mesh_.coordinates().begin(), out.mesh_.coordinates().end());
    out.halo().update(xyz, 3);
    failure.clear();
    for (VertexId v = 0; v < out.mesh_.num_vertices() && failure.empty(); ++v)
        for (int c = 0; c < 3; ++c)
            if (xyz[3 * static_cast<std::size_t>(v) + c] != out.mesh_.coordinates()[3 * static_cast<std::size_t>(v) + c]) {
                failure = path.string() + ": vertex " + std::to_string(out.mesh_.global_ids()[v]) + " has coordinates in piece " +
                          std::to_string(out.rank_) + " that differ from those in its owner's piece " +
                          std::to_string(out.vertex_owner_[v]);
                break;
            }
    agree(comm, failure);
    // Oriented before the corners' keys are taken: a mirrored cell has other corners.
    out.orientation_ = orient_pieces(out, options.orientation);
    // Canonical positions of the elements (corners) and cells, from their keys.
    {
        const int width = cells ? 5 : 4;  // a corner's map tells corners of two cells apart
        std::vector<std::int64_t> keys;
        keys.reserve(static_cast<std::size_t>(out.mesh_.num_elements()) * static_cast<std::size_t>(width));
        for (ElementId e = 0; e < out.mesh_.num_elements(); ++e) append_element_key(out.mesh_, e, width, keys);
        out.element_order_ = canonical_positions(comm, keys, width, out.global_elements_);
    }
    out.global_cells_ = out.global_elements_;
    if (cells) {
        std::vector<std::int64_t> keys;
        keys.reserve(static_cast<std::size_t>(out.mesh_.num_cells()) * kCellKeyWidth);
        for (ElementId c = 0; c < out.mesh_.num_cells(); ++c)
            append_cell_key(out.mesh_.cell_type(c), out.mesh_.cell(c), out.mesh_.global_ids(), keys);
        out.cell_order_ = canonical_positions(comm, keys, kCellKeyWidth, out.global_cells_);
    }
    // Each element must be counted exactly once: every piece must hold all the elements around
    // the vertices it owns.
    double counted = 0.0;
    for (auto c : out.counted_) counted += c;
    agree(comm, out.reducer().total(counted) != static_cast<double>(out.global_elements_)
                    ? path.string() + ": the pieces do not hold every element around the vertices they own"
                    : "");
    out.timings_.distribute = seconds_since(start);
    return out;
}

void DistributedMesh::assemble(void* arrays, ElementKind kind, ExchangeMode mode) {
    PartArrays& mine = *static_cast<PartArrays*>(arrays);
    static_assert(std::is_same_v<std::int32_t, int>, "the owners are moved, not copied");
    mesh_ = part_mesh(mine, kind);
    vertex_owner_ = std::move(mine.owner);
    element_order_ = std::move(mine.element_order);
    cell_order_ = std::move(mine.cell_order);
    // A cell's corners are counted where the cell is.
    counted_ = per_element(mesh_, counted_cells(mesh_, vertex_owner_, rank_));
    const auto start = Clock::now();
    build_schedule(mode);
    reducer_ = parallel::make_mpi_reducer(comm_);
    halo_ = parallel::make_mpi_halo(comm_, rank_, ranks_, *schedule_);
    timings_.schedule = seconds_since(start);
}

void DistributedMesh::write_pieces(const std::filesystem::path& path) const {
    parallel::together(comm_, true, [&] {
        if (path.extension() == ".pvtu") std::filesystem::create_directories(piece_path(path, rank_).parent_path());
        write_piece(piece_path(path, rank_), mesh_, vertex_owner_, counted_cells(mesh_, vertex_owner_, rank_), rank_,
                    path.extension() != ".pvtu");
        if (rank_ == 0 && path.extension() == ".pvtu") write_pvtu(path, ranks_);
    });
}

void DistributedMesh::write_partitioned(const Mesh& whole, int parts, const std::filesystem::path& path) {
    if (path.extension() != ".pvtu" && path.extension() != ".vtk")
        throw OptionError("pieces are written as OUT.pvtu (with OUT/OUT_<rank>.vtu) or Mesquite-style OUT.vtk "
                          "(OUT_<rank>.vtk); got '" + path.string() + "'");
    WholeSplit split = split_whole(whole, parts);
    if (path.extension() == ".pvtu") std::filesystem::create_directories(piece_path(path, 0).parent_path());
    const ElementKind kind = whole.kind();
    for (int p = 0; p < parts; ++p) {
        PartArrays& arrays = split.parts[p];
        Mesh piece = part_mesh(arrays, kind);
        piece.set_elements_flipped(whole.elements_flipped());
        write_piece(piece_path(path, p), piece, arrays.owner, counted_cells(piece, arrays.owner, p), p,
                    path.extension() != ".pvtu");
        arrays = {};
    }
    if (path.extension() == ".pvtu") write_pvtu(path, parts);
}

BoundaryFacets DistributedMesh::gather_boundary(bool surface) const {
    // A part holds every element around the vertices it owns, so a facet on its boundary with a
    // corner it owns is on the whole mesh's boundary; the owner of its corner with the smallest
    // global id reports it. (The faces where the part was cut have no owned corner.)
    BoundaryFacets local;
    std::string failure;
    try {
        local = BoundaryFacets::of(mesh_, surface);
    } catch (const MeshError& e) {
        failure = e.what();
    }
    agree(comm_, failure);
    const auto global = mesh_.global_ids();
    auto owned = [&](GlobalId v) { return vertex_owner_[static_cast<std::size_t>(v)] == rank_; };
    std::vector<std::int64_t> facets;
    for (const auto& f : local.facets) {
        GlobalId first = f[0];
        for (GlobalId v : f)
            if (v >= 0 && global[v] < global[first]) first = v;
        if (!owned(first)) continue;
        for (GlobalId v : f) facets.push_back(v < 0 ? -1 : global[v]);
    }
    // A cut is reported by the owner of its end with the smaller global id, which holds its cell.
    std::vector<std::int64_t> cuts;
    for (const auto& [a, b] : local.cuts)
        if (owned(global[a] < global[b] ? a : b)) cuts.insert(cuts.end(), {global[a], global[b]});
    std::vector<std::int64_t> ids;
    std::vector<double> xyz;
    for (std::size_t i = 0; i < local.ids.size(); ++i)
        if (owned(local.ids[i])) {
            ids.push_back(global[local.ids[i]]);
            xyz.insert(xyz.end(), local.xyz.begin() + 3 * static_cast<std::ptrdiff_t>(i),
                       local.xyz.begin() + 3 * static_cast<std::ptrdiff_t>(i + 1));
        }
    // The bounding box of all vertices, as the serial mesh's.
    std::array<double, 6> box;
    box.fill(std::numeric_limits<double>::infinity());
    const auto coordinates = mesh_.coordinates();
    for (VertexId v = 0; v < mesh_.num_vertices(); ++v)
        for (int c = 0; c < 3; ++c) {
            const double x = coordinates[3 * static_cast<std::size_t>(v) + c];
            box[c] = std::min(box[c], x);
            box[3 + c] = std::min(box[3 + c], -x);
        }
    MPI_Allreduce(MPI_IN_PLACE, box.data(), 6, MPI_DOUBLE, MPI_MIN, comm_);

    BoundaryFacets out;
    out.kind = mesh_.kind();
    out.surface = surface;
    const auto all_cuts = gather_to_all(comm_, cuts);
    for (std::size_t i = 0; i + 1 < all_cuts.size(); i += 2) out.cuts.push_back({all_cuts[i], all_cuts[i + 1]});
    const auto all_facets = gather_to_all(comm_, facets);
    for (std::size_t i = 0; i + 2 < all_facets.size(); i += 3)
        out.facets.push_back({all_facets[i], all_facets[i + 1], all_facets[i + 2]});
    const auto all_ids = gather_to_all(comm_, ids);
    const auto all_xyz = gather_to_all(comm_, xyz);
    std::vector<std::size_t> order(all_ids.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return all_ids[a] < all_ids[b]; });
    for (std::size_t i : order) {
        out.ids.push_back(all_ids[i]);
        out.xyz.insert(out.xyz.end(), all_xyz.begin() + 3 * static_cast<std::ptrdiff_t>(i),
                       all_xyz.begin() + 3 * static_cast<std::ptrdiff_t>(i + 1));
    }
    const double dx = -box[3] - box[0], dy = -box[4] - box[1], dz = -box[5] - box[2];
    out.diagonal = global_vertices_ > 0 ? std::sqrt(dx * dx + dy * dy + dz * dz) : 0.0;
    return out;
}

void DistributedMesh::update_ghost_coordinates() { halo_->update(mesh_.coordinates(), 3); }

void DistributedMesh::reorder_elements(std::span<const ElementId> order) {
    std::vector<GlobalId> positions = detail::gathered(element_order_, order);
    std::vector<std::uint8_t> flags = detail::gathered(counted_, order);
    mesh_.permute({}, order);  // all or nothing, as the moves after it cannot fail
    element_order_ = std::move(positions);
    counted_ = std::move(flags);
}

std::vector<double> DistributedMesh::gather_vertex_field(std::span<const double> field, int width) const {
    const auto w = static_cast<std::size_t>(width);
    std::vector<double> mine;
    std::vector<std::int64_t> keys;
    const auto ids = mesh_.global_ids();
    for (std::size_t v = 0; v < vertex_owner_.size(); ++v)
        if (vertex_owner_[v] == rank_) {
            keys.push_back(ids[v]);
            for (std::size_t c = 0; c < w; ++c) mine.push_back(field[w * v + c]);
        }
    const int count = static_cast<int>(keys.size());
    std::vector<int> counts(static_cast<std::size_t>(ranks_)), offsets(static_cast<std::size_t>(ranks_));
    MPI_Gather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, comm_);
    std::exclusive_scan(counts.begin(), counts.end(), offsets.begin(), 0);
    const int total = rank_ == 0 ? offsets.back() + counts.back() : 0;
    std::vector<std::int64_t> all_keys(static_cast<std::size_t>(total));
    MPI_Gatherv(keys.data(), count, MPI_INT64_T, all_keys.data(), counts.data(), offsets.data(), MPI_INT64_T, 0, comm_);
    for (int r = 0; r < ranks_; ++r) counts[r] *= width, offsets[r] *= width;
    std::vector<double> values(w * static_cast<std::size_t>(total));
    MPI_Gatherv(mine.data(), width * count, MPI_DOUBLE, values.data(), counts.data(), offsets.data(), MPI_DOUBLE, 0, comm_);
    std::vector<double> out;
    if (rank_ != 0) return out;
    out.assign(w * static_cast<std::size_t>(global_vertices_), 0.0);
    for (std::size_t i = 0; i < all_keys.size(); ++i)
        for (std::size_t c = 0; c < w; ++c) out[w * static_cast<std::size_t>(all_keys[i]) + c] = values[w * i + c];
    return out;
}

void DistributedMesh::broadcast(std::string& bytes) const {
    std::uint64_t size = bytes.size();
    MPI_Bcast(&size, 1, MPI_UINT64_T, 0, comm_);
    bytes.resize(size);
    // Counts of MPI calls are ints: send in pieces.
    for (std::uint64_t at = 0; at < size; at += 1u << 30)
        MPI_Bcast(bytes.data() + at, static_cast<int>(std::min<std::uint64_t>(size - at, 1u << 30)), MPI_CHAR, 0, comm_);
}

void DistributedMesh::on_root(const std::function<void()>& work) const { parallel::together(comm_, rank_ == 0, work); }

// The owned vertices' global ids and coordinates (3 per vertex), in local order.
void DistributedMesh::owned_vertices(std::vector<std::int64_t>& ids, std::vector<double>& xyz) const {
    for (VertexId v = 0; v < mesh_.num_vertices(); ++v)
        if (vertex_owner_[v] == rank_) {
            ids.push_back(mesh_.global_ids()[v]);
            for (int c = 0; c < 3; ++c) xyz.push_back(mesh_.coordinates()[3 * static_cast<std::size_t>(v) + c]);
        }
}

void DistributedMesh::gather_coordinates(Mesh* whole) const {
    std::vector<std::int64_t> ids;
    std::vector<double> xyz;
    owned_vertices(ids, xyz);
    const auto all_ids = gather_to_root(comm_, ids).values;
    const auto all_xyz = gather_to_root(comm_, xyz).values;
    if (rank_ != 0) return;
    if (!whole || static_cast<GlobalId>(whole->num_vertices()) != global_vertices_ ||
        all_ids.size() != static_cast<std::size_t>(global_vertices_))
        throw OptionError("DistributedMesh::gather_coordinates: rank 0 must pass the mesh given to scatter()");
    auto out = whole->coordinates();
    for (std::size_t i = 0; i < all_ids.size(); ++i) {
        const VertexId v = original_vertex_[static_cast<std::size_t>(all_ids[i])];
        for (int c = 0; c < 3; ++c) out[3 * static_cast<std::size_t>(v) + c] = all_xyz[3 * i + c];
    }
}

Mesh DistributedMesh::gather_whole() const {
    // Vertices first, their buffers freed before the elements come: rank 0 holds the gathered
    // arrays of one kind at a time next to the mesh it builds.
    std::vector<double> coordinates;
    std::vector<std::uint8_t> fixed;
    {
        std::vector<std::int64_t> ids;
        std::vector<double> xyz;
        owned_vertices(ids, xyz);
        std::vector<std::int64_t> flags;  // int64 rather than bytes: one gather helper for both
        for (VertexId v = 0; v < mesh_.num_vertices(); ++v)
            if (vertex_owner_[v] == rank_) flags.push_back(mesh_.fixed()[v]);
        const auto all_ids = gather_to_root(comm_, ids).values;
        const auto all_flags = gather_to_root(comm_, flags).values;
        const auto all_xyz = gather_to_root(comm_, xyz).values;
        if (rank_ == 0) {
            coordinates.resize(3 * static_cast<std::size_t>(global_vertices_));
            fixed.resize(static_cast<std::size_t>(global_vertices_));
            for (std::size_t i = 0; i < all_ids.size(); ++i) {
                const auto g = static_cast<std::size_t>(all_ids[i]);
                std::copy_n(all_xyz.begin() + 3 * static_cast<std::ptrdiff_t>(i), 3, coordinates.begin() + 3 * static_cast<std::ptrdiff_t>(g));
                fixed[g] = static_cast<std::uint8_t>(all_flags[i]);
            }
        }
    }
    // Each element (each cell, for a mesh with cells) once, from the rank that counts it: its
    // canonical position, (its type,) then its vertices' ids.
    const bool cells = reducer().max(mesh_.has_cells() ? 1.0 : 0.0) > 0.0;
    std::vector<std::int64_t> records;
    {
        const std::vector<std::uint8_t> counted_cell = cells ? counted_cells(mesh_, vertex_owner_, rank_) : counted_;
        const std::vector<GlobalId>& order = cells ? cell_order_ : element_order_;
        for (ElementId c = 0; c < mesh_.num_cells(); ++c)
            if (counted_cell[c]) {
                records.push_back(order[c]);
                if (cells) records.push_back(static_cast<std::int64_t>(mesh_.cell_type(c)));
                for (VertexId v : mesh_.cell(c)) records.push_back(mesh_.global_ids()[v]);
            }
    }
    auto all_records = gather_to_root(comm_, records).values;
    std::vector<std::int64_t>().swap(records);
    if (rank_ != 0) return {};
    const int k = corner_count(mesh_.kind());
    const std::size_t head = cells ? 2 : 1, units = static_cast<std::size_t>(global_cells_);
    auto vertices_of = [&](std::size_t at) {
        return static_cast<std::size_t>(cells ? cell_info(static_cast<CellType>(all_records[at + 1])).corners : k);
    };
    std::vector<CellType> types;
    std::vector<std::int64_t> offsets;  // a mesh with cells: where each cell's ids start
    if (cells) {
        types.resize(units);
        for (std::size_t at = 0; at < all_records.size(); at += head + vertices_of(at))
            types[static_cast<std::size_t>(all_records[at])] = static_cast<CellType>(all_records[at + 1]);
        offsets.assign(units + 1, 0);
        for (std::size_t c = 0; c < units; ++c) offsets[c + 1] = offsets[c] + cell_info(types[c]).corners;
    }
    std::vector<VertexId> connectivity(cells ? static_cast<std::size_t>(offsets.back()) : units * static_cast<std::size_t>(k));
    for (std::size_t at = 0; at < all_records.size(); at += head + vertices_of(at)) {
        const auto position = static_cast<std::size_t>(all_records[at]);
        const auto first = cells ? static_cast<std::size_t>(offsets[position]) : position * static_cast<std::size_t>(k);
        for (std::size_t i = 0; i < vertices_of(at); ++i) connectivity[first + i] = static_cast<VertexId>(all_records[at + head + i]);
    }
    std::vector<std::int64_t>().swap(all_records);  // before the mesh builds its adjacency
    Mesh whole = cells ? Mesh::from_cells(std::move(coordinates), types, std::move(connectivity))
                              : Mesh(mesh_.kind(), std::move(coordinates), std::move(connectivity));
    whole.set_fixed(std::move(fixed));
    whole.set_elements_flipped(mesh_.elements_flipped());  // written back in the pieces' convention
    return whole;
}

std::int64_t DistributedMesh::received_vertices() const {
    std::int64_t total = 0;
    for (const auto& p : schedule_->partners) total += static_cast<std::int64_t>(p.receive.size());
    return total;
}

std::int64_t DistributedMesh::sent_vertices() const {
    std::int64_t total = 0;
    for (const auto& p : schedule_->partners) total += static_cast<std::int64_t>(p.send.size());
    return total;
}

}  // namespace paloverde
