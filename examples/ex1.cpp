// Example 1: read a mesh, untangle it and raise its worst element with the global solver, write
// the result. The MPI twin is ex1p.cpp.
//
//   ex1 [IN] [OUT]     defaults: the bundled tangled cube, ex1_out.vtu
//
// Exit codes: 0 improved (or already fine), 1 the solver failed or an error (a bad file names
// its line), the mesh written either way once read: the solver hands back its best iterate,
// never one worse than the input.
#include <iostream>
#include <string>

#include <paloverde/io/mesh_io.hpp>
#include <paloverde/solvers/global_solver.hpp>

int main(int argc, char** argv) try {
    const std::string input = argc > 1 ? argv[1] : PALOVERDE_EXAMPLE_MESH;
    const std::string output = argc > 2 ? argv[2] : "ex1_out.vtu";

    // [ex1]
    auto file = paloverde::read_mesh(input);   // any format; errors name the file and line
    paloverde::GlobalSolverOptions options;    // checked by the solver; errors name the option
    options.termination.max_iterations = 200;
    const paloverde::Summary summary = paloverde::GlobalSolver(options).improve(file.mesh);
    std::cout << summary.full_report();        // why it stopped, quality before and after
    paloverde::write_mesh(output, file.mesh);  // through a temporary file and a rename
    // [ex1]

    return summary.success() ? 0 : 1;
} catch (const std::exception& e) {
    std::cerr << "ex1: " << e.what() << "\n";
    return 1;
}
