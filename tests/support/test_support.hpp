#pragma once
// Helpers shared by the tests: where the shared meshes are, scratch directories, running the CLI.
#include <filesystem>
#include <string>
#include <vector>

#include "paloverde/core/types.hpp"

namespace paloverde::test {

// ../shared/data/<relative>
std::filesystem::path shared_data(const std::string& relative);

// A fresh empty directory under the test's working directory, removed at the end of the run.
class ScratchDir {
public:
    explicit ScratchDir(const std::string& name);
    ~ScratchDir();
    const std::filesystem::path& path() const { return path_; }
    std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

private:
    std::filesystem::path path_;
};

// Writes `text` to `path` (for hand-made bad inputs).
void write_file(const std::filesystem::path& path, const std::string& text);

struct CommandResult {
    int exit_code = -1;
    std::string output;  // stdout and stderr together
};
// Runs the paloverde command line with the given arguments (shell-quoted by the caller).
CommandResult run_cli(const std::string& arguments);

// The regular simplex with unit edges, positively oriented (triangles in the xy plane), 3
// coordinates per corner, and its volume (area).
std::vector<double> regular_simplex(ElementKind kind);
double regular_simplex_volume(ElementKind kind);

}  // namespace paloverde::test
