// Example 1p: example 1 over MPI. Rank 0 reads the mesh and splits it (METIS), every rank improves
// its part with the same global solver (all vertices move at once; the result is the serial one
// bit for bit, on any number of ranks), and rank 0 gathers the coordinates and writes the mesh.
//
//   mpirun -n 4 ex1p [IN] [OUT]     defaults: the bundled tangled cube, ex1p_out.vtu
//
// A mesh too large for one rank would be read as pieces instead (DistributedMesh::read_pieces,
// written by `paloverde partition`).
#include <mpi.h>

#include <iostream>
#include <string>

#include <paloverde/io/mesh_io.hpp>
#include <paloverde/parallel/distributed_mesh.hpp>
#include <paloverde/solvers/global_solver.hpp>

namespace {
// Runs `work` on rank 0 and tells every rank whether it succeeded, so that no rank waits for a
// rank 0 that gave up.
template <class Work>
bool on_rank_0(int rank, Work&& work) {
    int ok = 1;
    if (rank == 0) try {
            work();
        } catch (const std::exception& e) {
            std::cerr << "ex1p: " << e.what() << "\n";
            ok = 0;
        }
    MPI_Bcast(&ok, 1, MPI_INT, 0, MPI_COMM_WORLD);
    return ok == 1;
}
}  // namespace

int main(int argc, char** argv) {
    MPI_Init(&argc, &argv);
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    const std::string input = argc > 1 ? argv[1] : PALOVERDE_EXAMPLE_MESH;
    const std::string output = argc > 2 ? argv[2] : "ex1p_out.vtu";
    int code = 1;

    // [ex1p]
    paloverde::MeshFile file;  // the whole mesh, on rank 0 only
    if (on_rank_0(rank, [&] { file = paloverde::read_mesh(input); })) {
        auto part = paloverde::DistributedMesh::scatter(MPI_COMM_WORLD, rank == 0 ? &file.mesh : nullptr);
        paloverde::GlobalSolverOptions options;
        options.termination.max_iterations = 200;
        const paloverde::Summary summary = paloverde::GlobalSolver(options).improve(part);  // the same on every rank
        part.gather_coordinates(rank == 0 ? &file.mesh : nullptr);
        if (rank == 0) std::cout << summary.full_report();
        if (on_rank_0(rank, [&] { paloverde::write_mesh(output, file.mesh); })) code = summary.success() ? 0 : 1;
    }
    // [ex1p]

    MPI_Finalize();
    return code;
}
