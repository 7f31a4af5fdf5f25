#pragma once
// The registry's tables, for the config reader and writer.
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "config/table.hpp"
#include "paloverde/config/config.hpp"

namespace paloverde::config::detail {

// One type of SolverOptions and its table, behind one interface (options_kind<O> in registry.cpp
// builds it from the table alone).
struct OptionsKind {
    std::string what;
    // The solver untangles (its options have `untangle` and `improve_shape`).
    bool untangles = false;
    // An untangle step (and `--untangle`): untangle, then stop once no element is inverted.
    std::function<void(SolverOptions&)> untangle_only;
    std::function<void(SolverOptions&, int threads)> set_threads;
    std::function<void(SolverOptions&, const Node&, const std::string&, const Reader&, const Skip&,
                       const std::vector<std::string>&)>
        read;
    std::function<Node(const SolverOptions&, const Skip&, bool comments)> write;
    std::function<std::vector<OptionInfo>(const SolverOptions&, const Skip&)> describe;
    std::function<std::vector<std::string>(const Skip&)> keys;
    std::function<bool(const std::string&)> has;
};

struct SolverKind {
    std::string name, help;
    const OptionsKind* options = nullptr;
    Skip skip;  // keys the name decides
    std::function<SolverOptions()> defaults;
    std::function<std::unique_ptr<Solver>(const SolverOptions&)> make;
    // The target_worst_quality the solver aims at, if any (none while only untangling).
    std::function<std::optional<double>(const SolverOptions&)> target;
    // It improves a part of a DistributedMesh (else it runs serially only).
    bool distributed = true;
};

struct WrapperKind {
    std::string name, help;
    std::string solver;  // the solver whose options it takes (and whose distributed version it has, or not)
    const OptionsKind* options = nullptr;
    Skip skip;           // keys the wrapper sets itself
    std::function<SolverOptions()> defaults;
    std::function<InstructionQueue(const SolverOptions&)> make;
    // Per improver of the queue, in order: its target, if any.
    std::function<std::vector<std::optional<double>>(const SolverOptions&)> targets;
};

const std::vector<SolverKind>& solver_kinds();
std::vector<std::string> solver_names();
std::vector<std::string> wrapper_names();
const SolverKind* find_solver(const std::string& name);
const std::vector<WrapperKind>& wrapper_kinds();
const WrapperKind* find_wrapper(const std::string& name);
// An untangle step: the global solver's options without the shape phase's.
const Skip& untangle_skip();
const Table<AssessSpec>& assess_table();
// Which solvers (other than `except`) take `key`: "solver global" / "solvers global, local".
std::string solvers_with(const std::string& key, const std::string& except);

// The objects of every kind but "section" (registry.cpp) and the sections (schema.cpp).
std::vector<ObjectInfo> object_infos();
std::vector<ObjectInfo> section_infos();

}  // namespace paloverde::config::detail
