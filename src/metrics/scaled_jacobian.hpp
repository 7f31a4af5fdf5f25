#pragma once
#include <memory>

#include "paloverde/metrics/quality_metric.hpp"

namespace paloverde::metrics {
// The minimum corner scaled Jacobian (scaled_jacobian.cpp): in the catalogue, for assessments.
std::unique_ptr<QualityMetric> make_scaled_jacobian();
}  // namespace paloverde::metrics
