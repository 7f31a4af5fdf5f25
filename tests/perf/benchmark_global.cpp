// Benchmark of the global solver's passes (run by hand, not a test):
//   paloverde_benchmark MESH [--threads N] [--iterations N]
// Reports, per million elements, a streaming pass that only reads the connectivity and
// coordinate arrays, a pass that gathers each element's corners, the objective pass (qualities
// and the log-barrier sum) and the gradient pass; then the time of N shape iterations.
#include <omp.h>

#include <chrono>
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <string>

#include "metrics/tet_blocks.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/objectives/objective_function.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "solvers/workspace.hpp"

namespace pv = paloverde;
using Clock = std::chrono::steady_clock;

namespace {
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Best of `repeats` runs of f, in seconds.
template <class F>
double best_of(int repeats, F f) {
    double best = 1e300;
    for (int r = 0; r < repeats; ++r) {
        const auto t = Clock::now();
        f();
        best = std::min(best, seconds_since(t));
    }
    return best;
}
}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::cerr << "usage: paloverde_benchmark MESH [--threads N] [--iterations N]\n";
        return 2;
    }
    int threads = 1, iterations = 40;
    for (int i = 2; i + 1 < argc; i += 2) {
        const std::string flag = argv[i];
        if (flag == "--threads") threads = std::atoi(argv[i + 1]);
        else if (flag == "--iterations") iterations = std::atoi(argv[i + 1]);
    }
    omp_set_num_threads(threads);
    try {
        auto t = Clock::now();
        auto file = pv::read_mesh(argv[1]);
        const double read = seconds_since(t);
        const auto& mesh = file.mesh;
        t = Clock::now();
        pv::detail::Workspace work(mesh, true);
        const double setup = seconds_since(t);
        const auto m = static_cast<std::size_t>(work.movable_elements());
        const double per_million = 1e6 / static_cast<double>(m);
        std::cout << argv[1] << ": " << mesh.num_vertices() << " vertices, " << mesh.num_elements() << " elements ("
                  << m << " movable), " << threads << " thread(s)\n"
                  << "read " << read << " s, renumber + setup " << setup << " s\n"
                  << "tetrahedron block kernels: "
                  << (pv::metrics::best_block_path() == pv::metrics::BlockPath::avx2 ? "AVX2" : "baseline (SSE2)") << "\n";

        const auto& wm = work.mesh();
        std::vector<double> x(wm.coordinates().begin(), wm.coordinates().end());
        std::vector<double> q(m), w(m), g(x.size());
        auto metric = pv::make_metric("aspect_ratio");
        metric->set_scale(work.scale());
        pv::LogBarrier barrier;
        const pv::Reducer serial;
        work.evaluate(*metric, x, q);
        barrier.update(q, serial);

        volatile double sink = 0.0;
        const auto conn = wm.connectivity();
        const int k = wm.corners();
        // The floor: read the connectivity and the coordinates once, in order, no indirection.
        const double stream = best_of(5, [&] {
            long long ids = 0;
            double s = 0.0;
#pragma omp parallel for reduction(+ : ids) schedule(static)
            for (std::size_t i = 0; i < m * static_cast<std::size_t>(k); ++i) ids += conn[i];
#pragma omp parallel for reduction(+ : s) schedule(static)
            for (std::size_t i = 0; i < x.size(); ++i) s += x[i];
            sink = sink + s + static_cast<double>(ids);
        });
        // Reading every element's corners through the connectivity (what any pass must do).
        const double gather = best_of(5, [&] {
            double s = 0.0;
#pragma omp parallel for reduction(+ : s) schedule(static)
            for (std::size_t e = 0; e < m; ++e)
                for (int i = 0; i < k; ++i) s += x[3 * static_cast<std::size_t>(conn[e * k + i])];
            sink = sink + s;
        });
        const double objective = best_of(5, [&] {
            work.evaluate(*metric, x, q);
            sink = sink + barrier.value(q, serial);
        });
        const double gradient = best_of(5, [&] {
            barrier.weights(q, w);
            work.gradient(*metric, x, w, g);
        });
        const double t_solve = best_of(5, [&] { barrier.update(q, serial); });
        std::cout << std::fixed << std::setprecision(2) << "t solve (barrier update) " << t_solve * per_million * 1e3
                  << " ns per element\n";
        std::cout << std::fixed << std::setprecision(2) << "per element (ns):  streaming read " << stream * per_million * 1e3
                  << "   corner gather " << gather * per_million * 1e3 << "   objective pass "
                  << objective * per_million * 1e3 << "   gradient pass " << gradient * per_million * 1e3 << "\n"
                  << "gradient pass / streaming read = " << gradient / stream
                  << ",  objective pass / streaming read = " << objective / stream << "\n";

        pv::GlobalSolverOptions options;
        options.threads = threads;
        options.termination.max_iterations = iterations;
        options.termination.min_progress = 0.0;  // run every iteration
        auto copy = mesh;
        const auto summary = pv::GlobalSolver(options).improve(copy);
        const double solve = summary.history.empty() ? 0.0 : summary.history.back().seconds - summary.history.front().seconds;
        std::cout << std::setprecision(3) << summary.iterations << " iterations: " << solve << " s in the iterations ("
                  << solve / std::max(1, summary.iterations) << " s each; " << summary.quality_passes << " quality and "
                  << summary.gradient_passes << " gradient passes), " << summary.seconds
                  << " s in all with assessment before and after\n"
                  << summary.brief_report() << "\n";
    } catch (const std::exception& e) {
        std::cerr << "paloverde_benchmark: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
