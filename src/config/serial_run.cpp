// A build without MPI (PALOVERDE_MPI=OFF) in place of partitioned_run.cpp: there is one process,
// and a spec that asks for a distributed run is refused, naming the key that asks for it.
#include <filesystem>

#include "config/partitioned_run.hpp"

namespace paloverde::config::detail {

int world_size() { return 1; }

RunResult run_partitioned(const RunSpec& spec, const RunHooks&) {
    const auto pvtu = [](const std::string& path) { return std::filesystem::path(path).extension() == ".pvtu"; };
    std::string key = "partition.parts";
    if (!spec.input.pieces.empty()) key = "input.pieces";
    else if (pvtu(spec.input.mesh)) key = "input.mesh";
    else if (!spec.output.pieces.empty()) key = "output.pieces";
    else if (pvtu(spec.output.mesh)) key = "output.mesh";
    throw ConfigError(origin(spec, key), key,
                      "this build has no MPI: a partitioned run (partition.parts > 1, pieces or a .pvtu) needs "
                      "Paloverde built with PALOVERDE_MPI=ON; run it serially (partition.parts: 1, no pieces)");
}

}  // namespace paloverde::config::detail
