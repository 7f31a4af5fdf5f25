#pragma once
// A whole distributed improvement run, as the command line does it: get the mesh onto the ranks
// (rank 0 reads and partitions one file, or every rank reads its piece), run the global solver,
// write the result (gathered into one file by rank 0, or as pieces), and report the paper's
// numbers: initialization time by stage, communication volume, solve time.
#include <mpi.h>

#include <cstdint>
#include <filesystem>
#include <string>

#include "paloverde/parallel/distributed_mesh.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "paloverde/solvers/local_solver.hpp"

namespace paloverde {

struct DistributedRunOptions {
    std::filesystem::path input;   // a mesh file, or pieces: OUT.pvtu (or OUT.vtk with `pieces`)
    bool pieces = false;           // input names pieces (implied by .pvtu)
    std::filesystem::path output;  // .pvtu: pieces; any other mesh format: one file from rank 0; empty: none
    bool fix_boundary = true;      // for a whole-file input without a `fixed` field
    DistributeOptions distribute;
    void validate() const;         // throws OptionError
};

struct DistributedRunReport {
    Summary summary;
    int ranks = 1;
    double read_seconds = 0.0;     // rank 0 reading the file (or the slowest rank reading its piece)
    DistributeTimings timings;     // partition, distribute, schedule
    double solve_seconds = 0.0;
    double write_seconds = 0.0;
    std::int64_t ghost_copies = 0;   // ghost values received per exchange, summed over ranks
    std::int64_t messages = 0;       // point-to-point messages per exchange, summed over ranks
    int colors = 0;                  // rounds of the colored exchange
    std::string exchange;            // "colored" or "root_relayed"

    std::string to_json() const;
};

// Collective over `comm`; every rank returns the same report. Errors (unreadable input, bad
// pieces, options) are thrown on every rank.
DistributedRunReport improve_distributed(MPI_Comm comm, const DistributedRunOptions& options, GlobalSolver& solver);
DistributedRunReport improve_distributed(MPI_Comm comm, const DistributedRunOptions& options, LocalSolver& solver);

}  // namespace paloverde
