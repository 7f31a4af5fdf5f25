// The distributed run's numbers, as the paper reports them: initialization time by stage (its
// Table 1), the communication of the exchange (Table 2), the solve time (Figs. 3, 5). Run by
// hand under mpirun (examples/study.py); never timed in CI.
//   mpirun -n P paloverde_parallel_benchmark MESH [--method global|local] [--iterations N]
//          [--exchange colored|root]
// Prints the run's report as JSON, with the peak resident memory of the ranks.
#include <mpi.h>
#include <sys/resource.h>

#include <nlohmann/json.hpp>

#include <cstring>
#include <iostream>
#include <string>

#include "paloverde/core/error.hpp"
#include "paloverde/parallel/distributed_run.hpp"

namespace pv = paloverde;

int main(int argc, char** argv) {
    MPI_Init(&argc, &argv);
    int rank = 0, status = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    try {
        if (argc < 2) throw pv::OptionError("usage: paloverde_parallel_benchmark MESH [--method global|local] "
                                            "[--iterations N] [--exchange colored|root]");
        pv::DistributedRunOptions options;
        options.input = argv[1];
        std::string method = "global";
        int iterations = 40;
        for (int i = 2; i + 1 < argc; i += 2) {
            const std::string flag = argv[i], value = argv[i + 1];
            if (flag == "--method") method = value;
            else if (flag == "--iterations") iterations = std::stoi(value);
            else if (flag == "--exchange")
                options.distribute.exchange = value == "root" ? pv::ExchangeMode::RootRelayed : pv::ExchangeMode::Colored;
            else throw pv::OptionError("unknown flag " + flag);
        }
        pv::DistributedRunReport report;
        if (method == "local") {
            pv::LocalSolverOptions local;
            local.threads = 1;
            local.termination.max_iterations = iterations;
            local.termination.min_progress = 0.0;
            pv::LocalSolver solver(local);
            report = pv::improve_distributed(MPI_COMM_WORLD, options, solver);
        } else {
            pv::GlobalSolverOptions global;
            global.threads = 1;
            global.termination.max_iterations = iterations;
            global.termination.min_progress = 0.0;  // run every iteration
            pv::GlobalSolver solver(global);
            report = pv::improve_distributed(MPI_COMM_WORLD, options, solver);
        }
        // Peak resident memory: the sum over the ranks and the largest rank's (bytes per element
        // held decide how large a mesh fits).
        rusage usage{};
        getrusage(RUSAGE_SELF, &usage);
        const long long peak = static_cast<long long>(usage.ru_maxrss) * 1024;  // ru_maxrss is in KiB
        long long total = 0, largest = 0;
        MPI_Reduce(&peak, &total, 1, MPI_LONG_LONG, MPI_SUM, 0, MPI_COMM_WORLD);
        MPI_Reduce(&peak, &largest, 1, MPI_LONG_LONG, MPI_MAX, 0, MPI_COMM_WORLD);
        if (rank == 0) {
            auto json = nlohmann::json::parse(report.to_json());
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
