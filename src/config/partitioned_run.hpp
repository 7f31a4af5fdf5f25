#pragma once
#include "paloverde/config/run.hpp"

namespace paloverde::config::detail {

// A run that needs the partitioned (MPI) machinery: RunSpec::partitioned() (input.pieces, a
// .pvtu input or output, partition.parts > 1 or output.pieces). config::run() hands such a spec
// here after check_runnable() and before reading anything.
RunResult run_partitioned(const RunSpec& spec, const RunHooks& hooks);

}  // namespace paloverde::config::detail
