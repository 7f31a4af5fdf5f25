#include "paloverde/solvers/instruction_queue.hpp"

#include <algorithm>
#include <sstream>

#include "paloverde/core/error.hpp"
#include "paloverde/parallel/mesh_part.hpp"

namespace paloverde {

InstructionQueue& InstructionQueue::assess(std::string label, QualityAssessor assessor) {
    steps_.push_back({std::move(label), std::make_shared<const QualityAssessor>(std::move(assessor)), nullptr, std::nullopt});
    return *this;
}

InstructionQueue& InstructionQueue::improve(std::unique_ptr<Solver> solver) {
    if (!solver) throw OptionError("InstructionQueue::improve needs a solver, got none");
    std::string label(solver->name());
    return improve(std::move(label), std::move(solver));
}

InstructionQueue& InstructionQueue::improve(std::string label, std::unique_ptr<Solver> solver) {
    if (!solver) throw OptionError("InstructionQueue::improve needs a solver, got none");
    steps_.push_back({std::move(label), nullptr, std::shared_ptr<Solver>(std::move(solver)), std::nullopt});
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

namespace {
// Puts the mesh's targets back as they were when it was made.
class KeptTargets {
public:
    explicit KeptTargets(Mesh& mesh)
        : mesh_(mesh), maps_(mesh.target_maps().begin(), mesh.target_maps().end()),
          volumes_(mesh.target_volumes().begin(), mesh.target_volumes().end()),
          roots_(mesh.target_metric_roots().begin(), mesh.target_metric_roots().end()) {}
    ~KeptTargets() {
        if (maps_.empty()) mesh_.clear_targets();
        else mesh_.set_targets(std::move(maps_), std::move(volumes_), std::move(roots_));
    }
    KeptTargets(const KeptTargets&) = delete;
    KeptTargets& operator=(const KeptTargets&) = delete;

private:
    Mesh& mesh_;
    std::vector<CornerMap> maps_;
    std::vector<double> volumes_;
    std::vector<CornerMap> roots_;
};
}  // namespace

InstructionQueue& InstructionQueue::targets(TargetOptions options) {
    steps_.push_back({"targets", nullptr, nullptr, options});
    return *this;
}

QueueResult InstructionQueue::run(MeshPart part, std::shared_ptr<RunReports> reports) const {
    QueueResult result;
    std::optional<KeptTargets> kept;
    // The run's reports, for one improve().
    struct Shared {
        Solver& solver;
        ~Shared() { solver.share_reports(nullptr, false, false); }
    };
    const bool sets_targets = std::any_of(steps_.begin(), steps_.end(), [](const Instruction& s) { return s.targets.has_value(); });
    bool changed = false;  // by a step before this one
    for (std::size_t i = 0; i < steps_.size(); ++i) {
        const Instruction& step = steps_[i];
        if (step.targets) {
            changed = true;
            if (!kept) kept.emplace(part.mesh());
            // Targets from a reference: the mesh at its reference coordinates (morphing).
            set_targets(part, *step.targets);
            continue;
        }
        if (step.assessor) {
            result.steps.push_back({step.label, step.assessor->assess(part)});
            continue;
        }
        step.solver->share_reports(reports, !changed, !sets_targets && i + 1 == steps_.size());
        const Shared shared{*step.solver};
        changed = true;
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
