// Example 2: an instruction queue (Mesquite's word): assess the mesh, untangle and smooth it with
// the local smoother, then raise its worst element with the global solver under a termination of
// our own (a time limit and a target worst quality), assess it again. An observer prints the
// progress of every solver.
//
//   ex2 [IN] [OUT]     defaults: the shared mesh tire.vtk perturbed by 0.2 edge lengths, ex2_out.vtu
#include <iostream>
#include <memory>
#include <string>

#include <paloverde/io/mesh_io.hpp>
#include <paloverde/mesh/perturb.hpp>
#include <paloverde/solvers/global_solver.hpp>
#include <paloverde/solvers/instruction_queue.hpp>
#include <paloverde/solvers/local_solver.hpp>

int main(int argc, char** argv) try {
    const std::string output = argc > 2 ? argv[2] : "ex2_out.vtu";
    auto file = paloverde::read_mesh(argc > 1 ? argv[1] : PALOVERDE_EXAMPLE_SHARED_MESH);
    if (argc <= 1) {  // make the shared mesh worth improving: some interior vertices moved
        paloverde::PerturbOptions moves;
        moves.fraction = 0.3;
        moves.amount = 0.2;
        paloverde::perturb(file.mesh, moves);
    }

    // [ex2]
    paloverde::LocalSolverOptions local;  // untangles, then a few sweeps over the worst vertices
    local.termination.max_iterations = 10;

    paloverde::GlobalSolverOptions global;
    global.termination.max_seconds = 60.0;             // whichever comes first
    global.termination.target_worst_quality = 0.5;     // aspect ratio, the default metric
    global.termination.max_iterations = 300;

    paloverde::InstructionQueue queue;
    queue.assess("input")
        .improve("local", std::make_unique<paloverde::LocalSolver>(local))
        .improve("global", std::make_unique<paloverde::GlobalSolver>(global))
        .assess("output")
        .observe([](std::string_view label, const paloverde::IterationRecord& r) {
            if (r.iteration % 25 == 0)
                std::cout << label << " " << r.phase << " iteration " << r.iteration << ": worst " << r.best_worst_quality
                          << "\n";
        });
    const paloverde::QueueResult result = queue.run(file.mesh);
    std::cout << result.report();  // both assessments as tables, each solver's summary
    // [ex2]

    paloverde::write_mesh(output, file.mesh, {}, file.point_fields, file.cell_fields);
    return result.success ? 0 : 1;
} catch (const std::exception& e) {
    std::cerr << "ex2: " << e.what() << "\n";
    return 1;
}
