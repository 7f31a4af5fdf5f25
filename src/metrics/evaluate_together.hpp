#pragma once
// Several metrics over the same elements, as the quality report rates them: each block of
// tetrahedra is gathered once and rated by every built-in metric with a block kernel (the
// report's six), in place of one gather per metric; the other metrics rate the range by their
// own evaluate(). The qualities are those evaluate() gives, bit for bit.
#include <span>

#include "paloverde/metrics/quality_metric.hpp"

namespace paloverde::metrics {

struct TetBlock;

// A metric that rates a block of tetrahedra gathered by someone else: evaluate_together() gathers
// each block once (its corners mapped as the mesh's corner maps say) for all the metrics it rates.
class BlockRater {
public:
    // Whether it rates this mesh's blocks so (a mesh of tetrahedra).
    virtual bool rates_blocks(const Mesh& mesh) const = 0;
    // quality[j] for the block's elements first, ..., first + count - 1.
    virtual void rate_block(const TetBlock& x, ElementId first, int count, double* quality) const = 0;

protected:
    ~BlockRater() = default;
};

// quality[i][e - first] = metric i's quality of element e, for e in [first, last).
void evaluate_together(std::span<const QualityMetric* const> metrics, const Mesh& mesh, std::span<const double> xyz,
                       ElementId first, ElementId last, std::span<double* const> quality);

}  // namespace paloverde::metrics
