#pragma once
// An ordered list of instructions run over one mesh: quality assessments and improvers
// (solvers), in Mesquite's sense. A queue stops at the first improver that fails (it could not
// untangle, or had nothing to move), so later steps never work on a mesh in an unexpected state;
// the result says which step stopped it and why.
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "paloverde/assess/quality_assessor.hpp"
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

class InstructionQueue {
public:
    InstructionQueue& assess(std::string label, QualityAssessor assessor = QualityAssessor());
    InstructionQueue& improve(std::unique_ptr<Solver> solver);
    std::size_t size() const { return steps_.size(); }

    QueueResult run(SimplexMesh& mesh) const;

private:
    struct Instruction {
        std::string label;
        std::shared_ptr<const QualityAssessor> assessor;  // one of the two is set
        std::shared_ptr<Solver> solver;
    };
    std::vector<Instruction> steps_;
};

}  // namespace paloverde
