// The distributed run's numbers, as the paper reports them: initialization time by stage (its
// Table 1), the communication of the exchange (Table 2), the solve time (Figs. 3, 5). Run by
// hand under mpirun (examples/parallel_scaling.sh); never timed in CI.
//   mpirun -n P paloverde_parallel_benchmark MESH [--method global|local] [--iterations N]
//          [--exchange colored|root]
#include <mpi.h>

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
        if (rank == 0) std::cout << report.to_json() << "\n";
    } catch (const std::exception& e) {
        if (rank == 0) std::cerr << "paloverde_parallel_benchmark: " << e.what() << "\n";
        status = 1;
    }
    MPI_Finalize();
    return status;
}
