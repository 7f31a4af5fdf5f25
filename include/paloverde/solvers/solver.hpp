#pragma once
// A solver (vertex mover) improves a mesh in place and says what it did. Whatever stops it, the
// mesh it leaves is never worse than the one it got: no more inverted elements, and no lower
// worst quality among the elements it could move.
//
// One entry point for serial and distributed runs: improve() takes a MeshPart, the whole mesh
// (`solver.improve(mesh)`) or this rank's part of a DistributedMesh (`solver.improve(part)`,
// collective: every rank ends with the same Summary).
#include <functional>
#include <memory>
#include <optional>
#include <string_view>
#include <utility>

#include "paloverde/assess/quality_assessor.hpp"
#include "paloverde/parallel/mesh_part.hpp"
#include "paloverde/solvers/summary.hpp"

namespace paloverde {

// Told of each iteration as it is recorded (progress lines, live plots); must not throw.
using IterationObserver = std::function<void(const IterationRecord&)>;

// The reports a run makes of the mesh before and after its queue (InstructionQueue::run), shared
// with its solvers so that each state is assessed once: the first solver takes its own report of
// the input from `input` (QualityAssessor::taken_from), and the last makes `output` along with its
// own report of the result. A solver's run that does not start from the mesh as given, or does
// not end on the mesh handed back (following a motion, sliding the boundary, on a surface),
// assesses for itself and leaves `output` empty.
struct RunReports {
    QualityAssessor assessor;             // what the run's reports rate
    QualityReport input;                  // its report of the mesh as given
    std::optional<QualityReport> output;  // its report of the result, where the last solver made it
};
// What one solver's run does with them.
struct SharedReports {
    const RunReports* input = nullptr;  // its first report is taken from input->input
    RunReports* output = nullptr;       // it makes output->output
};

class Solver {
public:
    virtual ~Solver() = default;
    virtual std::string_view name() const = 0;
    virtual Summary improve(MeshPart part) = 0;

    void set_observer(IterationObserver observer) { observer_ = std::move(observer); }
    // For the next improve(): the run's reports, and whether this solver takes its report of the
    // input from them (the queue's first step to change the mesh) and makes the report of its
    // result (the last). nullptr: none.
    void share_reports(std::shared_ptr<RunReports> reports, bool takes_input, bool makes_output) {
        reports_ = std::move(reports);
        takes_input_ = takes_input;
        makes_output_ = makes_output;
    }

protected:
    // Adds r to the history and tells the observer.
    void add_record(Summary& summary, IterationRecord r) const {
        summary.history.push_back(std::move(r));
        if (observer_) observer_(summary.history.back());
    }
    const IterationObserver& observer() const { return observer_; }
    // For a run that starts from the mesh as given and ends on the mesh handed back.
    SharedReports shared_reports() const {
        return {takes_input_ ? reports_.get() : nullptr, makes_output_ ? reports_.get() : nullptr};
    }

private:
    IterationObserver observer_;
    std::shared_ptr<RunReports> reports_;
    bool takes_input_ = false, makes_output_ = false;
};

}  // namespace paloverde
