#pragma once
// Runs a RunSpec: reads the input, runs each method's queue on its own copy of the mesh, writes
// the outputs (each through a temporary file and a rename) and says how it went.
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "paloverde/config/config.hpp"
#include "paloverde/solvers/instruction_queue.hpp"

namespace paloverde::config {

// Exit codes of `paloverde run` and `paloverde improve`.
enum class RunStatus {
    Done = 0,             // every improver succeeded and every target was reached
    Failed = 1,           // an improver failed (could not untangle, nothing to move)
    TargetNotReached = 3  // finished with a valid mesh, but a target_worst_quality was not reached
};
std::string_view to_string(RunStatus status);

struct MethodResult {
    std::string name;
    RunStatus status = RunStatus::Done;
    std::string message;   // why it failed or missed its target
    QueueResult queue;     // each step's report or summary
    std::string metric;    // output.metric: what the numbers below measure
    QualityReport before, after;  // the whole mesh before and after the queue
    double worst_before = 0.0, worst_after = 0.0;  // smallest `metric` over elements with a free vertex
    double mean_before = 0.0, mean_after = 0.0;    // mean `metric` over all elements
    double seconds = 0.0;  // the queue's wall time
    int iterations = 0, untangle_iterations = 0;   // over its improvers
    std::string mesh_written;  // "" if output.mesh is not set
};

struct RunResult {
    std::string input;
    std::vector<MethodResult> methods;
    RunStatus status = RunStatus::Done;  // the worst over methods: Failed, then TargetNotReached

    int exit_code() const { return static_cast<int>(status); }
    std::string report() const;       // text: per method its steps, then a comparison for a study
    std::string to_json() const;      // run keys, "methods": [...]; one method's keys also at the top
    std::string table_csv() const;    // one row per method
    std::string history_csv() const;  // method, improver (its label), then Summary::history_csv's columns
};

struct RunHooks {
    // Each recorded iteration of every improver (progress lines); must not throw.
    std::function<void(std::string_view method, std::string_view step, const IterationRecord&)> on_iteration;
    // When a method's queue has finished.
    std::function<void(const MethodResult&)> on_method_done;
};

// The queue the steps describe; each solver uses `threads`.
InstructionQueue build_queue(std::span<const StepSpec> steps, int threads = 0);

// Checks the spec (check_runnable), runs every method and writes the outputs. Throws ConfigError
// for a config that cannot run, FileError / MeshError for unreadable input or unwritable output.
RunResult run(const RunSpec& spec, const RunHooks& hooks = {});

}  // namespace paloverde::config
