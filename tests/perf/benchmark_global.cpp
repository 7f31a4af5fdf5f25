// Benchmark of the global solver's passes (run by hand, not a test):
//   paloverde_benchmark MESH [--threads N] [--iterations N] [--keep FACTORS]
// (--keep: targets that keep these factors of the input, docs/targets.md, rated with the metric
// they ask for; the passes then carry every element through its target.)
// Reports, per element, a streaming pass that only reads the connectivity and coordinate
// arrays, the objective pass (qualities and the log-barrier sum) and the gradient pass, with the
// parts of the latter (gather, rate, gradients, scatter); then the time of N shape iterations.
// Also the set-up's parts and the time of one full quality report.
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <string>

#include "metrics/tet_blocks.hpp"
#include "paloverde/assess/quality_assessor.hpp"
#include "paloverde/core/memory.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/renumber.hpp"
#include "paloverde/metrics/targets.hpp"
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

const char* block_path_name(pv::metrics::BlockPath path) {
    switch (path) {
        case pv::metrics::BlockPath::avx512: return "AVX-512";
        case pv::metrics::BlockPath::avx2: return "AVX2";
        case pv::metrics::BlockPath::baseline: break;
    }
    return "baseline (SSE2)";
}
}  // namespace

int main(int argc, char** argv) {
    paloverde::keep_freed_memory();  // as the command line does
    if (argc < 2) {
        std::cerr << "usage: paloverde_benchmark MESH [--threads N] [--iterations N] [--keep FACTORS]\n";
        return 2;
    }
    int threads = 1, iterations = 40;
    std::string keep;
    for (int i = 2; i + 1 < argc; i += 2) {
        const std::string flag = argv[i];
        if (flag == "--threads") threads = std::atoi(argv[i + 1]);
        else if (flag == "--iterations") iterations = std::atoi(argv[i + 1]);
        else if (flag == "--keep") keep = argv[i + 1];
    }
    omp_set_num_threads(threads);
    try {
        auto t = Clock::now();
        auto file = pv::read_mesh(argv[1]);
        const double read = seconds_since(t);
        auto& mesh = file.mesh;
        const pv::TargetOptions targets = pv::TargetOptions::from(keep);
        pv::set_targets(mesh, targets);
        const std::string metric_name = targets.metric("aspect_ratio");
        t = Clock::now();
        pv::detail::Workspace work(mesh, true);
        const double setup = seconds_since(t);
        // The set-up's larger parts on their own: the vertex graph, the whole locality order
        // (graph included), and a copy of the mesh (which builds its vertex-element adjacency).
        const double graph = best_of(1, [&] { pv::vertex_graph(mesh); });
        const double locality = best_of(1, [&] { pv::locality_vertex_order(mesh); });
        const double mesh_copy = best_of(1, [&] { pv::Mesh(mesh.kind(), std::vector<double>(mesh.coordinates().begin(), mesh.coordinates().end()),
                                                      std::vector<pv::VertexId>(mesh.connectivity().begin(), mesh.connectivity().end())); });
        const auto m = static_cast<std::size_t>(work.movable_elements());
        const double per_million = 1e6 / static_cast<double>(m);
        std::cout << argv[1] << ": " << mesh.num_vertices() << " vertices, " << mesh.num_elements() << " elements ("
                  << m << " movable), " << threads << " thread(s), rated with " << metric_name
                  << (mesh.has_targets() ? " against targets" : "")
                  << (mesh.target_metric_roots().empty() ? "" : " (simplices in their neighbourhood's metric)") << "\n"
                  << "read " << read << " s, renumber + setup " << setup << " s (vertex graph " << graph
                  << " s, locality order " << locality << " s, a mesh copy " << mesh_copy << " s)\n"
                  << "tetrahedron block kernels: "
                  << block_path_name(pv::metrics::best_block_path()) << "\n";
        // The quality report a run prints before and after (every metric), best of 3.
        const double report = best_of(3, [&] { pv::QualityAssessor().assess(mesh); });
        std::cout << "quality report (every metric) " << report << " s\n";

        const auto& wm = work.mesh();
        std::vector<double> x(wm.coordinates().begin(), wm.coordinates().end());
        std::vector<double> q(m), w(m), g(x.size());
        auto metric = pv::make_metric(metric_name);
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
        // What the gradient pass is made of: gathering each block of elements' corners, then
        // also rating them, then also their gradients (the rest of the pass is the weighted
        // scatter to the vertices and adding up the lanes).
        namespace pm = pv::metrics;
        const pm::BlockPath path = pm::best_block_path();
        const auto* conn_data = conn.data();
        auto over_blocks = [&](auto rate) {
            double s = 0.0;
#pragma omp parallel for reduction(+ : s) schedule(static)
            for (std::size_t b = 0; b < m; b += pm::kTetBlock) {
                pm::TetBlock corners, gradient;
                alignas(64) double quality[pm::kTetBlock];
                const int count = static_cast<int>(std::min<std::size_t>(pm::kTetBlock, m - b));
                pm::gather_tets(conn_data + 4 * b, x.data(), count, corners);
                s += rate(corners, quality, gradient);
            }
            sink = sink + s;
        };
        const bool tets = wm.kind() == pv::ElementKind::Tetrahedron;
        const double gather = !tets ? 0.0 : best_of(5, [&] {
            over_blocks([](const pm::TetBlock& c, double*, pm::TetBlock&) { return c.at[0][0]; });
        });
        const double rate = !tets ? 0.0 : best_of(5, [&] {
            over_blocks([&](const pm::TetBlock& c, double* q, pm::TetBlock&) {
                pm::tet_aspect_block(path, c, q, nullptr);
                return q[0];
            });
        });
        const double rate_gradient = !tets ? 0.0 : best_of(5, [&] {
            over_blocks([&](const pm::TetBlock& c, double* q, pm::TetBlock& g) {
                pm::tet_aspect_block(path, c, q, &g);
                return g.at[0][0];
            });
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
        const double ns = per_million * 1e3;
        std::cout << std::fixed << std::setprecision(2) << "per element (ns):  streaming read " << stream * ns
                  << "   objective pass " << objective * ns << "   gradient pass " << gradient * ns << "\n";
        if (tets)
            std::cout << "  inside the gradient pass: corner gather " << gather * ns << ", + qualities " << rate * ns
                      << ", + their gradients " << rate_gradient * ns << "; weighted scatter and lane sums "
                      << (gradient - rate_gradient) * ns << "\n";
        std::cout << "gradient pass / streaming read = " << gradient / stream
                  << ",  objective pass / streaming read = " << objective / stream << "\n";

        pv::GlobalSolverOptions options;
        options.shape_metric = metric_name;
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
