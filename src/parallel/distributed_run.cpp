#include "paloverde/parallel/distributed_run.hpp"

#include <chrono>
#include <functional>
#include <nlohmann/json.hpp>

#include "paloverde/core/error.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "parallel/collective.hpp"

namespace paloverde {

namespace {
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

}  // namespace

void DistributedRunOptions::validate() const {
    if (input.empty()) throw OptionError("a distributed run needs an input mesh or pieces");
    distribute.validate();
}

namespace {
DistributedRunReport run(MPI_Comm comm, const DistributedRunOptions& options,
                         const std::function<Summary(DistributedMesh&)>& improve) {
    options.validate();
    DistributedRunReport report;
    int rank = 0;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &report.ranks);
    report.exchange = options.distribute.exchange == ExchangeMode::Colored ? "colored" : "root_relayed";

    const bool pieces = options.pieces || options.input.extension() == ".pvtu";
    SimplexMesh whole;  // rank 0, whole-file runs
    auto start = Clock::now();
    DistributedMesh part;
    if (pieces) {
        part = DistributedMesh::read_pieces(comm, options.input, options.distribute);
        report.read_seconds = part.timings.distribute;  // reading and checking the pieces
    } else {
        parallel::together(comm, rank == 0, [&] {
            ReadOptions read;
            read.fix_boundary = options.fix_boundary;
            read.orientation = options.distribute.orientation;
            whole = read_mesh(options.input, read).mesh;
        });
        report.read_seconds = seconds_since(start);
        part = DistributedMesh::scatter(comm, rank == 0 ? &whole : nullptr, options.distribute);
        // Rank 0 keeps the whole mesh only to write it: it is as large as all the parts together.
        const bool writes_whole = !options.output.empty() && options.output.extension() != ".pvtu";
        if (!writes_whole) whole = SimplexMesh();
    }
    report.timings = part.timings;
    const double local[2] = {static_cast<double>(part.received_vertices()), static_cast<double>(part.schedule().partners.size())};
    report.ghost_copies = static_cast<std::int64_t>(part.reducer().total(local[0]));
    report.messages = static_cast<std::int64_t>(part.reducer().total(local[1]));
    report.colors = part.schedule().colors;

    MPI_Barrier(comm);
    start = Clock::now();
    report.summary = improve(part);
    report.solve_seconds = part.reducer().max(seconds_since(start));

    start = Clock::now();
    if (!options.output.empty()) {
        if (options.output.extension() == ".pvtu") {
            part.write_pieces(options.output);
        } else {
            if (pieces)
                throw OptionError("a run from pieces writes pieces: give an output ending in .pvtu (got '" +
                                  options.output.string() + "')");
            part.gather_coordinates(rank == 0 ? &whole : nullptr);
            parallel::together(comm, rank == 0, [&] { write_mesh(options.output, whole); });
        }
    }
    report.write_seconds = part.reducer().max(seconds_since(start));
    return report;
}
}  // namespace

DistributedRunReport improve_distributed(MPI_Comm comm, const DistributedRunOptions& options, GlobalSolver& solver) {
    return run(comm, options, [&](DistributedMesh& part) { return solver.improve(part); });
}

DistributedRunReport improve_distributed(MPI_Comm comm, const DistributedRunOptions& options, LocalSolver& solver) {
    return run(comm, options, [&](DistributedMesh& part) { return solver.improve(part); });
}

std::string DistributedRunReport::to_json() const {
    nlohmann::json j = nlohmann::json::parse(summary.to_json());
    j["parallel"] = {{"ranks", ranks},
                     {"exchange", exchange},
                     {"colors", colors},
                     {"ghost_copies", ghost_copies},
                     {"messages_per_exchange", messages},
                     {"seconds",
                      {{"read", read_seconds},
                       {"partition", timings.partition},
                       {"distribute", timings.distribute},
                       {"schedule", timings.schedule},
                       {"solve", solve_seconds},
                       {"write", write_seconds}}}};
    return j.dump(2);
}

}  // namespace paloverde
