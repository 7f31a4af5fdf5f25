// A run config over MPI ranks: every rank parses the same config and runs this. Rank 0 reads and
// splits input.mesh (or every rank reads its piece), each method's queue runs on the distributed
// mesh, the outputs are written (meshes gathered on rank 0, or as pieces; reports by rank 0), and
// every rank returns the same RunResult. Anything that can fail on one rank alone is made to fail
// on all of them, so no rank is left waiting in a collective call.
#include <unistd.h>

#include <algorithm>
#include <chrono>

#include "config/partitioned_run.hpp"
#include "config/registry_internal.hpp"
#include "parallel/mpi_support.hpp"
#include "io/xml_reader.hpp"
#include "paloverde/io/atomic_file.hpp"
#include "paloverde/parallel/distributed_mesh.hpp"

namespace paloverde::config::detail {

int world_size() { return parallel::mpi_running() ? parallel::ranks_in(MPI_COMM_WORLD) : 1; }

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

bool is_pvtu(const std::string& path) { return std::filesystem::path(path).extension() == ".pvtu"; }

using parallel::together;

ConfigError config_error(const RunSpec& spec, const std::string& key, const std::string& message) {
    return ConfigError(origin(spec, key), key, message);
}

// Where a step of method `m` was written: "queue[2]" or "study[1].queue[2]".
std::string step_path(const RunSpec& spec, std::size_t m, std::size_t i) {
    return (spec.study.empty() ? std::string() : "study[" + std::to_string(m) + "].") + "queue[" + std::to_string(i) + "]";
}

// The solvers and wrappers that have a distributed version, for the error that names a step
// without one.
std::string distributed_ones() {
    std::string solvers, wrappers;
    for (const SolverKind& kind : solver_kinds())
        if (kind.distributed) solvers += (solvers.empty() ? "" : ", ") + kind.name;
    for (const WrapperKind& kind : wrapper_kinds())
        if (find_solver(kind.solver)->distributed) wrappers += (wrappers.empty() ? "" : ", ") + kind.name;
    return "has no distributed version: a partitioned run takes the solvers " + solvers + " (and the wrappers " +
           wrappers + "); run it serially (partition.parts: 1, no pieces, without mpirun)";
}

// Method `m`'s queue, the same as a serial run's; a step without a distributed version is an
// error naming it.
BuiltQueue build_queue_for(const RunSpec& spec, const MethodSpec& method, std::size_t m) {
    for (std::size_t i = 0; i < method.queue.size(); ++i) {
        const StepSpec& step = method.queue[i];
        const std::string path = step_path(spec, m, i);
        const SolverKind* solver = nullptr;
        std::string key;
        switch (step.kind) {
            case StepSpec::Kind::Assess: continue;
            case StepSpec::Kind::Untangle:
            case StepSpec::Kind::Improve:
                solver = find_solver(step.name);
                key = path + (step.kind == StepSpec::Kind::Untangle ? ".untangle" : ".improve") + ".name";
                break;
            case StepSpec::Kind::Wrapper:
                if (const WrapperKind* wrapper = find_wrapper(step.name)) solver = find_solver(wrapper->solver);
                key = path + ".wrapper.name";
                break;
        }
        if (solver && !solver->distributed) {
            const std::string where = origin(spec, key).empty() ? origin(spec, path) : origin(spec, key);
            throw ConfigError(where, key, "'" + step.name + "' " + distributed_ones());
        }
    }
    return build_queue_of(method.queue, spec.threads);
}

// Everything about the config and the number of ranks that can be wrong, before anything is read.
// The same on every rank: it depends on the spec and the world's size only.
void check_partitioned(const RunSpec& spec, int ranks, bool pieces) {
    const InputSpec& in = spec.input;
    const int parts = spec.partition.parts;
    const std::string launch = "mpirun -n " + std::to_string(parts);
    if (!pieces && parts != ranks) {
        std::string message;
        if (ranks == 1)
            message = "splitting input.mesh into " + std::to_string(parts) + " parts needs " + std::to_string(parts) +
                      " MPI ranks, one per part, but this run has 1: launch it with `" + launch +
                      " paloverde run ...`, or set partition.parts: 1 for a serial run";
        else if (parts == 1)
            message = "this run has " + std::to_string(ranks) + " MPI ranks but partition.parts is 1 (a serial run): "
                      "set partition.parts: " + std::to_string(ranks) + " (or --set partition.parts=" +
                      std::to_string(ranks) + ") to split input.mesh over them, or run it without mpirun";
        else
            message = "must equal the number of MPI ranks (one part per rank): it is " +
                      std::to_string(parts) + " but this run has " + std::to_string(ranks) + "; set partition.parts: " +
                      std::to_string(ranks) + " or launch it with `" + launch + " ...`";
        throw config_error(spec, "partition.parts", message);
    }
    if (pieces) {
        const std::string key = in.pieces.empty() ? "input.mesh" : "input.pieces";
        if (parts != 1 && parts != ranks)
            throw config_error(spec, "partition.parts",
                               "the pieces are read one per MPI rank; partition.parts is " + std::to_string(parts) +
                                   " but this run has " + std::to_string(ranks) +
                                   " ranks: launch it on as many ranks as there are pieces, or leave partition.parts out");
        const bool listed = !in.pieces.empty() && !(in.pieces.size() == 1 && is_pvtu(in.pieces[0]));
        if (listed) {
            for (const auto& p : in.pieces)
                if (is_pvtu(p))
                    throw config_error(spec, key, "'" + p + "' is a .pvtu, which lists its pieces itself: give it "
                                                  "alone (pieces: [" + p + "]) or as input.mesh");
            if (static_cast<int>(in.pieces.size()) != ranks)
                throw config_error(spec, key, "lists " + std::to_string(in.pieces.size()) + " pieces but this run has " +
                                                  std::to_string(ranks) + (ranks == 1 ? " MPI rank" : " MPI ranks") +
                                                  ": piece k goes to rank k, so launch it with `mpirun -n " +
                                                  std::to_string(in.pieces.size()) + " ...`");
        }
        if (in.fixed == FixedVertices::Boundary)
            throw config_error(spec, "input.fixed",
                               "pieces carry their own `fixed` field (a piece alone cannot tell the boundary of the "
                               "whole mesh): use fixed: auto, file or none, or split the whole mesh in this run "
                               "(input.mesh and partition.parts)");
        if (!in.fixed_vertices.empty())
            throw config_error(spec, "input.fixed_vertices",
                               "ids in the file's order do not exist for pieces: set the `fixed` field of the whole "
                               "mesh before splitting it, or split it in this run (input.mesh and partition.parts)");
        if (in.format != MeshFormat::FromExtension)
            throw config_error(spec, "input.format", "pieces are read by their extension: leave input.format: auto");
    }
    if (spec.study.size() > 1 && !spec.output.pieces.empty() && spec.output.pieces.find("{method}") == std::string::npos)
        throw config_error(spec, "output.pieces",
                           "a study writes pieces per method: put {method} in the name (e.g. out_{method}.pvtu)");
}

// A list of piece files as a .pvtu of this rank's own (read_pieces takes one path), removed
// when done. Each rank writes its own: ranks on other nodes may not share a temporary folder.
class ListedPieces {
public:
    ListedPieces(const std::vector<std::string>& files, int rank) {
        path_ = std::filesystem::temp_directory_path() /
                ("paloverde_pieces_" + std::to_string(::getpid()) + "_" + std::to_string(rank) + ".pvtu");
        std::string text = "<?xml version=\"1.0\"?>\n<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\">\n"
                           "  <PUnstructuredGrid GhostLevel=\"1\">\n";
        for (const auto& f : files)
            text += "    <Piece Source=\"" + io::xml_escaped(std::filesystem::absolute(f).string()) + "\"/>\n";
        text += "  </PUnstructuredGrid>\n</VTKFile>\n";
        write_text_file(path_, text);
    }
    ~ListedPieces() {
        std::error_code ignored;
        std::filesystem::remove(path_, ignored);
    }
    ListedPieces(const ListedPieces&) = delete;
    ListedPieces& operator=(const ListedPieces&) = delete;
    const std::filesystem::path& path() const { return path_; }

private:
    std::filesystem::path path_;
};

// Reads the pieces of input.pieces or a .pvtu input.mesh; errors about a listed set name
// input.pieces rather than the temporary .pvtu.
DistributedMesh read_input_pieces(const RunSpec& spec, MPI_Comm comm, int rank, const DistributeOptions& options) {
    const InputSpec& in = spec.input;
    if (in.pieces.empty()) return DistributedMesh::read_pieces(comm, in.mesh, options);
    if (in.pieces.size() == 1 && is_pvtu(in.pieces[0])) return DistributedMesh::read_pieces(comm, in.pieces[0], options);
    std::unique_ptr<ListedPieces> listed;
    together(comm, true, [&] { listed = std::make_unique<ListedPieces>(in.pieces, rank); });
    try {
        return DistributedMesh::read_pieces(comm, listed->path(), options);
    } catch (const Error& e) {
        std::string message = e.what();
        const std::string temporary = listed->path().string();
        for (std::size_t at = message.find(temporary); at != std::string::npos; at = message.find(temporary))
            message.replace(at, temporary.size(), "the pieces of input.pieces");
        if (dynamic_cast<const OptionError*>(&e)) throw OptionError(message);
        throw MeshError(message);
    }
}

// Rank 0's decision about the file it read, on every rank (for the same RunResult everywhere).
OrientationDecision broadcast(MPI_Comm comm, OrientationDecision d) {
    double packed[5] = {static_cast<double>(d.mode), d.oriented ? 1.0 : 0.0, static_cast<double>(d.sign), d.share,
                        d.flipped ? 1.0 : 0.0};
    parallel::broadcast_from_root(comm, packed, 5);
    d.mode = static_cast<OrientationMode>(packed[0]);
    d.oriented = packed[1] != 0.0;
    d.sign = static_cast<int>(packed[2]);
    d.share = packed[3];
    d.flipped = packed[4] != 0.0;
    return d;
}

std::string input_name(const RunSpec& spec) {
    if (!spec.input.mesh.empty()) return spec.input.mesh;
    std::string names;
    for (const auto& p : spec.input.pieces) names += (names.empty() ? "" : ", ") + p;
    return names;
}

}  // namespace

RunResult run_partitioned(const RunSpec& spec, const RunHooks& hooks) {
    const int ranks = world_size();
    const bool pieces = !spec.input.pieces.empty() || is_pvtu(spec.input.mesh);
    check_partitioned(spec, ranks, pieces);
    const auto methods = spec.methods();
    std::vector<BuiltQueue> queues;  // every option checked before the mesh is read
    for (std::size_t m = 0; m < methods.size(); ++m) queues.push_back(build_queue_for(spec, methods[m], m));
    if (!parallel::mpi_running())
        throw Error("a partitioned run needs MPI: call MPI_Init before config::run (the paloverde program does it "
                    "for such a config, or when launched by mpirun)");

    const MPI_Comm comm = MPI_COMM_WORLD;
    const int rank = parallel::rank_in(comm);
    DistributeOptions distribute;
    distribute.exchange = spec.parallel.exchange == "root" ? ExchangeMode::RootRelayed : ExchangeMode::Colored;
    distribute.orientation = spec.input.orientation;
    ParallelReport report;
    report.ranks = ranks;
    report.exchange = distribute.exchange == ExchangeMode::Colored ? "colored" : "root_relayed";
    report.from_pieces = pieces;

    MeshFile file;  // rank 0, when it reads and splits input.mesh: the whole mesh, for output.mesh
    // output.mesh as one file: rank 0 writes the whole mesh, kept from the input or gathered from pieces.
    const bool writes_whole = !spec.output.mesh.empty() && !is_pvtu(spec.output.mesh);
    DistributedMesh part;
    auto start = Clock::now();
    if (pieces) {
        part = read_input_pieces(spec, comm, rank, distribute);
        report.read_seconds = seconds_since(start);
        if (spec.input.fixed == FixedVertices::None)
            part.mesh().set_fixed(std::vector<std::uint8_t>(static_cast<std::size_t>(part.mesh().num_vertices()), 0));
    } else {
        together(comm, rank == 0, [&] { file = read_input(spec); });
        report.read_seconds = seconds_since(start);
        part = DistributedMesh::scatter(comm, rank == 0 ? &file.mesh : nullptr, distribute);
        report.partition_seconds = part.timings().partition;
        report.distribute_seconds = part.timings().distribute;
        // The whole mesh is as large as all the parts together: rank 0 keeps it only to write it.
        if (!writes_whole) file = MeshFile();
    }
    // Each part's targets from its own elements, the ideal size the whole mesh's, and from its own
    // reference coordinates (scattered with the whole mesh's; RunSpec::check_runnable refuses a
    // reference for pieces).
    // keep: auto keeps nothing of a surface's cells (as set_run_targets).
    const bool surface = part.reducer().max(is_surface_mesh(part.mesh()) ? 1.0 : 0.0) > 0.0;
    set_targets(MeshPart(part),
                spec.targets.options(part.mesh().has_cells() && !surface, !spec.input.displacement.empty()));
    // What rank 0 holds, told by rank 0's mesh itself so that the report cannot drift from it.
    int kept = rank == 0 && file.mesh.num_vertices() > 0 ? 1 : 0;
    parallel::broadcast_from_root(comm, &kept, 1);
    report.whole_mesh_on_rank_0 = pieces ? (writes_whole ? "gathered" : "never") : (kept ? "kept" : "dropped");
    report.schedule_seconds = part.timings().schedule;
    report.vertices = part.global_vertices();
    report.elements = part.global_cells();  // as the reports count: cells, for a mesh with cells
    report.ghost_copies = static_cast<std::int64_t>(part.reducer().total(static_cast<double>(part.received_vertices())));
    report.messages = static_cast<std::int64_t>(part.reducer().total(static_cast<double>(part.schedule().partners.size())));
    report.colors = part.schedule().colors;

    RunResult result;
    result.input = input_name(spec);
    result.kind = part.mesh().kind();
    result.orientation = pieces ? part.orientation() : broadcast(comm, file.orientation);
    WriteOptions write;
    write.encoding = spec.output.ascii ? Encoding::Ascii : Encoding::Binary;
    run_methods(spec, hooks, part, queues, [&](MethodResult& r) {
        const auto start = Clock::now();
        if (!spec.output.mesh.empty()) {
            r.mesh_written = replace_method(spec.output.mesh, r.name);
            if (is_pvtu(r.mesh_written)) {
                part.write_pieces(r.mesh_written);
            } else if (pieces) {
                // No rank has the whole mesh: rank 0 builds it from the parts for this write only.
                Mesh whole;
                together(comm, true, [&] { whole = part.gather_whole(); });
                together(comm, rank == 0, [&] { write_mesh(r.mesh_written, whole, write); });
            } else {
                // Every rank takes part in the gather; only rank 0 holds the whole mesh and writes it.
                together(comm, true, [&] { part.gather_coordinates(rank == 0 ? &file.mesh : nullptr); });
                together(comm, rank == 0,
                         [&] { write_mesh(r.mesh_written, file.mesh, write, file.point_fields, file.cell_fields); });
            }
        }
        if (!spec.output.pieces.empty()) part.write_pieces(replace_method(spec.output.pieces, r.name));
        report.write_seconds += part.reducer().max(seconds_since(start));
    }, result);
    for (const MethodResult& r : result.methods) report.solve_seconds += r.seconds;
    // Rank 0's clock for the stages it leads, so that every rank reports the same numbers.
    double seconds[4] = {report.read_seconds, report.partition_seconds, report.distribute_seconds,
                         report.schedule_seconds};
    parallel::broadcast_from_root(comm, seconds, 4);
    report.read_seconds = seconds[0], report.partition_seconds = seconds[1], report.distribute_seconds = seconds[2];
    report.schedule_seconds = seconds[3];
    result.parallel = report;
    together(comm, rank == 0, [&] { write_reports(spec, result); });
    return result;
}

}  // namespace paloverde::config::detail
