#pragma once
// MPI for the `paloverde` program. Launched by mpirun (or another MPI launcher), MPI starts with
// the program; otherwise only a partitioned run starts it (then a one-rank run), so that serial
// commands do not pay for MPI's start-up. Under mpirun every rank runs the command, and only
// rank 0 writes to the console (main silences the others).
//
// A build without MPI (PALOVERDE_MPI=OFF) has serial_session.cpp instead of mpi_session.cpp: one
// process, and what needs MPI refuses with "this build has no MPI: ...".
#include <cstdlib>
#include <string>

#include "paloverde/mesh/mesh.hpp"

namespace paloverde::cli {

class MpiSession {
public:
    MpiSession();   // initializes MPI when an MPI launcher started this process (without MPI: throws)
    ~MpiSession();  // finalizes MPI if it was initialized
    MpiSession(const MpiSession&) = delete;
    MpiSession& operator=(const MpiSession&) = delete;

    // Whether an MPI launcher (mpirun, mpiexec, srun with PMI/PMIx) started this process.
    static bool launched() {
        // Open MPI's mpirun, PMIx launchers, and MPICH's hydra (PMI) set these in every process.
        for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"})
            if (std::getenv(name)) return true;
        return false;
    }
    // Initializes MPI if it is not yet (a partitioned run without mpirun: one rank). Without MPI
    // there is none to start, and config::run refuses the run, naming the key that asks for it.
    static void ensure();
    // Throws, in a build without MPI, that `what` needs one.
    static void require(const std::string& what);
    // Writes `whole` split into `parts` pieces for a distributed run (DistributedMesh::write_partitioned).
    static void write_pieces(const Mesh& whole, int parts, const std::string& path);
    static int rank();  // in MPI_COMM_WORLD; 0 without MPI
    static int size();  // ranks of MPI_COMM_WORLD; 1 without MPI
    // The exit code every rank returns: the largest of the ranks' codes (a collective call
    // when MPI runs with more than one rank).
    static int agree(int exit_code);
};

}  // namespace paloverde::cli
