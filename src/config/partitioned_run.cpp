#include "config/partitioned_run.hpp"

#include <filesystem>

namespace paloverde::config::detail {

// Partitioned runs are wired here: split or read the pieces (input.pieces, partition.parts and
// partition.method), run each method's queue on the distributed mesh (parallel.exchange), write
// output.pieces and the run's other outputs, and fill the RunResult as the serial run() does.
// Until then every config that needs them stops here, before anything is read.
RunResult run_partitioned(const RunSpec& spec, const RunHooks& hooks) {
    (void)hooks;
    auto pvtu = [](const std::string& path) { return std::filesystem::path(path).extension() == ".pvtu"; };
    const std::string key = !spec.input.pieces.empty() ? "input.pieces"
                            : pvtu(spec.input.mesh)    ? "input.mesh"
                            : spec.partition.parts > 1 ? "partition.parts"
                            : pvtu(spec.output.mesh)   ? "output.mesh"
                                                       : "output.pieces";
    const auto origin = spec.origins.find(key);
    throw ConfigError(origin == spec.origins.end() ? std::string() : origin->second, key,
                      "partitioned (MPI) runs are not available in this build yet; for a serial run use input.mesh, "
                      "leave input.pieces and output.pieces unset and keep partition.parts: 1");
}

}  // namespace paloverde::config::detail
