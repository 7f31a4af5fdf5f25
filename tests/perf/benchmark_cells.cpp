// Benchmark of both solvers on tangled structured meshes of cells (run by hand, not a test):
//   paloverde_cell_benchmark [--n N] [--seeds S] [--fill hexahedra|wedges|pyramids|mixed|tetrahedra]
//                            [--fraction F] [--amount A] [--threads T] [--write DIR]
// An N^3 grid of unit cubes filled with the chosen cells (tetrahedra: Kuhn's six per cube, the
// simplex mesh of the same vertices), F of its interior vertices moved by up to A edge lengths
// (seeds 1..S). Per seed and solver: inverted cells before and after, worst aspect ratio after,
// iterations, seconds, and microseconds per iteration per cell and per corner simplex.
// --write DIR: write each seed's tangled grid to DIR/grid-N-seedS.vtk instead of solving, as
// input for other runs (docs/cells.md's distributed runs).
#include <omp.h>

#include <cstdlib>
#include <exception>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <string>

#include "paloverde/core/memory.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/orientation.hpp"
#include "paloverde/mesh/perturb.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "paloverde/solvers/local_solver.hpp"
#include "support/cell_meshes.hpp"

namespace pv = paloverde;

int main(int argc, char** argv) {
    paloverde::keep_freed_memory();  // as the command line does
    int n = 47, seeds = 3, threads = 1;
    double fraction = 0.2, amount = 0.5;
    std::string write_to;
    pv::test::Fill fill = pv::test::Fill::Hexahedra;
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string key = argv[i], value = argv[i + 1];
        if (key == "--n") n = std::stoi(value);
        else if (key == "--seeds") seeds = std::stoi(value);
        else if (key == "--threads") threads = std::stoi(value);
        else if (key == "--fraction") fraction = std::stod(value);
        else if (key == "--amount") amount = std::stod(value);
        else if (key == "--write") write_to = value;
        else if (key == "--fill") {
            const char* names[] = {"hexahedra", "wedges", "pyramids", "mixed", "tetrahedra"};
            int f = 0;
            while (f < 5 && value != names[f]) ++f;
            if (f == 5) {
                std::cerr << "unknown fill '" << value << "'\n";
                return 2;
            }
            fill = static_cast<pv::test::Fill>(f);
        } else {
            std::cerr << "unknown option " << key << "\n";
            return 2;
        }
    }
    omp_set_num_threads(threads);
    const pv::Mesh grid = pv::test::cube_grid(n, fill);
    std::cout << "grid " << n << "^3: " << grid.num_cells() << " cells, " << grid.num_elements() << " corner simplices, "
              << grid.num_vertices() << " vertices; " << threads << " thread(s)\n";
    auto tangled = [&](int seed) {
        pv::Mesh mesh = grid;
        pv::PerturbOptions perturb;
        perturb.fraction = fraction;
        perturb.amount = amount;
        perturb.seed = static_cast<std::uint64_t>(seed);
        pv::perturb(mesh, perturb);
        return mesh;
    };
    if (!write_to.empty()) {
        for (int seed = 1; seed <= seeds; ++seed) {
            const pv::Mesh mesh = tangled(seed);
            const auto path = std::filesystem::path(write_to) /
                              ("grid-" + std::to_string(n) + "-seed" + std::to_string(seed) + ".vtk");
            try {
                pv::write_mesh(path, mesh);
            } catch (const std::exception& e) {
                std::cerr << e.what() << "\n";
                return 1;
            }
            std::cout << path.string() << "\n";
        }
        return 0;
    }
    std::cout << "seed solver    inverted_before inverted_after worst_after iterations seconds us/it/cell us/it/corner\n";
    for (int seed = 1; seed <= seeds; ++seed)
        for (int method : {0, 1}) {
            pv::Mesh mesh = tangled(seed);
            pv::Summary s;
            if (method == 0) {
                pv::GlobalSolverOptions o;
                o.threads = threads;
                s = pv::GlobalSolver(o).improve(mesh);
            } else {
                pv::LocalSolverOptions o;
                o.threads = threads;
                s = pv::LocalSolver(o).improve(mesh);
            }
            const double per_iteration = s.seconds / std::max(1, s.iterations);
            std::cout << std::setw(4) << seed << " " << std::setw(6) << (method == 0 ? "global" : "local") << std::setw(18)
                      << s.before.inverted << std::setw(15) << s.after.inverted << std::setw(12) << std::setprecision(5)
                      << s.worst_after << std::setw(11) << s.iterations << std::setw(8) << std::setprecision(3) << s.seconds
                      << std::setw(12) << std::setprecision(3) << 1e6 * per_iteration / grid.num_cells() << std::setw(13)
                      << 1e6 * per_iteration / grid.num_elements() << "\n";
        }
}
