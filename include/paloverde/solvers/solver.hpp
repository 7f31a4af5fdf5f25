#pragma once
// A solver (vertex mover) improves a mesh in place and says what it did. Whatever stops it, the
// mesh it leaves is never worse than the one it got: no more inverted elements, and no lower
// worst quality among the elements it could move.
//
// One entry point for serial and distributed runs: improve() takes a MeshPart, the whole mesh
// (`solver.improve(mesh)`) or this rank's part of a DistributedMesh (`solver.improve(part)`,
// collective: every rank ends with the same Summary).
#include <functional>
#include <string_view>
#include <utility>

#include "paloverde/parallel/mesh_part.hpp"
#include "paloverde/solvers/summary.hpp"

namespace paloverde {

// Told of each iteration as it is recorded (progress lines, live plots); must not throw.
using IterationObserver = std::function<void(const IterationRecord&)>;

class Solver {
public:
    virtual ~Solver() = default;
    virtual std::string_view name() const = 0;
    virtual Summary improve(MeshPart part) = 0;

    void set_observer(IterationObserver observer) { observer_ = std::move(observer); }

protected:
    // Adds r to the history and tells the observer.
    void add_record(Summary& summary, IterationRecord r) const {
        summary.history.push_back(std::move(r));
        if (observer_) observer_(summary.history.back());
    }
    const IterationObserver& observer() const { return observer_; }

private:
    IterationObserver observer_;
};

}  // namespace paloverde
