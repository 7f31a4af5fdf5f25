// Example 3: a quality metric of our own, registered by name and used from a config file as the
// built-in ones are (examples/ex3.yaml). The metric, sized_aspect, rates shape and size at once:
// the aspect ratio times 2 / (v + 1/v), v = |V| / V_ref the element's volume over the mesh's
// mean. It is 1 for a regular tetrahedron of the mean size, lower when the element is skewed,
// larger or smaller than that, and <= 0 when inverted.
//
//   ex3 [CONFIG] [IN] [OUT]     defaults: examples/ex3.yaml as written; IN, OUT replace its
//                               input.mesh and output.mesh
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include <paloverde/config/config.hpp>
#include <paloverde/config/run.hpp>
#include <paloverde/metrics/quality_metric.hpp>

#include "sized_aspect.hpp"  // the metric itself

int main(int argc, char** argv) try {
    // [ex3-register]
    paloverde::register_metric({"sized_aspect",
                                "aspect ratio times 2 / (v + 1/v), v = |V| / V_ref; tetrahedra; ideal 1 (regular, of the "
                                "mean size), <= 0 when inverted (examples/ex3.cpp).",
                                [](const paloverde::MetricOptions&) { return std::make_unique<example::SizedAspect>(); }});
    // [ex3-register]

    const std::string config = argc > 1 ? argv[1] : "examples/ex3.yaml";
    std::vector<paloverde::config::Override> overrides;
    if (argc > 2) overrides.push_back({"input.mesh=" + std::string(argv[2]), "ex3's argument", true});
    if (argc > 3) overrides.push_back({"output.mesh=" + std::string(argv[3]), "ex3's argument", true});

    // [ex3-run]
    const auto spec = paloverde::config::read_config(config, overrides);  // errors name the file, line and key
    const auto result = paloverde::config::run(spec);                     // reads, runs, writes the outputs
    std::cout << result.report();
    return result.exit_code();
    // [ex3-run]
} catch (const std::exception& e) {
    std::cerr << "ex3: " << e.what() << "\n";
    return 1;
}
