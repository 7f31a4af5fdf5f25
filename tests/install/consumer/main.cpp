// Improves a one-free-vertex tet mesh through the installed library and checks the result.
#include <iostream>
#include <paloverde/assess/quality_assessor.hpp>
#include <paloverde/solvers/global_solver.hpp>

int main() {
    // Four tets around vertex 4, which starts off-centre; the outer vertices are the boundary.
    paloverde::Mesh mesh(paloverde::ElementKind::Tetrahedron,
                         {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0.05, 0.05, 0.05, 1, 1, 1},
                         {0, 1, 2, 4, 0, 3, 1, 4, 0, 2, 3, 4, 1, 5, 2, 3});
    mesh.set_fixed({1, 1, 1, 1, 0, 1});
    const auto summary = paloverde::GlobalSolver().improve(mesh);
    std::cout << summary.brief_report() << "\n";
    return summary.valid() && summary.worst_after > summary.worst_before ? 0 : 1;
}
