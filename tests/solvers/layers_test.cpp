// The layers read top-down (docs/layout.md): a file includes its own folder and the layers below
// it, never one above. Checked over every source and header of the library, the command line,
// the wrappers and the Python module, from the includes as written.
#include <boost/test/unit_test.hpp>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <string>

namespace fs = std::filesystem;

namespace {

// Higher layers may include lower ones. Folders on one level do not include each other.
const std::map<std::string, int> kLayer{
    {"core", 0},       {"mesh", 1},   {"io", 2},      {"metrics", 2}, {"parallel", 3}, {"objectives", 4},
    {"assess", 4},     {"solvers", 5}, {"wrappers", 6}, {"config", 7}, {"cli", 8},
    {"python", 8},
};

// The layer folder of a path below src/ or include/paloverde/ ("solvers/workspace.hpp" -> solvers);
// the wrappers' one header sits at include/paloverde/wrappers.hpp.
std::string folder_of(const std::string& relative) {
    const auto slash = relative.find('/');
    if (slash == std::string::npos) return relative == "wrappers.hpp" ? "wrappers" : "";
    return relative.substr(0, slash);
}

}  // namespace

BOOST_AUTO_TEST_SUITE(layers)

BOOST_AUTO_TEST_CASE(no_include_climbs_a_layer) {
    const fs::path root = PALOVERDE_SOURCE_DIR;
    const std::regex include_line(R"(^\s*#\s*include\s*"(paloverde/)?([^"]+)\")");
    const std::vector<std::pair<fs::path, std::string>> trees{
        {root / "src", ""}, {root / "include" / "paloverde", ""}, {root / "wrappers", "wrappers"}};
    int files = 0, includes = 0;
    for (const auto& [tree, fixed_folder] : trees) {
        for (const auto& entry : fs::recursive_directory_iterator(tree)) {
            const auto ext = entry.path().extension();
            if (!entry.is_regular_file() || (ext != ".cpp" && ext != ".hpp")) continue;
            const std::string relative = fs::relative(entry.path(), tree).generic_string();
            // The Python package (wrappers/python) sits on top, beside the command line.
            const std::string from = fixed_folder.empty()                ? folder_of(relative)
                                     : relative.starts_with("python/") ? "python"
                                                                       : fixed_folder;
            BOOST_TEST_CONTEXT(entry.path().string()) {
                BOOST_TEST_REQUIRE(kLayer.count(from) == 1, "a folder with no layer: " << from);
                ++files;
                std::ifstream in(entry.path());
                std::string line;
                while (std::getline(in, line)) {
                    std::smatch m;
                    if (!std::regex_search(line, m, include_line)) continue;
                    const std::string to = folder_of(m[2].str());
                    const auto layer = kLayer.find(to);
                    if (layer == kLayer.end()) continue;  // a file beside this one, or a library's
                    ++includes;
                    BOOST_TEST_INFO(line);
                    BOOST_TEST((to == from || layer->second < kLayer.at(from)));
                }
            }
        }
    }
    // The walk saw the tree (a wrong root would pass trivially).
    BOOST_TEST(files > 100);
    BOOST_TEST(includes > 200);
}

BOOST_AUTO_TEST_SUITE_END()
