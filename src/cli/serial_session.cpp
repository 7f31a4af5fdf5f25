// The program's session in a build without MPI (PALOVERDE_MPI=OFF), in place of mpi_session.cpp:
// always one process. Started by an MPI launcher, every process would run the whole command and
// write the same files, so it refuses.
#include "mpi_session.hpp"
#include "paloverde/core/error.hpp"

namespace paloverde::cli {

MpiSession::MpiSession() {
    if (launched()) require("a run under mpirun (or another MPI launcher)");
}

MpiSession::~MpiSession() = default;

void MpiSession::ensure() {}  // nothing to start: config::run refuses a partitioned run itself

void MpiSession::require(const std::string& what) {
    throw Error("this build has no MPI: " + what + " needs Paloverde built with PALOVERDE_MPI=ON");
}

void MpiSession::write_pieces(const Mesh&, int, const std::string&) {
    require("writing pieces for a distributed run");
}

int MpiSession::rank() { return 0; }
int MpiSession::size() { return 1; }
int MpiSession::agree(int exit_code) { return exit_code; }

}  // namespace paloverde::cli
