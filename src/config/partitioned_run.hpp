#pragma once
// What the serial run (run.cpp) and the partitioned run (partitioned_run.cpp) share, and the
// partitioned run itself.
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "paloverde/config/run.hpp"

namespace paloverde::config::detail {

// The queue of a method's steps, with the target of each improver, in order.
struct BuiltQueue {
    InstructionQueue queue;
    std::vector<std::optional<double>> targets;
};
BuiltQueue build_queue_of(std::span<const StepSpec> steps, int threads);

// Runs every method's queue on the part (the whole mesh serially), each from the input's
// coordinates, with its reports before and after; write_outputs then writes the method's mesh.
// Stops after a method that was interrupted. Collective on a distributed part.
void run_methods(const RunSpec& spec, const RunHooks& hooks, MeshPart part, std::vector<BuiltQueue>& queues,
                 const std::function<void(MethodResult&)>& write_outputs, RunResult& result);

// input.mesh read, with the fixed flags input.fixed and input.fixed_vertices ask for; the file's
// own `fixed` field is dropped from the fields written back.
MeshFile read_input(const RunSpec& spec);
// Sets the spec's targets (`targets`) on the mesh, a reference read with `read` in the mesh's
// orientation (`flipped`), or `reference` itself (input.displacement); `name` names the mesh in
// errors. With a reference, its coordinates too (Mesh::reference_coordinates: morphing).
void set_run_targets(const RunSpec& spec, Mesh& mesh, ReadOptions read, bool flipped, const std::string& name,
                     const Mesh* reference = nullptr);

// "file:line:column" (or the flag) where `key` was set; "" for a default.
std::string origin(const RunSpec& spec, const std::string& key);
// `path` with {method} replaced by the method's name.
std::string replace_method(std::string path, const std::string& method);

// output.history, output.table, output.summary and output.plot (each through a temporary).
void write_reports(const RunSpec& spec, const RunResult& result);

// Ranks of MPI_COMM_WORLD; 1 when MPI is not initialized (or the build has none: serial_run.cpp,
// whose run_partitioned refuses).
int world_size();

// A run over the ranks of MPI_COMM_WORLD (see config::run): the spec is partitioned() or the
// world has more than one rank. config::run() hands it here after check_runnable(); everything
// that can be checked before reading (partition.parts against the ranks, solvers that have a
// distributed version, outputs that fit) is checked first, with errors naming key and line.
RunResult run_partitioned(const RunSpec& spec, const RunHooks& hooks);

}  // namespace paloverde::config::detail
