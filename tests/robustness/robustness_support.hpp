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
#include <vector>

#include "paloverde/core/error.hpp"
#include "paloverde/solvers/solver.hpp"
#include "paloverde/solvers/stop.hpp"
#include "paloverde/solvers/summary.hpp"
#include "support/solver_checks.hpp"
#include "support/test_support.hpp"

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

// The same end: coordinates bit for bit, the counters, the history, the message, the reports and
// what the boundary did.
inline void check_same_end(const Outcome& a, const Outcome& b) {
    BOOST_TEST(same_coordinates(a.mesh, b.mesh));
    check_same_run(a.summary, b.summary);
    BOOST_TEST(a.summary.message == b.summary.message);
    BOOST_TEST(a.summary.before.inverted == b.summary.before.inverted);
    BOOST_TEST(a.summary.worst_before == b.summary.worst_before);
    BOOST_TEST(a.summary.after.to_json() == b.summary.after.to_json());
    BOOST_TEST_REQUIRE(a.summary.boundary.has_value() == b.summary.boundary.has_value());
    if (a.summary.boundary) BOOST_TEST(a.summary.boundary->moved == b.summary.boundary->moved);
}

// The checkpoint files of a run with file FILE: its own, and those of the runs inside it
// (RunCheckpoints: FILE.run, and FILE.run.run one level further down).
inline std::vector<std::filesystem::path> checkpoint_files(const std::filesystem::path& file) {
    return {file, file.string() + ".run", file.string() + ".run.run"};
}

// An observer that copies a run's checkpoint files each time any of them changed, into a folder
// of their own each (under `dir`, by the same names); `wholes` counts the changes of FILE itself
// (written before each run inside it).
class CheckpointCopies {
public:
    CheckpointCopies(std::filesystem::path checkpoint, std::filesystem::path dir)
        : file(std::move(checkpoint)), dir_(std::move(dir)) {}
    const std::filesystem::path file;
    std::vector<std::filesystem::path> copies;  // FILE's copy in each folder
    int wholes = 0;

    IterationObserver observer() {
        namespace fs = std::filesystem;
        return [this](const IterationRecord&) {
            if (!fs::exists(file)) return;
            const std::string whole = read_text(file);
            std::string bytes;
            for (const fs::path& f : checkpoint_files(file)) bytes += fs::exists(f) ? read_text(f) + "|" : "-|";
            if (bytes == last_) return;
            wholes += whole != last_whole_;
            last_ = bytes, last_whole_ = whole;
            const fs::path folder = dir_ / ("copy" + std::to_string(copies.size()));
            fs::create_directory(folder);
            copies.push_back(folder / file.filename());
            const auto from = checkpoint_files(file), to = checkpoint_files(copies.back());
            for (std::size_t i = 0; i < from.size(); ++i)
                if (fs::exists(from[i])) fs::copy_file(from[i], to[i]);
        };
    }

private:
    std::filesystem::path dir_;
    std::string last_, last_whole_;
};

// Resuming from `file` on `input` throws a FileError whose message has `words`; the mesh is left
// as it was.
template <class Solver, class Options>
void check_refused(const Mesh& input, Options options, const std::filesystem::path& file, const std::string& words) {
    options.checkpoint.resume = file.string();
    Mesh mesh = input;
    BOOST_CHECK_EXCEPTION(Solver(options).improve(mesh), FileError, [&](const FileError& e) {
        BOOST_TEST_MESSAGE(e.what());
        return std::string(e.what()).find(words) != std::string::npos;
    });
    BOOST_TEST(same_coordinates(mesh, input));
}

// `options` run on `input` with checkpoints every `every` iterations, into a scratch folder named
// `name`, its files copied whenever they changed (FILE at least `wholes` times; and, for a run made
// of runs (`inner`), the inner runs' files alone too), then resumed from every copy: each run, and
// the one writing them, ends as `uninterrupted`. Returns the most files a copy held (how many levels
// of runs were resumed from: FILE, FILE.run, FILE.run.run).
template <class Solver, class Options>
int check_resumed_from_every_copy(const std::string& name, const Mesh& input, const Options& options, int every,
                                   int wholes, const Outcome& uninterrupted, bool inner = true) {
    const StopRequestCleared cleared;
    const ScratchDir dir(name);
    CheckpointCopies copies(dir / "run.ckpt", dir.path());
    auto writing = options;
    writing.checkpoint.file = copies.file.string();
    writing.checkpoint.every_iterations = every;
    // Writing checkpoints changes nothing.
    check_same_end(run<Solver>(input, writing, copies.observer()), uninterrupted);
    BOOST_TEST_REQUIRE(copies.wholes >= wholes);
    if (inner) BOOST_TEST_REQUIRE(copies.copies.size() > static_cast<std::size_t>(copies.wholes));
    int levels = 0;
    for (std::size_t i = 0; i < copies.copies.size(); ++i) {
        const auto files = checkpoint_files(copies.copies[i]);
        levels = std::max(levels, static_cast<int>(std::count_if(files.begin(), files.end(), [](const auto& f) {
                                      return std::filesystem::exists(f);
                                  })));
        BOOST_TEST_CONTEXT(name << " resumed from copy " << i
                                << (std::filesystem::exists(copies.copies[i].string() + ".run") ? ", in a run" : "")) {
            auto resuming = options;
            resuming.checkpoint.resume = copies.copies[i].string();
            check_same_end(run<Solver>(input, resuming), uninterrupted);
        }
    }
    return levels;
}

}  // namespace paloverde::test
