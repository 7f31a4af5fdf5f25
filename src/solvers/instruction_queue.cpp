#include "paloverde/solvers/instruction_queue.hpp"

#include <sstream>

#include "paloverde/core/error.hpp"

namespace paloverde {

InstructionQueue& InstructionQueue::assess(std::string label, QualityAssessor assessor) {
    steps_.push_back({std::move(label), std::make_shared<const QualityAssessor>(std::move(assessor)), nullptr});
    return *this;
}

InstructionQueue& InstructionQueue::improve(std::unique_ptr<Solver> solver) {
    if (!solver) throw OptionError("InstructionQueue::improve needs a solver, got none");
    std::string label(solver->name());
    return improve(std::move(label), std::move(solver));
}

InstructionQueue& InstructionQueue::improve(std::string label, std::unique_ptr<Solver> solver) {
    if (!solver) throw OptionError("InstructionQueue::improve needs a solver, got none");
    steps_.push_back({std::move(label), nullptr, std::shared_ptr<Solver>(std::move(solver))});
    attach(steps_.back());
    return *this;
}

InstructionQueue& InstructionQueue::append(const InstructionQueue& other) {
    for (const Instruction& step : other.steps_) {
        steps_.push_back(step);
        attach(steps_.back());
    }
    return *this;
}

InstructionQueue& InstructionQueue::observe(StepObserver observer) {
    observer_ = std::move(observer);
    for (const Instruction& step : steps_) attach(step);
    return *this;
}

void InstructionQueue::attach(const Instruction& step) const {
    if (!step.solver || !observer_) return;
    step.solver->set_observer([observer = observer_, label = step.label](const IterationRecord& r) { observer(label, r); });
}

QueueResult InstructionQueue::run(MeshPart part) const {
    QueueResult result;
    for (const Instruction& step : steps_) {
        if (step.assessor) {
            result.steps.push_back({step.label, step.assessor->assess(part)});
            continue;
        }
        Summary summary = step.solver->improve(part);
        const bool ok = summary.success();
        const bool interrupted = summary.reason == TerminationReason::Interrupted;
        const std::string why = summary.message;
        result.steps.push_back({step.label, std::move(summary)});
        if (!ok) {
            result.success = false;
            result.message = "'" + step.label + (interrupted ? "' was interrupted: " : "' failed: ") + why;
            break;
        }
    }
    return result;
}

std::string QueueResult::report() const {
    std::ostringstream out;
    for (const Step& step : steps) {
        out << "== " << step.label << "\n";
        if (const auto* report = std::get_if<QualityReport>(&step.outcome)) out << report->to_text();
        else out << std::get<Summary>(step.outcome).brief_report() << "\n";
    }
    if (!success) out << "stopped: " << message << "\n";
    return out.str();
}

}  // namespace paloverde
