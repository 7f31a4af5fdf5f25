#pragma once
// The one way a distributed run fails: together, with one exit code.
#include <mpi.h>

#include <exception>
#include <limits>
#include <string>

#include "paloverde/core/error.hpp"

namespace paloverde::parallel {

// Collective: runs `work` where `here` is true (on rank 0 alone, or on every rank), and makes a
// failure anywhere a failure everywhere, so that no rank waits for one that gave up. The lowest
// failing rank rethrows its own exception; every other rank throws one of the same kind with the
// same message: OptionError (a usage error: exit code 2), MeshError, or Error (exit code 1).
template <class Work>
void together(MPI_Comm comm, bool here, Work&& work) {
    std::exception_ptr failure;
    std::string message;
    int kind = 0;  // 0: none, 1: OptionError, 2: MeshError, 3: anything else
    if (here) {
        try {
            work();
        } catch (const OptionError& e) {
            failure = std::current_exception(), message = e.what(), kind = 1;
        } catch (const MeshError& e) {
            failure = std::current_exception(), message = e.what(), kind = 2;
        } catch (const std::exception& e) {
            failure = std::current_exception(), message = e.what(), kind = 3;
        } catch (...) {
            failure = std::current_exception(), message = "unknown error", kind = 3;
        }
    }
    int rank = 0;
    MPI_Comm_rank(comm, &rank);
    int lowest = kind != 0 ? rank : std::numeric_limits<int>::max();
    MPI_Allreduce(MPI_IN_PLACE, &lowest, 1, MPI_INT, MPI_MIN, comm);
    if (lowest == std::numeric_limits<int>::max()) return;
    int header[2] = {kind, static_cast<int>(message.size())};
    MPI_Bcast(header, 2, MPI_INT, lowest, comm);
    message.resize(static_cast<std::size_t>(header[1]));
    MPI_Bcast(message.data(), header[1], MPI_CHAR, lowest, comm);
    if (rank == lowest) std::rethrow_exception(failure);
    if (header[0] == 1) throw OptionError(message);
    if (header[0] == 2) throw MeshError(message);
    throw Error(message);
}

}  // namespace paloverde::parallel
