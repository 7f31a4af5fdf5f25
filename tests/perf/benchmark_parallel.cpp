// The distributed run's numbers, as the paper reports them: initialization time by stage (its
// Table 1), the communication of the exchange (Table 2), the solve time (Figs. 3, 5). Run by
// hand under mpirun (examples/study.py); never timed in CI. Every rank count runs the
// distributed code, 1 included (a config run on one rank would be the serial one).
//   mpirun -n P paloverde_parallel_benchmark MESH [--method global|local] [--iterations N]
//          [--exchange colored|root]
// Prints the solver's summary as JSON with "parallel" (as a partitioned config run reports it)
// and the peak resident memory of the ranks.
#include <mpi.h>
#include <sys/resource.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <iostream>
#include <memory>
#include <string>

#include "paloverde/core/error.hpp"
#include "paloverde/core/memory.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/parallel/distributed_mesh.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "paloverde/solvers/local_solver.hpp"
#include "parallel/collective.hpp"

namespace pv = paloverde;

namespace {
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }
}  // namespace

int main(int argc, char** argv) {
    paloverde::keep_freed_memory();  // as the command line does
    MPI_Init(&argc, &argv);
    int rank = 0, ranks = 1, status = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &ranks);
    try {
        if (argc < 2) throw pv::OptionError("usage: paloverde_parallel_benchmark MESH [--method global|local] "
                                            "[--iterations N] [--exchange colored|root]");
        std::string method = "global";
        int iterations = 40;
        pv::DistributeOptions distribute;
        for (int i = 2; i + 1 < argc; i += 2) {
            const std::string flag = argv[i], value = argv[i + 1];
            if (flag == "--method") method = value;
            else if (flag == "--iterations") iterations = std::stoi(value);
            else if (flag == "--exchange")
                distribute.exchange = value == "root" ? pv::ExchangeMode::RootRelayed : pv::ExchangeMode::Colored;
            else throw pv::OptionError("unknown flag " + flag);
        }
        std::unique_ptr<pv::Solver> solver;
        if (method == "local") {
            pv::LocalSolverOptions local;
            local.threads = 1;
            local.termination.max_iterations = iterations;
            local.termination.min_progress = 0.0;
            solver = std::make_unique<pv::LocalSolver>(local);
        } else {
            pv::GlobalSolverOptions global;
            global.threads = 1;
            global.termination.max_iterations = iterations;
            global.termination.min_progress = 0.0;  // run every iteration
            solver = std::make_unique<pv::GlobalSolver>(global);
        }

        // Rank 0 reads and splits the mesh, as `paloverde run` does (a failure there stops every rank).
        auto start = Clock::now();
        pv::Mesh whole;
        pv::parallel::together(MPI_COMM_WORLD, rank == 0, [&] { whole = pv::read_mesh(argv[1]).mesh; });
        double read_seconds = seconds_since(start);
        MPI_Bcast(&read_seconds, 1, MPI_DOUBLE, 0, MPI_COMM_WORLD);
        auto part = pv::DistributedMesh::scatter(MPI_COMM_WORLD, rank == 0 ? &whole : nullptr, distribute);
        whole = pv::Mesh();

        MPI_Barrier(MPI_COMM_WORLD);
        start = Clock::now();
        const pv::Summary summary = solver->improve(part);
        const double solve_seconds = part.reducer().max(seconds_since(start));

        double timings[3] = {part.timings().partition, part.timings().distribute, part.timings().schedule};
        MPI_Bcast(timings, 3, MPI_DOUBLE, 0, MPI_COMM_WORLD);
        const auto ghost_copies = static_cast<std::int64_t>(part.reducer().total(static_cast<double>(part.received_vertices())));
        const auto messages = static_cast<std::int64_t>(part.reducer().total(static_cast<double>(part.schedule().partners.size())));
        // Peak resident memory: the sum over the ranks and the largest rank's (bytes per element
        // held decide how large a mesh fits).
        rusage usage{};
        getrusage(RUSAGE_SELF, &usage);
        const long long peak = static_cast<long long>(usage.ru_maxrss) * 1024;  // ru_maxrss is in KiB
        long long total = 0, largest = 0;
        MPI_Reduce(&peak, &total, 1, MPI_LONG_LONG, MPI_SUM, 0, MPI_COMM_WORLD);
        MPI_Reduce(&peak, &largest, 1, MPI_LONG_LONG, MPI_MAX, 0, MPI_COMM_WORLD);
        if (rank == 0) {
            auto json = nlohmann::json::parse(summary.to_json());
            json["parallel"] = {
                {"ranks", ranks},
                {"exchange", distribute.exchange == pv::ExchangeMode::Colored ? "colored" : "root_relayed"},
                {"colors", part.schedule().colors},
                {"ghost_copies", ghost_copies},
                {"messages_per_exchange", messages},
                {"seconds",
                 {{"read", read_seconds},
                  {"partition", timings[0]},
                  {"distribute", timings[1]},
                  {"schedule", timings[2]},
                  {"solve", solve_seconds},
                  {"write", 0.0}}}};
            json["memory"] = {{"peak_rss_bytes_total", total}, {"peak_rss_bytes_largest_rank", largest}};
            std::cout << json.dump(2) << "\n";
        }
    } catch (const std::exception& e) {
        if (rank == 0) std::cerr << "paloverde_parallel_benchmark: " << e.what() << "\n";
        status = 1;
    }
    MPI_Finalize();
    return status;
}
