#pragma once
// Every object a run can name, by kind and name, with its options declared once: the config
// reader, the command line (`paloverde improve --metric ...`, `--set`), `--print-config`, the
// reference in docs/config.md (`paloverde run --describe`) and the C++ calls below all go through
// the same table, so one name has one meaning everywhere.
//
// Kinds: "solver" (global, local, smart_laplace, laplace), "objective" (log_barrier, p_mean,
// min_quality), "metric" (aspect_ratio, ...), "termination", "assessor" (quality), "wrapper"
// (untangle, shape_improvement, local_shape_improvement, laplace, untangle_then_improve) and
// "section" (the parts of a run config: run, input, partition, parallel, output, study method,
// and the queue steps assess / improve / untangle / wrapper).
#include <memory>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "paloverde/solvers/global_solver.hpp"
#include "paloverde/solvers/instruction_queue.hpp"
#include "paloverde/solvers/laplace_solver.hpp"
#include "paloverde/solvers/local_solver.hpp"

namespace paloverde::config {

// The options of any solver; which alternative goes with which name: global -> Global,
// local -> Local, smart_laplace / laplace -> Laplace (`smart` set by the name).
using SolverOptions = std::variant<GlobalSolverOptions, LocalSolverOptions, LaplaceSolverOptions>;

struct OptionInfo {
    std::string key;            // as written in a config ("max_iterations")
    std::string type;           // "whole number", "number", "true/false", "one of: a, b", "map (termination)", ...
    std::string default_value;  // as YAML ("500", "~", "aspect_ratio")
    std::string help;
};

struct ObjectInfo {
    std::string kind;
    std::string name;
    std::string help;
    std::vector<OptionInfo> options;
};

// Every object, kinds in the order listed above.
const std::vector<ObjectInfo>& registry();
// The names of one kind, in registry order.
std::vector<std::string> names_of(std::string_view kind);
// Throws OptionError listing the known names when there is no such object.
const ObjectInfo& describe(std::string_view kind, std::string_view name);
// The registry as the markdown reference of docs/config.md.
std::string registry_markdown();

// The defaults of a solver or wrapper by name (a wrapper's are those of the solver it runs).
SolverOptions default_options(std::string_view solver_or_wrapper);
// A solver by name; the options must be the name's alternative. Validates (throws OptionError).
std::unique_ptr<Solver> make_solver(std::string_view name, const SolverOptions& options);
inline std::unique_ptr<Solver> make_solver(std::string_view name) { return make_solver(name, default_options(name)); }
// A wrapper's ready queue by name (paloverde/wrappers.hpp); the options as for its solver.
InstructionQueue make_wrapper(std::string_view name, const SolverOptions& options);

}  // namespace paloverde::config
