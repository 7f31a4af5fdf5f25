#pragma once
// An ordered list of instructions run over one mesh: quality assessments and improvers
// (solvers), in Mesquite's sense. A queue stops at the first improver that fails (it could not
// untangle, had nothing to move, hit a NaN) or is interrupted (stop.hpp), so later steps never work on a mesh in an unexpected state;
// the result says which step stopped it and why.
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "paloverde/assess/quality_assessor.hpp"
#include "paloverde/metrics/targets.hpp"
#include "paloverde/solvers/solver.hpp"

namespace paloverde {

struct QueueResult {
    struct Step {
        std::string label;
        std::variant<QualityReport, Summary> outcome;  // an assessment or an improver's summary
    };
    std::vector<Step> steps;
    bool success = true;   // every improver succeeded
    std::string message;   // why the queue stopped early, if it did

    std::string report() const;  // assessments as tables, summaries as brief reports
};

// Told of each iteration of every improver of a queue, with the improver's label.
using StepObserver = std::function<void(std::string_view label, const IterationRecord&)>;

class InstructionQueue {
public:
    InstructionQueue& assess(std::string label, QualityAssessor assessor = QualityAssessor());
    // Labelled with the solver's name, or with `label`.
    InstructionQueue& improve(std::unique_ptr<Solver> solver);
    InstructionQueue& improve(std::string label, std::unique_ptr<Solver> solver);
    // Sets the mesh's targets (metrics/targets.hpp) from its coordinates at this point of the
    // queue, and the factors from a reference from its reference coordinates
    // (Mesh::reference_coordinates): the steps after it rate every element against its target.
    // The queue hands the mesh back with the targets it had before.
    InstructionQueue& targets(TargetOptions options);
    // The steps of `other`, after these (its solvers are shared, not copied).
    InstructionQueue& append(const InstructionQueue& other);
    // Sets the observer of every improver of the queue, also those added later. Copies of a queue
    // share their solvers, and so the observer.
    InstructionQueue& observe(StepObserver observer);
    std::size_t size() const { return steps_.size(); }

    // On the whole mesh or, collectively, on this rank's part of a distributed one. `reports`: the
    // caller's report of the mesh as given, and the slot for its report of the result
    // (RunReports). The first step to change the mesh, if a solver, takes its own report of the
    // input from them; the last step, if a solver, fills the slot, unless the queue sets targets
    // (it hands the mesh's own targets back after its last step, which the caller's report rates).
    QueueResult run(MeshPart part, std::shared_ptr<RunReports> reports = nullptr) const;

private:
    struct Instruction {
        std::string label;
        std::shared_ptr<const QualityAssessor> assessor;  // one of the three is set
        std::shared_ptr<Solver> solver;
        std::optional<TargetOptions> targets;
    };
    void attach(const Instruction& step) const;

    std::vector<Instruction> steps_;
    StepObserver observer_;
};

}  // namespace paloverde
