#include "paloverde/parallel/distributed_mesh.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <numeric>
#include <set>
#include <string>
#include <type_traits>

#include "io/xml_reader.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/io/atomic_file.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/renumber.hpp"
#include "paloverde/parallel/partition.hpp"
#include "parallel/collective.hpp"

namespace paloverde {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

template <class T>
MPI_Datatype mpi_type();
template <> MPI_Datatype mpi_type<double>() { return MPI_DOUBLE; }
template <> MPI_Datatype mpi_type<std::int32_t>() { return MPI_INT32_T; }
template <> MPI_Datatype mpi_type<std::int64_t>() { return MPI_INT64_T; }
template <> MPI_Datatype mpi_type<std::uint8_t>() { return MPI_UINT8_T; }

template <class T>
void send_vector(const std::vector<T>& data, int to, int tag, MPI_Comm comm) {
    const std::int64_t size = static_cast<std::int64_t>(data.size());
    MPI_Send(&size, 1, MPI_INT64_T, to, tag, comm);
    if (size > 0) MPI_Send(data.data(), static_cast<int>(size), mpi_type<T>(), to, tag, comm);
}

template <class T>
std::vector<T> receive_vector(int from, int tag, MPI_Comm comm) {
    std::int64_t size = 0;
    MPI_Recv(&size, 1, MPI_INT64_T, from, tag, comm, MPI_STATUS_IGNORE);
    std::vector<T> data(static_cast<std::size_t>(size));
    if (size > 0) MPI_Recv(data.data(), static_cast<int>(size), mpi_type<T>(), from, tag, comm, MPI_STATUS_IGNORE);
    return data;
}


// Collective: each rank's values, concatenated in rank order on rank 0, with each rank's count.
template <class T = std::int64_t>
struct Gathered {
    std::vector<T> values;
    std::vector<int> counts;
};
template <class T>
Gathered<T> gather_to_root(MPI_Comm comm, const std::vector<T>& mine) {
    int rank = 0, ranks = 1;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &ranks);
    Gathered<T> out;
    int count = static_cast<int>(mine.size());
    if (rank == 0) out.counts.resize(static_cast<std::size_t>(ranks));
    MPI_Gather(&count, 1, MPI_INT, out.counts.data(), 1, MPI_INT, 0, comm);
    std::vector<int> offsets(out.counts.size(), 0);
    for (std::size_t p = 1; p < offsets.size(); ++p) offsets[p] = offsets[p - 1] + out.counts[p - 1];
    if (rank == 0) out.values.resize(static_cast<std::size_t>(offsets.back() + out.counts.back()));
    MPI_Gatherv(mine.data(), count, mpi_type<T>(), out.values.data(), out.counts.data(), offsets.data(), mpi_type<T>(), 0, comm);
    return out;
}
// The inverse: rank 0's values cut by `counts`, `expected` of them to each rank.
std::vector<std::int64_t> scatter_from_root(MPI_Comm comm, const std::vector<std::int64_t>& values,
                                            const std::vector<int>& counts, std::size_t expected) {
    std::vector<int> offsets(counts.size(), 0);
    for (std::size_t p = 1; p < offsets.size(); ++p) offsets[p] = offsets[p - 1] + counts[p - 1];
    std::vector<std::int64_t> mine(expected);
    MPI_Scatterv(values.data(), counts.data(), offsets.data(), MPI_INT64_T, mine.data(), static_cast<int>(expected),
                 MPI_INT64_T, 0, comm);
    return mine;
}

// Collective: when a check failed on any rank (a non-empty message), it fails on every rank as a
// MeshError, with the lowest failing rank's message.
void agree(MPI_Comm comm, const std::string& failure) {
    parallel::together(comm, !failure.empty(), [&] { throw MeshError(failure); });
}

// The pieces of one rank's part, as rank 0 sends them or a piece file holds them.
struct PartArrays {
    std::vector<double> coordinates;
    std::vector<std::uint8_t> fixed;
    std::vector<std::int64_t> canonical;  // per vertex
    std::vector<std::int32_t> owner;      // per vertex
    std::vector<std::int32_t> connectivity;
    std::vector<std::int64_t> element_order;
};

class MpiReducer final : public Reducer {
public:
    explicit MpiReducer(MPI_Comm comm) : comm_(comm) {}
    void sum(std::span<ExactSum> sums) const override {
        if (sums.empty()) return;
        std::vector<std::int64_t> digits(sums.size() * ExactSum::kDigits);
        std::vector<std::int64_t> special(sums.size());
        for (std::size_t i = 0; i < sums.size(); ++i) {
            sums[i].normalize();
            std::copy(sums[i].digits().begin(), sums[i].digits().end(), digits.begin() + i * ExactSum::kDigits);
            special[i] = sums[i].special();
        }
        MPI_Allreduce(MPI_IN_PLACE, digits.data(), static_cast<int>(digits.size()), MPI_INT64_T, MPI_SUM, comm_);
        MPI_Allreduce(MPI_IN_PLACE, special.data(), static_cast<int>(special.size()), MPI_INT64_T, MPI_BOR, comm_);
        for (std::size_t i = 0; i < sums.size(); ++i) {
            std::copy(digits.begin() + i * ExactSum::kDigits, digits.begin() + (i + 1) * ExactSum::kDigits,
                      sums[i].digits().begin());
            sums[i].special() = special[i];
        }
    }
    double min(double value) const override {
        MPI_Allreduce(MPI_IN_PLACE, &value, 1, MPI_DOUBLE, MPI_MIN, comm_);
        return value;
    }
    double max(double value) const override {
        MPI_Allreduce(MPI_IN_PLACE, &value, 1, MPI_DOUBLE, MPI_MAX, comm_);
        return value;
    }

private:
    MPI_Comm comm_;
};

class MpiHalo final : public Halo {
public:
    MpiHalo(MPI_Comm comm, int rank, int ranks, const ExchangeSchedule& schedule)
        : comm_(comm), rank_(rank), ranks_(ranks), schedule_(schedule) {}

    void update(std::span<double> values, int width) const override {
        if (schedule_.mode == ExchangeMode::Colored) colored(values, width);
        else root_relayed(values, width);
    }

private:
    static std::vector<double> pack(std::span<const double> values, int width, const std::vector<VertexId>& list) {
        std::vector<double> out(list.size() * static_cast<std::size_t>(width));
        for (std::size_t i = 0; i < list.size(); ++i)
            for (int c = 0; c < width; ++c) out[i * width + c] = values[static_cast<std::size_t>(list[i]) * width + c];
        return out;
    }
    static void unpack(std::span<double> values, int width, const std::vector<VertexId>& list, const double* in) {
        for (std::size_t i = 0; i < list.size(); ++i)
            for (int c = 0; c < width; ++c) values[static_cast<std::size_t>(list[i]) * width + c] = in[i * width + c];
    }

    // Color by color, each rank trades with at most one partner per color.
    void colored(std::span<double> values, int width) const {
        std::vector<double> incoming;
        for (const ExchangePartner& p : schedule_.partners) {
            const auto outgoing = pack(values, width, p.send);
            incoming.resize(p.receive.size() * static_cast<std::size_t>(width));
            MPI_Sendrecv(outgoing.data(), static_cast<int>(outgoing.size()), MPI_DOUBLE, p.rank, p.color,
                         incoming.data(), static_cast<int>(incoming.size()), MPI_DOUBLE, p.rank, p.color, comm_,
                         MPI_STATUS_IGNORE);
            unpack(values, width, p.receive, incoming.data());
        }
    }

    // Every rank sends all its outgoing values to rank 0, which forwards each block to its
    // destination: the paper's baseline.
    void root_relayed(std::span<double> values, int width) const {
        std::vector<int> counts(static_cast<std::size_t>(ranks_), 0);  // doubles to each destination
        std::vector<double> outgoing;
        for (int to = 0; to < ranks_; ++to)
            for (const ExchangePartner& p : schedule_.partners)
                if (p.rank == to) {
                    const auto block = pack(values, width, p.send);
                    outgoing.insert(outgoing.end(), block.begin(), block.end());
                    counts[to] = static_cast<int>(block.size());
                }
        std::vector<int> all_counts(rank_ == 0 ? static_cast<std::size_t>(ranks_) * ranks_ : 0);
        MPI_Gather(counts.data(), ranks_, MPI_INT, all_counts.data(), ranks_, MPI_INT, 0, comm_);
        std::vector<int> gathered_sizes(rank_ == 0 ? ranks_ : 0), gathered_offsets(rank_ == 0 ? ranks_ : 0);
        std::vector<double> gathered;
        if (rank_ == 0) {
            int offset = 0;
            for (int from = 0; from < ranks_; ++from) {
                gathered_offsets[from] = offset;
                gathered_sizes[from] = std::accumulate(all_counts.begin() + from * ranks_, all_counts.begin() + (from + 1) * ranks_, 0);
                offset += gathered_sizes[from];
            }
            gathered.resize(static_cast<std::size_t>(offset));
        }
        MPI_Gatherv(outgoing.data(), static_cast<int>(outgoing.size()), MPI_DOUBLE, gathered.data(),
                    gathered_sizes.data(), gathered_offsets.data(), MPI_DOUBLE, 0, comm_);
        // Rank 0 regroups by destination, sources in rank order.
        std::vector<double> forward;
        std::vector<int> forward_sizes(rank_ == 0 ? ranks_ : 0), forward_offsets(rank_ == 0 ? ranks_ : 0);
        if (rank_ == 0) {
            for (int to = 0; to < ranks_; ++to) {
                forward_offsets[to] = static_cast<int>(forward.size());
                for (int from = 0; from < ranks_; ++from) {
                    int within = 0;
                    for (int d = 0; d < to; ++d) within += all_counts[from * ranks_ + d];
                    const double* block = gathered.data() + gathered_offsets[from] + within;
                    forward.insert(forward.end(), block, block + all_counts[from * ranks_ + to]);
                }
                forward_sizes[to] = static_cast<int>(forward.size()) - forward_offsets[to];
            }
        }
        std::size_t expected = 0;
        for (const ExchangePartner& p : schedule_.partners) expected += p.receive.size() * static_cast<std::size_t>(width);
        std::vector<double> incoming(expected);
        MPI_Scatterv(forward.data(), forward_sizes.data(), forward_offsets.data(), MPI_DOUBLE, incoming.data(),
                     static_cast<int>(incoming.size()), MPI_DOUBLE, 0, comm_);
        std::size_t offset = 0;
        for (int from = 0; from < ranks_; ++from)
            for (const ExchangePartner& p : schedule_.partners)
                if (p.rank == from) {
                    unpack(values, width, p.receive, incoming.data() + offset);
                    offset += p.receive.size() * static_cast<std::size_t>(width);
                }
    }

    MPI_Comm comm_;
    int rank_, ranks_;
    const ExchangeSchedule& schedule_;
};

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

// Piece files: the part's mesh with its global ids, owners and which elements it counts.
const char* const kGlobalIds = "GlobalNodeIds";
const char* const kOwner = "OwnerRank";
const char* const kGhostCells = "vtkGhostType";  // 1: counted by another piece (ParaView hides those)
const char* const kPartition = "PartitionId";

void write_piece(const std::filesystem::path& path, const SimplexMesh& mesh, std::span<const int> owner,
                 std::span<const std::uint8_t> counted, int piece, bool mesquite_names) {
    std::vector<Field> points(2), cells(2);
    points[0].name = mesquite_names ? "GLOBAL_ID" : kGlobalIds;
    points[1].name = mesquite_names ? "PROCESSOR_ID" : kOwner;
    for (VertexId v = 0; v < mesh.num_vertices(); ++v) {
        points[0].values.push_back(static_cast<double>(mesh.global_ids()[v]));
        points[1].values.push_back(owner[v]);
    }
    cells[0].name = kPartition;
    cells[1].name = kGhostCells;
    for (ElementId e = 0; e < mesh.num_elements(); ++e) {
        cells[0].values.push_back(piece);
        cells[1].values.push_back(counted[e] ? 0.0 : 1.0);
    }
    write_mesh(path, mesh, {}, points, cells);
}

// Where piece p of `path` lives: OUT.pvtu -> OUT/OUT_p.vtu; OUT.vtk (Mesquite style) -> OUT_p.vtk.
std::filesystem::path piece_path(const std::filesystem::path& path, int piece) {
    const std::string stem = path.stem().string(), number = std::to_string(piece);
    if (path.extension() == ".pvtu") return path.parent_path() / stem / (stem + "_" + number + ".vtu");
    return path.parent_path() / (stem + "_" + number + path.extension().string());
}

void write_pvtu(const std::filesystem::path& path, int pieces) {
    std::string text =
        "<?xml version=\"1.0\"?>\n"
        "<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
        "  <PUnstructuredGrid GhostLevel=\"1\">\n"
        "    <PPointData>\n";
    for (const char* name : {"fixed", kGlobalIds, kOwner})
        text += "      <PDataArray type=\"Float64\" Name=\"" + std::string(name) + "\"/>\n";
    text += "    </PPointData>\n    <PCellData>\n";
    for (const char* name : {kPartition, kGhostCells})
        text += "      <PDataArray type=\"Float64\" Name=\"" + std::string(name) + "\"/>\n";
    text += "    </PCellData>\n    <PPoints>\n      <PDataArray type=\"Float64\" NumberOfComponents=\"3\"/>\n    </PPoints>\n";
    for (int p = 0; p < pieces; ++p)
        text += "    <Piece Source=\"" + piece_path(path.filename(), p).generic_string() + "\"/>\n";
    text += "  </PUnstructuredGrid>\n</VTKFile>\n";
    write_text_file(path, text);
}

// The piece files a .pvtu lists (relative to its folder), or the per-rank files of a pattern.
std::vector<std::filesystem::path> piece_files(const std::filesystem::path& path, int ranks) {
    std::vector<std::filesystem::path> files;
    if (path.extension() != ".pvtu") {
        for (int p = 0; p < ranks; ++p) files.push_back(piece_path(path, p));
        return files;
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) throw FileError(path.string(), 0, "cannot open the .pvtu file");
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const io::XmlDocument doc = io::parse_xml(text, path.string(), "AppendedData");
    for (const io::XmlElement& e : doc.elements)
        if (e.name == "Piece") {
            const std::string* source = e.attribute("Source");
            if (!source) throw FileError(path.string(), e.line, "<Piece> has no Source attribute");
            files.push_back(path.parent_path() / *source);
        }
    return files;
}

// One rank's piece file as part arrays, vertices sorted by global id.
PartArrays read_piece(const std::filesystem::path& file, int ranks, ElementKind& kind) {
    ReadOptions options;
    options.fix_boundary = false;
    options.orientation = OrientationMode::AsIs;  // decided over all pieces together, once assembled
    MeshFile piece = read_mesh(file, options);
    const Field* ids = piece.point_field(kGlobalIds);
    if (!ids) ids = piece.point_field("GLOBAL_ID");
    const Field* owners = piece.point_field(kOwner);
    if (!owners) owners = piece.point_field("PROCESSOR_ID");
    if (!ids || !owners)
        throw FileError(file.string(), 0, "a piece needs the point fields GlobalNodeIds (or GLOBAL_ID) and OwnerRank "
                                          "(or PROCESSOR_ID); write pieces with `paloverde partition`");
    if (!piece.fixed_from_file)
        throw FileError(file.string(), 0, "a piece needs a `fixed` point field: a piece alone cannot tell the "
                                          "boundary of the whole mesh");
    const SimplexMesh& mesh = piece.mesh;
    kind = mesh.kind();
    const VertexId n = mesh.num_vertices();
    for (VertexId v = 0; v < n; ++v) {
        const double id = ids->values[v], owner = owners->values[v];
        if (!(id >= 0.0 && id < 9e15 && id == std::floor(id)))
            throw FileError(file.string(), 0, "vertex " + std::to_string(v) + " has global id " + std::to_string(id) +
                                                  ", not a non-negative integer");
        if (!(owner >= 0.0 && owner < ranks && owner == std::floor(owner)))
            throw FileError(file.string(), 0, "vertex " + std::to_string(v) + " has owner " + std::to_string(owner) +
                                                  ", not a rank in [0, " + std::to_string(ranks) + ")");
    }
    std::vector<VertexId> order(static_cast<std::size_t>(n));
    std::iota(order.begin(), order.end(), VertexId{0});
    std::sort(order.begin(), order.end(), [&](VertexId a, VertexId b) { return ids->values[a] < ids->values[b]; });
    std::vector<VertexId> local(static_cast<std::size_t>(n));
    PartArrays out;
    for (VertexId i = 0; i < n; ++i) {
        const VertexId v = order[i];
        local[v] = i;
        if (i > 0 && ids->values[v] == ids->values[order[i - 1]])
            throw FileError(file.string(), 0, "global id " + std::to_string(static_cast<GlobalId>(ids->values[v])) +
                                                  " appears twice in the piece");
        for (int c = 0; c < 3; ++c) out.coordinates.push_back(mesh.coordinates()[3 * static_cast<std::size_t>(v) + c]);
        out.fixed.push_back(mesh.fixed()[v]);
        out.canonical.push_back(static_cast<std::int64_t>(ids->values[v]));
        out.owner.push_back(static_cast<std::int32_t>(owners->values[v]));
    }
    for (VertexId v : mesh.connectivity()) out.connectivity.push_back(local[v]);
    return out;
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
    reducer_ = std::make_unique<MpiReducer>(comm);
    halo_ = std::make_unique<MpiHalo>(comm, rank, ranks, *schedule_);
    timings.schedule = seconds_since(start);
}
void DistributedMesh::build_schedule(ExchangeMode mode) {
    ExchangeSchedule& schedule = *schedule_;
    schedule = {};
    schedule.mode = mode;
    const auto ids = mesh.global_ids();
    // Ghosts, grouped by owner (in canonical order within each group).
    std::vector<std::vector<VertexId>> receive(static_cast<std::size_t>(ranks));
    for (VertexId v = 0; v < mesh.num_vertices(); ++v)
        if (vertex_owner[v] != rank) receive[vertex_owner[v]].push_back(v);
    // Tell each owner which of its vertices this rank holds.
    std::vector<int> request_counts(static_cast<std::size_t>(ranks)), offer_counts(static_cast<std::size_t>(ranks));
    for (int p = 0; p < ranks; ++p) request_counts[p] = static_cast<int>(receive[p].size());
    MPI_Alltoall(request_counts.data(), 1, MPI_INT, offer_counts.data(), 1, MPI_INT, comm);
    std::vector<int> request_offsets(static_cast<std::size_t>(ranks), 0), offer_offsets(static_cast<std::size_t>(ranks), 0);
    std::partial_sum(request_counts.begin(), request_counts.end() - 1, request_offsets.begin() + 1);
    std::partial_sum(offer_counts.begin(), offer_counts.end() - 1, offer_offsets.begin() + 1);
    std::vector<std::int64_t> requested;
    for (const auto& list : receive)
        for (VertexId v : list) requested.push_back(ids[v]);
    std::vector<std::int64_t> offered(static_cast<std::size_t>(offer_offsets.back() + offer_counts.back()));
    MPI_Alltoallv(requested.data(), request_counts.data(), request_offsets.data(), MPI_INT64_T, offered.data(),
                  offer_counts.data(), offer_offsets.data(), MPI_INT64_T, comm);

    std::vector<std::pair<int, int>> my_edges;
    std::string failure;
    for (int p = 0; p < ranks; ++p) {
        if (receive[p].empty() && offer_counts[p] == 0) continue;
        ExchangePartner partner;
        partner.rank = p;
        partner.receive = receive[p];
        for (int i = 0; i < offer_counts[p]; ++i) {
            const GlobalId id = offered[offer_offsets[p] + i];
            const auto it = std::lower_bound(ids.begin(), ids.end(), id);
            if (it == ids.end() || *it != id || vertex_owner[it - ids.begin()] != rank) {
                if (failure.empty())
                    failure = "rank " + std::to_string(p) + " holds vertex " + std::to_string(id) + " as owned by rank " +
                              std::to_string(rank) + ", which does not own it";
                continue;
            }
            partner.send.push_back(static_cast<VertexId>(it - ids.begin()));
        }
        schedule.partners.push_back(std::move(partner));
        my_edges.push_back({std::min(rank, p), std::max(rank, p)});
    }
    agree(comm, failure);
    // The whole process graph on every rank, colored the same way everywhere.
    int mine = static_cast<int>(my_edges.size());
    std::vector<int> edge_counts(static_cast<std::size_t>(ranks));
    MPI_Allgather(&mine, 1, MPI_INT, edge_counts.data(), 1, MPI_INT, comm);
    std::vector<int> edge_offsets(static_cast<std::size_t>(ranks), 0);
    for (int p = 1; p < ranks; ++p) edge_offsets[p] = edge_offsets[p - 1] + 2 * edge_counts[p - 1];
    std::vector<int> flat;
    for (const auto& [a, b] : my_edges) flat.push_back(a), flat.push_back(b);
    std::vector<int> flat_counts(static_cast<std::size_t>(ranks));
    for (int p = 0; p < ranks; ++p) flat_counts[p] = 2 * edge_counts[p];
    std::vector<int> all_flat(static_cast<std::size_t>(edge_offsets.back() + flat_counts.back()));
    MPI_Allgatherv(flat.data(), static_cast<int>(flat.size()), MPI_INT, all_flat.data(), flat_counts.data(),
                   edge_offsets.data(), MPI_INT, comm);
    std::set<std::pair<int, int>> edge_set;
    for (std::size_t i = 0; i + 1 < all_flat.size(); i += 2) edge_set.insert({all_flat[i], all_flat[i + 1]});
    const std::vector<std::pair<int, int>> edges(edge_set.begin(), edge_set.end());
    const auto colors = color_process_graph(ranks, edges);
    schedule.colors = colors.empty() ? 0 : *std::max_element(colors.begin(), colors.end()) + 1;
    for (ExchangePartner& p : schedule.partners) {
        const auto it = std::lower_bound(edges.begin(), edges.end(), std::pair{std::min(rank, p.rank), std::max(rank, p.rank)});
        p.color = colors[static_cast<std::size_t>(it - edges.begin())];
    }
    std::sort(schedule.partners.begin(), schedule.partners.end(),
              [](const ExchangePartner& a, const ExchangePartner& b) { return a.color < b.color; });
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
