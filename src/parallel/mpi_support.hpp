#pragma once
// Small MPI helpers of the parallel layer: datatypes, vectors sent whole, gathers to rank 0 and
// back, and a failed check made a failure on every rank.
#include <mpi.h>

#include <cstdint>
#include <string>
#include <vector>

#include "paloverde/core/error.hpp"
#include "parallel/collective.hpp"

namespace paloverde::parallel {

template <class T>
MPI_Datatype mpi_type();
template <>
inline MPI_Datatype mpi_type<double>() { return MPI_DOUBLE; }
template <>
inline MPI_Datatype mpi_type<std::int32_t>() { return MPI_INT32_T; }
template <>
inline MPI_Datatype mpi_type<std::int64_t>() { return MPI_INT64_T; }
template <>
inline MPI_Datatype mpi_type<std::uint8_t>() { return MPI_UINT8_T; }

// Whether MPI can be called: initialized and not yet finalized.
inline bool mpi_running() {
    int initialized = 0, finalized = 0;
    MPI_Initialized(&initialized);
    if (!initialized) return false;
    MPI_Finalized(&finalized);
    return !finalized;
}
inline int rank_in(MPI_Comm comm) {
    int rank = 0;
    MPI_Comm_rank(comm, &rank);
    return rank;
}
inline int ranks_in(MPI_Comm comm) {
    int ranks = 1;
    MPI_Comm_size(comm, &ranks);
    return ranks;
}
// Collective: every rank gets rank 0's `count` values.
template <class T>
void broadcast_from_root(MPI_Comm comm, T* values, int count) {
    MPI_Bcast(values, count, mpi_type<T>(), 0, comm);
}

template <class T>
void send_vector(const std::vector<T>& data, int to, int tag, MPI_Comm comm) {
    const std::int64_t size = static_cast<std::int64_t>(data.size());
    MPI_Send(&size, 1, MPI_INT64_T, to, tag, comm);
    if (size > 0) MPI_Send(data.data(), static_cast<int>(size), mpi_type<T>(), to, tag, comm);
}

template <class T>
std::vector<T> receive_vector(int from, int tag, MPI_Comm comm) {
    std::int64_t size = 0;
    MPI_Recv(&size, 1, MPI_INT64_T, from, tag, comm, MPI_STATUS_IGNORE);
    std::vector<T> data(static_cast<std::size_t>(size));
    if (size > 0) MPI_Recv(data.data(), static_cast<int>(size), mpi_type<T>(), from, tag, comm, MPI_STATUS_IGNORE);
    return data;
}

// Collective: each rank's values, concatenated in rank order on rank 0, with each rank's count.
template <class T = std::int64_t>
struct Gathered {
    std::vector<T> values;
    std::vector<int> counts;
};
template <class T>
Gathered<T> gather_to_root(MPI_Comm comm, const std::vector<T>& mine) {
    int rank = 0, ranks = 1;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &ranks);
    Gathered<T> out;
    int count = static_cast<int>(mine.size());
    if (rank == 0) out.counts.resize(static_cast<std::size_t>(ranks));
    MPI_Gather(&count, 1, MPI_INT, out.counts.data(), 1, MPI_INT, 0, comm);
    std::vector<int> offsets(out.counts.size(), 0);
    for (std::size_t p = 1; p < offsets.size(); ++p) offsets[p] = offsets[p - 1] + out.counts[p - 1];
    if (rank == 0) out.values.resize(static_cast<std::size_t>(offsets.back() + out.counts.back()));
    MPI_Gatherv(mine.data(), count, mpi_type<T>(), out.values.data(), out.counts.data(), offsets.data(), mpi_type<T>(), 0, comm);
    return out;
}
// Collective: each rank's values, concatenated in rank order on every rank.
template <class T>
std::vector<T> gather_to_all(MPI_Comm comm, const std::vector<T>& mine) {
    int ranks = 1;
    MPI_Comm_size(comm, &ranks);
    int count = static_cast<int>(mine.size());
    std::vector<int> counts(static_cast<std::size_t>(ranks));
    MPI_Allgather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, comm);
    std::vector<int> offsets(counts.size(), 0);
    for (std::size_t p = 1; p < offsets.size(); ++p) offsets[p] = offsets[p - 1] + counts[p - 1];
    std::vector<T> all(static_cast<std::size_t>(offsets.back() + counts.back()));
    MPI_Allgatherv(mine.data(), count, mpi_type<T>(), all.data(), counts.data(), offsets.data(), mpi_type<T>(), comm);
    return all;
}
// The inverse of gather_to_root: rank 0's values cut by `counts`, `expected` of them to each rank.
inline std::vector<std::int64_t> scatter_from_root(MPI_Comm comm, const std::vector<std::int64_t>& values,
                                            const std::vector<int>& counts, std::size_t expected) {
    std::vector<int> offsets(counts.size(), 0);
    for (std::size_t p = 1; p < offsets.size(); ++p) offsets[p] = offsets[p - 1] + counts[p - 1];
    std::vector<std::int64_t> mine(expected);
    MPI_Scatterv(values.data(), counts.data(), offsets.data(), MPI_INT64_T, mine.data(), static_cast<int>(expected),
                 MPI_INT64_T, 0, comm);
    return mine;
}

// Collective: when a check failed on any rank (a non-empty message), it fails on every rank as a
// MeshError, with the lowest failing rank's message.
inline void agree(MPI_Comm comm, const std::string& failure) {
    parallel::together(comm, !failure.empty(), [&] { throw MeshError(failure); });
}

}  // namespace paloverde::parallel
