#pragma once
// The exchange between ranks: the reducer (sums exact, so the same bits on any number of ranks)
// and the halo (ghost values from their owners, color by color over the edge-colored schedule,
// or relayed by rank 0: the paper's baseline). DistributedMesh::build_schedule (exchange.cpp)
// makes the schedule.
#include <mpi.h>

#include <memory>

#include "paloverde/parallel/distributed_mesh.hpp"

namespace paloverde::parallel {

std::unique_ptr<Reducer> make_mpi_reducer(MPI_Comm comm);
// The halo keeps a reference to `schedule`.
std::unique_ptr<Halo> make_mpi_halo(MPI_Comm comm, int rank, int ranks, const ExchangeSchedule& schedule);

}  // namespace paloverde::parallel
