// A distributed improvement run with checkpoints, for tests/robustness: a run config of one
// improve step (config::run, as `paloverde improve` under mpirun), whose summary is the solver's
// own. Under mpirun:
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
#include <vector>

#include "paloverde/config/run.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/io/atomic_file.hpp"

namespace pv = paloverde;
namespace cfg = paloverde::config;

int main(int argc, char** argv) {
    MPI_Init(&argc, &argv);
    int rank = 0, ranks = 1, status = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &ranks);
    try {
        if (argc < 3) throw pv::OptionError("usage: robustness_mpi_improve IN OUT [--method global|local] [--iterations N] "
                                            "[--checkpoint FILE] [--every N] [--resume FILE] [--summary FILE] [--pids PREFIX]");
        const std::string step = "queue[0].improve.";
        std::vector<cfg::Override> set{{"input.mesh=" + std::string(argv[1]), "IN", true},
                                       {"output.mesh=" + std::string(argv[2]), "OUT", true},
                                       {"partition.parts=" + std::to_string(ranks)},
                                       {step + "name=global"},
                                       {step + "termination.max_iterations=500"}};
        std::string summary_file;
        for (int i = 3; i + 1 < argc; i += 2) {
            const std::string flag = argv[i], value = argv[i + 1];
            if (flag == "--method") set.push_back({step + "name=" + value});
            else if (flag == "--iterations") set.push_back({step + "termination.max_iterations=" + value});
            else if (flag == "--checkpoint") set.push_back({step + "checkpoint.file=" + value, flag, true});
            else if (flag == "--every") set.push_back({step + "checkpoint.every_iterations=" + value});
            else if (flag == "--resume") set.push_back({step + "checkpoint.resume=" + value, flag, true});
            else if (flag == "--summary") summary_file = value;
            else if (flag == "--pids") std::ofstream(value + std::to_string(rank)) << ::getpid() << "\n";
            else throw pv::OptionError("unknown flag " + flag);
        }
        const cfg::RunResult result = cfg::run(cfg::parse_config("", "robustness_mpi_improve", set));
        const auto& summary = std::get<pv::Summary>(result.methods.at(0).queue.steps.at(0).outcome);
        if (rank == 0 && !summary_file.empty()) pv::write_text_file(summary_file, summary.to_json() + "\n");
    } catch (const std::exception& e) {
        if (rank == 0) std::cerr << "robustness_mpi_improve: " << e.what() << "\n";
        status = 1;
    }
    MPI_Finalize();
    return status;
}
