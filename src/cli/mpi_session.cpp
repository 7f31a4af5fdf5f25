#include "mpi_session.hpp"

#include <mpi.h>

#include "paloverde/parallel/distributed_mesh.hpp"

namespace paloverde::cli {

namespace {
bool running() {
    int initialized = 0, finalized = 0;
    MPI_Initialized(&initialized);
    if (!initialized) return false;
    MPI_Finalized(&finalized);
    return !finalized;
}
}  // namespace

MpiSession::MpiSession() {
    if (launched()) ensure();
}

MpiSession::~MpiSession() {
    if (running()) MPI_Finalize();
}

void MpiSession::ensure() {
    int initialized = 0;
    MPI_Initialized(&initialized);
    if (initialized) return;
    // Solvers use OpenMP threads inside a rank; only the main thread calls MPI.
    int provided = 0;
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
}

void MpiSession::require(const std::string&) {}  // this build has MPI

void MpiSession::write_pieces(const Mesh& whole, int parts, const std::string& path) {
    DistributedMesh::write_partitioned(whole, parts, path);
}

int MpiSession::rank() {
    if (!running()) return 0;
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    return rank;
}

int MpiSession::size() {
    if (!running()) return 1;
    int size = 1;
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    return size;
}

int MpiSession::agree(int exit_code) {
    if (size() <= 1) return exit_code;
    MPI_Allreduce(MPI_IN_PLACE, &exit_code, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    return exit_code;
}

}  // namespace paloverde::cli
