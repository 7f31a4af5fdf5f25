#include "paloverde/wrappers.hpp"

#include <memory>
#include <string>

namespace paloverde::wrappers {

namespace {
InstructionQueue around(std::unique_ptr<Solver> solver, std::string label = {}) {
    InstructionQueue queue;
    queue.assess("before");
    if (label.empty()) queue.improve(std::move(solver));
    else queue.improve(std::move(label), std::move(solver));
    queue.assess("after");
    return queue;
}
}  // namespace

InstructionQueue untangle(GlobalSolverOptions options) {
    options.untangle = true;
    options.improve_shape = false;
    return around(std::make_unique<GlobalSolver>(options), "untangle");
}

InstructionQueue shape_improvement(GlobalSolverOptions options) {
    options.untangle = false;
    options.improve_shape = true;
    return around(std::make_unique<GlobalSolver>(options));
}

InstructionQueue local_shape_improvement(LocalSolverOptions options) {
    options.improve_shape = true;
    return around(std::make_unique<LocalSolver>(options));
}

InstructionQueue laplace(LaplaceSolverOptions options) { return around(std::make_unique<LaplaceSolver>(options)); }

InstructionQueue untangle_then_improve(GlobalSolverOptions options) {
    GlobalSolverOptions untangling = options;
    untangling.untangle = true;
    untangling.improve_shape = false;
    options.untangle = false;
    options.improve_shape = true;
    InstructionQueue queue;
    queue.assess("before")
        .improve("untangle", std::make_unique<GlobalSolver>(untangling))
        .improve(std::make_unique<GlobalSolver>(options))
        .assess("after");
    return queue;
}

namespace {
InstructionQueue with_targets(const TargetOptions& targets, GlobalSolverOptions options) {
    options.shape_metric = targets.metric(options.shape_metric);
    InstructionQueue queue;
    queue.targets(targets).assess("before").improve(std::make_unique<GlobalSolver>(options)).assess("after");
    return queue;
}
}  // namespace

InstructionQueue size_adapt_shape(GlobalSolverOptions options) {
    return with_targets(TargetOptions::from("size"), std::move(options));
}

InstructionQueue boundary_layer_shape(GlobalSolverOptions options) {
    return with_targets(TargetOptions::from("size,aspect,orientation"), std::move(options));
}

InstructionQueue deforming_domain(GlobalSolverOptions options) {
    return with_targets(TargetOptions::from("size,aspect,skew", TargetSource::Reference), std::move(options));
}

}  // namespace paloverde::wrappers
