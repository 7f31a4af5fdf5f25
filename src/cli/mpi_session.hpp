#pragma once
// MPI for the `paloverde` program. Launched by mpirun (or another MPI launcher), MPI starts with
// the program; otherwise only a partitioned run starts it (then a one-rank run), so that serial
// commands do not pay for MPI's start-up. Under mpirun every rank runs the command, and only
// rank 0 writes to the console (main silences the others).
namespace paloverde::cli {

class MpiSession {
public:
    MpiSession();   // initializes MPI when an MPI launcher started this process
    ~MpiSession();  // finalizes MPI if it was initialized
    MpiSession(const MpiSession&) = delete;
    MpiSession& operator=(const MpiSession&) = delete;

    // Whether an MPI launcher (mpirun, mpiexec, srun with PMI/PMIx) started this process.
    static bool launched();
    // Initializes MPI if it is not yet (a partitioned run without mpirun: one rank).
    static void ensure();
    static int rank();  // in MPI_COMM_WORLD; 0 without MPI
    static int size();  // ranks of MPI_COMM_WORLD; 1 without MPI
    // The exit code every rank returns: the largest of the ranks' codes (a collective call
    // when MPI runs with more than one rank).
    static int agree(int exit_code);
};

}  // namespace paloverde::cli
