#include "support/test_support.hpp"

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <sys/wait.h>


namespace paloverde::test {

std::filesystem::path shared_data(const std::string& relative) {
    const std::filesystem::path path = std::filesystem::path(PALOVERDE_SHARED_DATA) / relative;
    if (!std::filesystem::exists(path)) throw std::runtime_error("shared test mesh missing: " + path.string());
    return path;
}

ScratchDir::ScratchDir(const std::string& name) : path_(std::filesystem::current_path() / ("scratch_" + name)) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
}

ScratchDir::~ScratchDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
}

void write_file(const std::filesystem::path& path, const std::string& text) {
    std::ofstream out(path, std::ios::binary);
    out << text;
    if (!out) throw std::runtime_error("cannot write " + path.string());
}

CommandResult run_cli(const std::string& arguments) {
    const std::string command = std::string(PALOVERDE_CLI) + " " + arguments + " 2>&1";
    FILE* pipe = ::popen(command.c_str(), "r");
    if (!pipe) throw std::runtime_error("cannot run " + command);
    CommandResult result;
    std::array<char, 4096> buffer{};
    while (std::size_t n = std::fread(buffer.data(), 1, buffer.size(), pipe)) result.output.append(buffer.data(), n);
    const int status = ::pclose(pipe);
    result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return result;
}

std::vector<double> regular_simplex(ElementKind kind) {
    if (kind == ElementKind::Triangle) return {0, 0, 0, 1, 0, 0, 0.5, std::sqrt(3.0) / 2, 0};
    return {0, 0, 0, 1, 0, 0, 0.5, std::sqrt(3.0) / 2, 0, 0.5, std::sqrt(3.0) / 6, std::sqrt(2.0 / 3.0)};
}

double regular_simplex_volume(ElementKind kind) {
    return kind == ElementKind::Triangle ? std::sqrt(3.0) / 4 : std::sqrt(2.0) / 12;
}

}  // namespace paloverde::test
