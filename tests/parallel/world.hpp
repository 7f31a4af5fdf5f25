#pragma once
// This process's rank and the number of ranks in MPI_COMM_WORLD, for the tests of tests/parallel.
#include <mpi.h>

namespace paloverde::test {

inline int rank() {
    int r = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &r);
    return r;
}
inline int ranks() {
    int n = 1;
    MPI_Comm_size(MPI_COMM_WORLD, &n);
    return n;
}

}  // namespace paloverde::test
