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
#include <any>
#include <memory>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "paloverde/core/error.hpp"
#include "paloverde/solvers/instruction_queue.hpp"

namespace paloverde::config {

// The options of any solver or wrapper, whatever their type: the registry knows which type goes
// with which name (global -> GlobalSolverOptions, local -> LocalSolverOptions, smart_laplace and
// laplace -> LaplaceSolverOptions, `smart` set by the name), so a new solver brings its own
// options struct and no list here grows.
class SolverOptions {
public:
    SolverOptions() = default;
    template <class Options>
        requires(!std::is_same_v<std::decay_t<Options>, SolverOptions>)
    SolverOptions(Options options) : value_(std::move(options)) {}

    // The options as `Options`, or nullptr when they are of another type.
    template <class Options>
    const Options* get_if() const noexcept {
        return std::any_cast<Options>(&value_);
    }
    template <class Options>
    Options* get_if() noexcept {
        return std::any_cast<Options>(&value_);
    }
    // The options as `Options`; throws OptionError when they are of another type.
    template <class Options>
    const Options& get() const {
        if (const Options* o = get_if<Options>()) return *o;
        throw OptionError("these are the options of another solver");
    }
    template <class Options>
    Options& get() {
        if (Options* o = get_if<Options>()) return *o;
        throw OptionError("these are the options of another solver");
    }

private:
    std::any value_;
};

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
