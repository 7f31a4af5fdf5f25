#pragma once
// What the stop, checkpoint and kill tests share.
#include <boost/test/unit_test.hpp>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

#include "paloverde/solvers/solver.hpp"
#include "paloverde/solvers/stop.hpp"
#include "paloverde/solvers/summary.hpp"
#include "support/solver_checks.hpp"

namespace paloverde::test {

// Clears the stop request before and after a test: it is process-wide.
struct StopRequestCleared {
    StopRequestCleared() { clear_stop_request(); }
    ~StopRequestCleared() { clear_stop_request(); }
};

// A solver's run on a copy of `input`: the mesh it hands back and its summary.
struct Outcome {
    Mesh mesh;
    Summary summary;
};

template <class Solver, class Options>
Outcome run(const Mesh& input, const Options& options, IterationObserver observer = {}) {
    Outcome out{input, {}};
    Solver solver(options);
    if (observer) solver.set_observer(std::move(observer));
    out.summary = solver.improve(out.mesh);
    return out;
}

// Bit for bit the same coordinates.
inline bool same_coordinates(const Mesh& a, const Mesh& b) {
    return a.coordinates().size() == b.coordinates().size() &&
           std::equal(a.coordinates().begin(), a.coordinates().end(), b.coordinates().begin(),
                      [](double x, double y) { return std::bit_cast<std::uint64_t>(x) == std::bit_cast<std::uint64_t>(y); });
}

// The same run: reason, counters and every history entry but its wall time.
inline void check_same_run(const Summary& a, const Summary& b) {
    BOOST_TEST(to_string(a.reason) == to_string(b.reason));
    BOOST_TEST(a.iterations == b.iterations);
    BOOST_TEST(a.untangle_iterations == b.untangle_iterations);
    BOOST_TEST(a.quality_passes == b.quality_passes);
    BOOST_TEST(a.gradient_passes == b.gradient_passes);
    BOOST_TEST(a.worst_after == b.worst_after);
    BOOST_TEST(a.after.inverted == b.after.inverted);
    BOOST_TEST_REQUIRE(a.history.size() == b.history.size());
    for (std::size_t i = 0; i < a.history.size(); ++i) {
        const auto &x = a.history[i], &y = b.history[i];
        BOOST_TEST_INFO("history entry " << i);
        BOOST_TEST((x.iteration == y.iteration && x.phase == y.phase && x.worst_quality == y.worst_quality &&
                    x.best_worst_quality == y.best_worst_quality && x.mean_quality == y.mean_quality &&
                    x.inverted == y.inverted && x.mu == y.mu && x.t == y.t && x.objective == y.objective &&
                    x.step == y.step && x.gain == y.gain && x.moved == y.moved));
    }
}

inline std::string read_text(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

inline void write_bytes(const std::filesystem::path& p, const std::string& bytes) {
    std::ofstream out(p, std::ios::binary | std::ios::trunc);
    out << bytes;
}

}  // namespace paloverde::test
