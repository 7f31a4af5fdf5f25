// libFuzzer target: the run-config reader (YAML text plus `--set` overrides). See
// docs/robustness.md.
//
// The input is one config file. Its lines that start with "#set " (comments to YAML) are also
// applied as `--set` assignments, so one input exercises both ways of setting a key. A
// paloverde::Error (a ConfigError naming the key, an OptionError) is the reader refusing bad input.
// Anything else is a finding: a crash, a sanitizer report, another exception (a YAML exception
// that escaped, std::out_of_range...), or a config that does not read back the same: `to_yaml`
// promises that reading its output gives the same RunSpec, so writing that again must give the
// same text.
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "paloverde/config/config.hpp"

namespace {

std::vector<paloverde::config::Override> set_lines(std::string_view text) {
    constexpr std::string_view prefix = "#set ";
    std::vector<paloverde::config::Override> overrides;
    while (!text.empty()) {
        const std::size_t end = text.find('\n');
        const std::string_view line = text.substr(0, end);
        if (line.substr(0, prefix.size()) == prefix) overrides.push_back({std::string(line.substr(prefix.size()))});
        if (end == std::string_view::npos) break;
        text.remove_prefix(end + 1);
    }
    return overrides;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    namespace config = paloverde::config;
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    config::RunSpec spec;
    try {
        spec = config::parse_config(text, "fuzz.yaml", set_lines(text));
    } catch (const paloverde::Error&) {
        return 0;  // refused with a message: the reader's job
    }
    for (const bool comments : {true, false}) {
        const std::string written = config::to_yaml(spec, comments);
        config::RunSpec again;
        try {
            again = config::parse_config(written, "written.yaml");
        } catch (const paloverde::Error& e) {
            throw std::logic_error(std::string("to_yaml wrote a config that does not read back: ") + e.what() +
                                   "\n--- written ---\n" + written);
        }
        if (config::to_yaml(again, comments) != written)
            throw std::logic_error("a config read back from to_yaml differs from the one written:\n--- written ---\n" +
                                   written + "\n--- read back and written again ---\n" + config::to_yaml(again, comments));
    }
    return 0;
}
