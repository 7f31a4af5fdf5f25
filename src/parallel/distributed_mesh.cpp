#include "paloverde/parallel/distributed_mesh.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <type_traits>

#include "paloverde/core/error.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/renumber.hpp"
#include "paloverde/parallel/partition.hpp"
#include "parallel/exchange.hpp"
#include "parallel/mpi_support.hpp"
#include "parallel/parts.hpp"
#include "parallel/pieces.hpp"

namespace paloverde {

namespace {

using namespace parallel;
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }









// Rank 0: splits the whole mesh (canonical numbering given by `canonical`) into the ranks' parts.
std::vector<PartArrays> split(const SimplexMesh& whole, std::span<const GlobalId> canonical,
                              std::span<const GlobalId> element_order, std::span<const int> part, int ranks) {
    // Each part's elements, counted first so that each list is allocated once.
    std::vector<int> touching;
    auto parts_touching = [&](ElementId e) {
        touching.clear();
        for (VertexId v : whole.element(e)) touching.push_back(part[v]);
        std::sort(touching.begin(), touching.end());
        touching.erase(std::unique(touching.begin(), touching.end()), touching.end());
        return std::span<const int>(touching);
    };
    std::vector<std::size_t> counts(static_cast<std::size_t>(ranks), 0);
    for (ElementId e = 0; e < whole.num_elements(); ++e)
        for (int p : parts_touching(e)) ++counts[p];
    std::vector<std::vector<ElementId>> elements(static_cast<std::size_t>(ranks));
    for (int p = 0; p < ranks; ++p) elements[p].reserve(counts[p]);
    for (ElementId e = 0; e < whole.num_elements(); ++e)
        for (int p : parts_touching(e)) elements[p].push_back(e);
    std::vector<PartArrays> parts(static_cast<std::size_t>(ranks));
    std::vector<VertexId> local(static_cast<std::size_t>(whole.num_vertices()), -1);
    for (int p = 0; p < ranks; ++p) {
        std::vector<VertexId> vertices;  // each once (marked in `local`), then in canonical order
        for (ElementId e : elements[p])
            for (VertexId v : whole.element(e))
                if (local[v] < 0) local[v] = 0, vertices.push_back(v);
        for (VertexId v = 0; v < whole.num_vertices(); ++v)
            if (part[v] == p && whole.elements_of(v).empty()) vertices.push_back(v);  // isolated vertices
        std::sort(vertices.begin(), vertices.end(), [&](VertexId a, VertexId b) { return canonical[a] < canonical[b]; });
        PartArrays& out = parts[p];
        // Sized up front: growing them would leave freed blocks behind on rank 0, which holds
        // the whole mesh too.
        out.coordinates.reserve(3 * vertices.size());
        out.fixed.reserve(vertices.size());
        out.canonical.reserve(vertices.size());
        out.owner.reserve(vertices.size());
        out.connectivity.reserve(elements[p].size() * static_cast<std::size_t>(whole.corners()));
        out.element_order.reserve(elements[p].size());
        for (std::size_t i = 0; i < vertices.size(); ++i) {
            const VertexId v = vertices[i];
            local[v] = static_cast<VertexId>(i);
            for (int c = 0; c < 3; ++c) out.coordinates.push_back(whole.coordinates()[3 * static_cast<std::size_t>(v) + c]);
            out.fixed.push_back(whole.fixed()[v]);
            out.canonical.push_back(canonical[v]);
            out.owner.push_back(part[v]);
        }
        for (ElementId e : elements[p]) {
            for (VertexId v : whole.element(e)) out.connectivity.push_back(local[v]);
            out.element_order.push_back(element_order[e]);
        }
        for (VertexId v : vertices) local[v] = -1;
        std::vector<ElementId>().swap(elements[p]);
    }
    return parts;
}

// The whole mesh cut into parts: canonical order, METIS, the parts' arrays.
struct WholeSplit {
    std::vector<PartArrays> parts;
    std::vector<VertexId> original_vertex;  // canonical id -> index in the whole mesh
};

WholeSplit split_whole(const SimplexMesh& whole, int ranks) {
    require_simplices(whole, "the mesh");
    if (whole.num_vertices() < ranks)
        throw OptionError("cannot distribute a mesh of " + std::to_string(whole.num_vertices()) + " vertices over " +
                          std::to_string(ranks) + " processes: use at most as many processes as vertices");
    Renumbering order = locality_order(whole);
    std::vector<ElementId>().swap(order.old_element);  // elements get the canonical order instead
    std::vector<GlobalId> canonical(static_cast<std::size_t>(whole.num_vertices()));
    for (VertexId i = 0; i < whole.num_vertices(); ++i) canonical[order.old_vertex[i]] = i;
    const auto element_order = canonical_element_positions(whole, canonical);
    const auto part = partition_vertices(whole, ranks);
    return {split(whole, canonical, element_order, part, ranks), std::move(order.old_vertex)};
}


// The orientation decision over all pieces: each rank measures the elements it counts, at one
// scale for all, and the exact sums are added across ranks, so every rank decides the same.
OrientationDecision orient_pieces(DistributedMesh& part, OrientationMode mode) {
    const Reducer& reducer = part.reducer();
    const bool oriented =
        part.mesh.kind() == ElementKind::Tetrahedron || reducer.min(part.mesh.is_planar() ? 1.0 : 0.0) > 0.0;
    double largest = 0.0;
    for (double x : part.mesh.coordinates()) largest = std::max(largest, std::abs(x));
    largest = reducer.max(largest);
    SignedMeasure measure;
    if (oriented)
        measure = signed_measure(part.mesh, part.mesh.coordinates(), unit_scale_exponent(std::span<const double>(&largest, 1)),
                                 part.plane_normal, part.counted);
    std::array<ExactSum, 3> sums{measure.total, measure.magnitude, measure.rounding};
    reducer.sum(sums);
    const OrientationDecision d = decide_orientation(mode, oriented, {sums[0], sums[1], sums[2]});
    if (d.flipped) {
        part.mesh.flip_elements();
        part.mesh.set_elements_flipped(true);
    }
    return d;
}

}  // namespace

DistributedMesh::DistributedMesh()
    : schedule_(std::make_unique<ExchangeSchedule>()), reducer_(std::make_unique<Reducer>()), halo_(std::make_unique<Halo>()) {}
DistributedMesh::~DistributedMesh() = default;
DistributedMesh::DistributedMesh(DistributedMesh&&) noexcept = default;
DistributedMesh& DistributedMesh::operator=(DistributedMesh&&) noexcept = default;

DistributedMesh DistributedMesh::scatter(MPI_Comm comm, const SimplexMesh* whole, const DistributeOptions& options) {
    options.validate();
    DistributedMesh out;
    out.comm = comm;
    MPI_Comm_rank(comm, &out.rank);
    MPI_Comm_size(comm, &out.ranks);
    const int ranks = out.ranks;

    auto start = Clock::now();
    WholeSplit split;
    std::int64_t header[4] = {0, 0, 0, 0};  // kind, global vertices, global elements, elements flipped
    double normal[3] = {0.0, 0.0, 1.0};
    parallel::together(comm, out.rank == 0, [&] {
        if (!whole) throw OptionError("DistributedMesh::scatter: rank 0 must pass the mesh");
        split = split_whole(*whole, ranks);
        out.original_vertex_ = std::move(split.original_vertex);
        header[0] = static_cast<std::int64_t>(whole->kind());
        header[1] = whole->num_vertices();
        header[2] = whole->num_elements();
        header[3] = whole->elements_flipped() ? 1 : 0;
        normal[0] = whole->plane_normal()[0], normal[1] = whole->plane_normal()[1], normal[2] = whole->plane_normal()[2];
    });
    out.timings.partition = seconds_since(start);
    start = Clock::now();
    MPI_Bcast(header, 4, MPI_INT64_T, 0, comm);
    MPI_Bcast(normal, 3, MPI_DOUBLE, 0, comm);
    out.global_vertices = header[1];
    out.global_elements = header[2];
    out.plane_normal = {normal[0], normal[1], normal[2]};

    PartArrays mine;
    if (out.rank == 0) {
        for (int p = 1; p < ranks; ++p) {
            PartArrays& part = split.parts[p];
            send_vector(part.coordinates, p, 1, comm);
            send_vector(part.fixed, p, 2, comm);
            send_vector(part.canonical, p, 3, comm);
            send_vector(part.owner, p, 4, comm);
            send_vector(part.connectivity, p, 5, comm);
            send_vector(part.element_order, p, 6, comm);
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
    }
    out.assemble(&mine, static_cast<ElementKind>(header[0]), options.exchange);
    out.mesh.set_elements_flipped(header[3] != 0);
    out.timings.distribute = seconds_since(start);
    return out;
}

DistributedMesh DistributedMesh::read_pieces(MPI_Comm comm, const std::filesystem::path& path,
                                             const DistributeOptions& options) {
    options.validate();
    DistributedMesh out;
    out.comm = comm;
    MPI_Comm_rank(comm, &out.rank);
    MPI_Comm_size(comm, &out.ranks);
    const auto start = Clock::now();
    PartArrays mine;
    ElementKind kind = ElementKind::Tetrahedron;
    parallel::together(comm, true, [&] {
        const auto files = piece_files(path, out.ranks);
        if (static_cast<int>(files.size()) != out.ranks)
            throw OptionError(path.string() + " has " + std::to_string(files.size()) + " pieces; run it on as many " +
                              "processes (got " + std::to_string(out.ranks) + ")");
        mine = read_piece(files[static_cast<std::size_t>(out.rank)], out.ranks, kind);
    });
    int kinds[2] = {static_cast<int>(kind), -static_cast<int>(kind)};
    MPI_Allreduce(MPI_IN_PLACE, kinds, 2, MPI_INT, MPI_MAX, comm);
    agree(comm, kinds[0] != -kinds[1] ? "the pieces of " + path.string() + " mix triangles and tetrahedra" : "");

    // Every global id must be owned exactly once, by the rank whose piece says so.
    std::vector<std::int64_t> owned;
    for (std::size_t v = 0; v < mine.owner.size(); ++v)
        if (mine.owner[v] == out.rank) owned.push_back(mine.canonical[v]);
    const auto all_owned = gather_to_root(comm, owned);
    std::int64_t counts[2] = {0, 0};  // vertices, elements
    std::vector<std::int64_t> element_keys;  // sorted global ids per element, padded to 4
    const int k = corner_count(kind);
    for (std::size_t e = 0; e < mine.connectivity.size() / k; ++e) {
        std::array<std::int64_t, 4> key{-1, -1, -1, -1};
        for (int i = 0; i < k; ++i) key[i] = mine.canonical[mine.connectivity[e * k + i]];
        std::sort(key.begin(), key.begin() + k);
        element_keys.insert(element_keys.end(), key.begin(), key.end());
    }
    const auto all_keys = gather_to_root(comm, element_keys);
    std::vector<std::int64_t> positions_flat;
    std::vector<int> key_counts;
    std::string failure;
    if (out.rank == 0) {
        std::vector<std::int64_t> ids = all_owned.values;
        std::sort(ids.begin(), ids.end());
        for (std::size_t i = 0; i < ids.size() && failure.empty(); ++i)
            if (ids[i] != static_cast<std::int64_t>(i))
                failure = path.string() + ": global vertex id " + std::to_string(i < ids.size() && ids[i] < static_cast<std::int64_t>(i) ? ids[i] : static_cast<std::int64_t>(i)) +
                          (ids[i] < static_cast<std::int64_t>(i) ? " is owned by more than one piece" : " is owned by no piece");
        counts[0] = static_cast<std::int64_t>(ids.size());
        // Canonical element positions: the elements' keys sorted, duplicates (copies) merged.
        std::vector<std::array<std::int64_t, 4>> keys(all_keys.values.size() / 4);
        for (std::size_t i = 0; i < keys.size(); ++i)
            std::copy_n(all_keys.values.begin() + 4 * i, 4, keys[i].begin());
        std::vector<std::array<std::int64_t, 4>> unique = keys;
        std::sort(unique.begin(), unique.end());
        unique.erase(std::unique(unique.begin(), unique.end()), unique.end());
        counts[1] = static_cast<std::int64_t>(unique.size());
        for (const auto& key : keys)
            positions_flat.push_back(std::lower_bound(unique.begin(), unique.end(), key) - unique.begin());
        for (int c : all_keys.counts) key_counts.push_back(c / 4);
    }
    agree(comm, out.rank == 0 ? failure : "");
    MPI_Bcast(counts, 2, MPI_INT64_T, 0, comm);
    out.global_vertices = counts[0];
    out.global_elements = counts[1];
    mine.element_order = scatter_from_root(comm, positions_flat, key_counts, element_keys.size() / 4);
    out.assemble(&mine, kind, options.exchange);
    // Each element must be counted exactly once: every piece must hold all the elements around
    // the vertices it owns.
    double counted = 0.0;
    for (auto c : out.counted) counted += c;
    agree(comm, out.reducer().total(counted) != static_cast<double>(out.global_elements)
                    ? path.string() + ": the pieces do not hold every element around the vertices they own"
                    : "");
    // Ghosts must sit where their owners put them.
    std::vector<double> xyz(out.mesh.coordinates().begin(), out.mesh.coordinates().end());
    out.halo().update(xyz, 3);
    failure.clear();
    for (VertexId v = 0; v < out.mesh.num_vertices() && failure.empty(); ++v)
        for (int c = 0; c < 3; ++c)
            if (xyz[3 * static_cast<std::size_t>(v) + c] != out.mesh.coordinates()[3 * static_cast<std::size_t>(v) + c]) {
                failure = path.string() + ": vertex " + std::to_string(out.mesh.global_ids()[v]) + " has coordinates in piece " +
                          std::to_string(out.rank) + " that differ from those in its owner's piece " +
                          std::to_string(out.vertex_owner[v]);
                break;
            }
    agree(comm, failure);
    out.orientation = orient_pieces(out, options.orientation);
    out.timings.distribute = seconds_since(start);
    return out;
}

void DistributedMesh::assemble(void* arrays, ElementKind kind, ExchangeMode mode) {
    PartArrays& mine = *static_cast<PartArrays*>(arrays);
    static_assert(std::is_same_v<std::int32_t, VertexId> && std::is_same_v<std::int64_t, GlobalId> &&
                  std::is_same_v<std::int32_t, int>, "the part's arrays are moved into the mesh, not copied");
    mesh = SimplexMesh(kind, std::move(mine.coordinates), std::move(mine.connectivity));
    mesh.set_fixed(std::move(mine.fixed));
    mesh.set_global_ids(std::move(mine.canonical));
    vertex_owner = std::move(mine.owner);
    element_order = std::move(mine.element_order);
    // The smallest canonical id is the first corner in local order (vertices are sorted by it).
    counted.resize(static_cast<std::size_t>(mesh.num_elements()));
    for (ElementId e = 0; e < mesh.num_elements(); ++e) {
        const auto corners = mesh.element(e);
        counted[e] = vertex_owner[*std::min_element(corners.begin(), corners.end())] == rank;
    }
    const auto start = Clock::now();
    build_schedule(mode);
    reducer_ = parallel::make_mpi_reducer(comm);
    halo_ = parallel::make_mpi_halo(comm, rank, ranks, *schedule_);
    timings.schedule = seconds_since(start);
}

void DistributedMesh::write_pieces(const std::filesystem::path& path) const {
    parallel::together(comm, true, [&] {
        if (path.extension() == ".pvtu") std::filesystem::create_directories(piece_path(path, rank).parent_path());
        write_piece(piece_path(path, rank), mesh, vertex_owner, counted, rank, path.extension() != ".pvtu");
        if (rank == 0 && path.extension() == ".pvtu") write_pvtu(path, ranks);
    });
}

void DistributedMesh::write_partitioned(const SimplexMesh& whole, int parts, const std::filesystem::path& path) {
    if (path.extension() != ".pvtu" && path.extension() != ".vtk")
        throw OptionError("pieces are written as OUT.pvtu (with OUT/OUT_<rank>.vtu) or Mesquite-style OUT.vtk "
                          "(OUT_<rank>.vtk); got '" + path.string() + "'");
    WholeSplit split = split_whole(whole, parts);
    if (path.extension() == ".pvtu") std::filesystem::create_directories(piece_path(path, 0).parent_path());
    const ElementKind kind = whole.kind();
    for (int p = 0; p < parts; ++p) {
        PartArrays& arrays = split.parts[p];
        SimplexMesh piece(kind, std::move(arrays.coordinates),
                          std::vector<VertexId>(arrays.connectivity.begin(), arrays.connectivity.end()));
        piece.set_fixed(std::move(arrays.fixed));
        piece.set_global_ids(std::vector<GlobalId>(arrays.canonical.begin(), arrays.canonical.end()));
        piece.set_elements_flipped(whole.elements_flipped());
        std::vector<std::uint8_t> counted(static_cast<std::size_t>(piece.num_elements()));
        for (ElementId e = 0; e < piece.num_elements(); ++e) {
            const auto corners = piece.element(e);
            counted[e] = arrays.owner[*std::min_element(corners.begin(), corners.end())] == p;
        }
        const std::vector<int> owner(arrays.owner.begin(), arrays.owner.end());
        write_piece(piece_path(path, p), piece, owner, counted, p, path.extension() != ".pvtu");
    }
    if (path.extension() == ".pvtu") write_pvtu(path, parts);
}

BoundaryFacets DistributedMesh::gather_boundary() const {
    // A part holds every element around the vertices it owns, so a facet on its boundary with a
    // corner it owns is on the whole mesh's boundary; the owner of its corner with the smallest
    // global id reports it. (The faces where the part was cut have no owned corner.)
    BoundaryFacets local;
    std::string failure;
    try {
        local = BoundaryFacets::of(mesh);
    } catch (const MeshError& e) {
        failure = e.what();
    }
    agree(comm, failure);
    const auto global = mesh.global_ids();
    auto owned = [&](GlobalId v) { return vertex_owner[static_cast<std::size_t>(v)] == rank; };
    std::vector<std::int64_t> facets;
    for (const auto& f : local.facets) {
        GlobalId first = f[0];
        for (GlobalId v : f)
            if (v >= 0 && global[v] < global[first]) first = v;
        if (!owned(first)) continue;
        for (GlobalId v : f) facets.push_back(v < 0 ? -1 : global[v]);
    }
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
    const auto coordinates = mesh.coordinates();
    for (VertexId v = 0; v < mesh.num_vertices(); ++v)
        for (int c = 0; c < 3; ++c) {
            const double x = coordinates[3 * static_cast<std::size_t>(v) + c];
            box[c] = std::min(box[c], x);
            box[3 + c] = std::min(box[3 + c], -x);
        }
    MPI_Allreduce(MPI_IN_PLACE, box.data(), 6, MPI_DOUBLE, MPI_MIN, comm);

    BoundaryFacets out;
    out.kind = mesh.kind();
    const auto all_facets = gather_to_all(comm, facets);
    for (std::size_t i = 0; i + 2 < all_facets.size(); i += 3)
        out.facets.push_back({all_facets[i], all_facets[i + 1], all_facets[i + 2]});
    const auto all_ids = gather_to_all(comm, ids);
    const auto all_xyz = gather_to_all(comm, xyz);
    std::vector<std::size_t> order(all_ids.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return all_ids[a] < all_ids[b]; });
    for (std::size_t i : order) {
        out.ids.push_back(all_ids[i]);
        out.xyz.insert(out.xyz.end(), all_xyz.begin() + 3 * static_cast<std::ptrdiff_t>(i),
                       all_xyz.begin() + 3 * static_cast<std::ptrdiff_t>(i + 1));
    }
    const double dx = -box[3] - box[0], dy = -box[4] - box[1], dz = -box[5] - box[2];
    out.diagonal = global_vertices > 0 ? std::sqrt(dx * dx + dy * dy + dz * dz) : 0.0;
    return out;
}

void DistributedMesh::update_ghost_coordinates() { halo_->update(mesh.coordinates(), 3); }

// The owned vertices' global ids and coordinates (3 per vertex), in local order.
void DistributedMesh::owned_vertices(std::vector<std::int64_t>& ids, std::vector<double>& xyz) const {
    for (VertexId v = 0; v < mesh.num_vertices(); ++v)
        if (vertex_owner[v] == rank) {
            ids.push_back(mesh.global_ids()[v]);
            for (int c = 0; c < 3; ++c) xyz.push_back(mesh.coordinates()[3 * static_cast<std::size_t>(v) + c]);
        }
}

void DistributedMesh::gather_coordinates(SimplexMesh* whole) const {
    std::vector<std::int64_t> ids;
    std::vector<double> xyz;
    owned_vertices(ids, xyz);
    const auto all_ids = gather_to_root(comm, ids).values;
    const auto all_xyz = gather_to_root(comm, xyz).values;
    if (rank != 0) return;
    if (!whole || static_cast<GlobalId>(whole->num_vertices()) != global_vertices ||
        all_ids.size() != static_cast<std::size_t>(global_vertices))
        throw OptionError("DistributedMesh::gather_coordinates: rank 0 must pass the mesh given to scatter()");
    auto out = whole->coordinates();
    for (std::size_t i = 0; i < all_ids.size(); ++i) {
        const VertexId v = original_vertex_[static_cast<std::size_t>(all_ids[i])];
        for (int c = 0; c < 3; ++c) out[3 * static_cast<std::size_t>(v) + c] = all_xyz[3 * i + c];
    }
}

SimplexMesh DistributedMesh::gather_whole() const {
    // Vertices first, their buffers freed before the elements come: rank 0 holds the gathered
    // arrays of one kind at a time next to the mesh it builds.
    std::vector<double> coordinates;
    std::vector<std::uint8_t> fixed;
    {
        std::vector<std::int64_t> ids;
        std::vector<double> xyz;
        owned_vertices(ids, xyz);
        std::vector<std::int64_t> flags;  // int64 rather than bytes: one gather helper for both
        for (VertexId v = 0; v < mesh.num_vertices(); ++v)
            if (vertex_owner[v] == rank) flags.push_back(mesh.fixed()[v]);
        const auto all_ids = gather_to_root(comm, ids).values;
        const auto all_flags = gather_to_root(comm, flags).values;
        const auto all_xyz = gather_to_root(comm, xyz).values;
        if (rank == 0) {
            coordinates.resize(3 * static_cast<std::size_t>(global_vertices));
            fixed.resize(static_cast<std::size_t>(global_vertices));
            for (std::size_t i = 0; i < all_ids.size(); ++i) {
                const auto g = static_cast<std::size_t>(all_ids[i]);
                std::copy_n(all_xyz.begin() + 3 * static_cast<std::ptrdiff_t>(i), 3, coordinates.begin() + 3 * static_cast<std::ptrdiff_t>(g));
                fixed[g] = static_cast<std::uint8_t>(all_flags[i]);
            }
        }
    }
    // Each element once, from the rank that counts it: its canonical position, then its corners' ids.
    const int k = mesh.corners();
    std::vector<std::int64_t> records;
    for (ElementId e = 0; e < mesh.num_elements(); ++e)
        if (counted[e]) {
            records.push_back(element_order[e]);
            for (VertexId v : mesh.element(e)) records.push_back(mesh.global_ids()[v]);
        }
    auto all_records = gather_to_root(comm, records).values;
    std::vector<std::int64_t>().swap(records);
    if (rank != 0) return {};
    std::vector<VertexId> connectivity(static_cast<std::size_t>(global_elements) * static_cast<std::size_t>(k));
    for (std::size_t at = 0; at < all_records.size(); at += static_cast<std::size_t>(k) + 1) {
        const auto position = static_cast<std::size_t>(all_records[at]) * static_cast<std::size_t>(k);
        for (int c = 0; c < k; ++c) connectivity[position + static_cast<std::size_t>(c)] = static_cast<VertexId>(all_records[at + 1 + c]);
    }
    std::vector<std::int64_t>().swap(all_records);  // before the mesh builds its adjacency
    SimplexMesh whole(mesh.kind(), std::move(coordinates), std::move(connectivity));
    whole.set_fixed(std::move(fixed));
    whole.set_elements_flipped(mesh.elements_flipped());  // written back in the pieces' convention
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
