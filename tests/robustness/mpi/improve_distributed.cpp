// A distributed improvement run with checkpoints, for tests/robustness (the command line's
// partitioned runs are wired elsewhere). Under mpirun:
//   robustness_mpi_improve IN OUT [--method global|local] [--iterations N] [--checkpoint FILE]
//                          [--every N] [--resume FILE] [--summary FILE] [--pids PREFIX]
// Rank 0 writes OUT and the summary (JSON); errors go to stderr and the exit code is 1. With
// --pids, each rank writes its process id to PREFIX<rank> first: Open MPI puts every rank in a
// process group of its own, so a test that kills the run must kill each rank by its id.
#include <mpi.h>

#include <unistd.h>

#include <fstream>
#include <iostream>
#include <string>

#include "paloverde/core/error.hpp"
#include "paloverde/io/atomic_file.hpp"
#include "paloverde/parallel/distributed_run.hpp"

namespace pv = paloverde;

int main(int argc, char** argv) {
    MPI_Init(&argc, &argv);
    int rank = 0, status = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    try {
        if (argc < 3) throw pv::OptionError("usage: robustness_mpi_improve IN OUT [--method global|local] [--iterations N] "
                                            "[--checkpoint FILE] [--every N] [--resume FILE] [--summary FILE] [--pids PREFIX]");
        pv::DistributedRunOptions run;
        run.input = argv[1];
        run.output = argv[2];
        std::string method = "global", summary_file;
        pv::CheckpointOptions checkpoint;
        int iterations = 500;
        for (int i = 3; i + 1 < argc; i += 2) {
            const std::string flag = argv[i], value = argv[i + 1];
            if (flag == "--method") method = value;
            else if (flag == "--iterations") iterations = std::stoi(value);
            else if (flag == "--checkpoint") checkpoint.file = value;
            else if (flag == "--every") checkpoint.every_iterations = std::stoi(value);
            else if (flag == "--resume") checkpoint.resume = value;
            else if (flag == "--summary") summary_file = value;
            else if (flag == "--pids") std::ofstream(value + std::to_string(rank)) << ::getpid() << "\n";
            else throw pv::OptionError("unknown flag " + flag);
        }
        pv::DistributedRunReport report;
        if (method == "local") {
            pv::LocalSolverOptions local;
            local.termination.max_iterations = iterations;
            local.checkpoint = checkpoint;
            pv::LocalSolver solver(local);
            report = pv::improve_distributed(MPI_COMM_WORLD, run, solver);
        } else {
            pv::GlobalSolverOptions global;
            global.termination.max_iterations = iterations;
            global.checkpoint = checkpoint;
            pv::GlobalSolver solver(global);
            report = pv::improve_distributed(MPI_COMM_WORLD, run, solver);
        }
        if (rank == 0 && !summary_file.empty()) pv::write_text_file(summary_file, report.summary.to_json() + "\n");
    } catch (const std::exception& e) {
        if (rank == 0) std::cerr << "robustness_mpi_improve: " << e.what() << "\n";
        status = 1;
    }
    MPI_Finalize();
    return status;
}
