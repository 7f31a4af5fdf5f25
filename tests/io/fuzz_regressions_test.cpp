// Every input the fuzz targets found a problem with (tests/fuzz/regressions/<format>/, see
// docs/robustness.md), replayed through the same checks in the ordinary build: each must give a
// mesh that survives a write and a re-read, or a paloverde::Error, nothing else. The fuzz build
// replays them too, under the sanitizers.
#include <boost/test/unit_test.hpp>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "fuzz/fuzz_input.hpp"
#include "support/test_support.hpp"

namespace fs = std::filesystem;
using namespace paloverde;

namespace {

// tests/fuzz/regressions, found from this file's own path.
fs::path regressions() { return fs::path(__FILE__).parent_path().parent_path() / "fuzz" / "regressions"; }

struct Folder {
    const char* name;
    MeshFormat format;
};
const Folder kFolders[] = {{"vtk", MeshFormat::VtkLegacy},
                           {"vtu", MeshFormat::Vtu},
                           {"gmsh", MeshFormat::Gmsh},
                           {"medit", MeshFormat::Medit},
                           {"tetgen", MeshFormat::TetGen}};

}  // namespace

BOOST_AUTO_TEST_SUITE(fuzz_regressions)

BOOST_AUTO_TEST_CASE(every_regression_input_is_read_or_refused_cleanly) {
    BOOST_REQUIRE(fs::is_directory(regressions()));
    const test::ScratchDir dir("fuzz_regressions");
    int inputs = 0;
    for (const Folder& folder : kFolders) {
        const fs::path path = regressions() / folder.name;
        if (!fs::is_directory(path)) continue;
        std::vector<fs::path> files(fs::directory_iterator(path), fs::directory_iterator{});
        for (const fs::path& file : files) {
            std::ifstream in(file, std::ios::binary);
            const std::string input((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
            ++inputs;
            BOOST_TEST_CONTEXT(file) {
                try {
                    fuzz::read_input(dir.path(), folder.format, input);
                } catch (const std::exception& e) {
                    BOOST_ERROR(e.what());
                }
            }
        }
    }
    BOOST_TEST(inputs > 0);
}

BOOST_AUTO_TEST_SUITE_END()
