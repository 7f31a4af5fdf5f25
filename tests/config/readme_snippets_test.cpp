// The README's C++ snippets are cut from the example programs, which the tests build and run: each
// block marked `<!-- examples/FILE [TAG] -->` must equal the lines of FILE between its two
// `// [TAG]` lines, less their common indentation.
#include <boost/test/unit_test.hpp>
#include <algorithm>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "support/io_checks.hpp"
#include "support/test_support.hpp"

namespace pv = paloverde;

namespace {

std::vector<std::string> lines_of(const std::string& text) {
    std::vector<std::string> out;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) out.push_back(line);
    return out;
}

std::string trimmed(const std::string& s) {
    const auto a = s.find_first_not_of(" \t"), b = s.find_last_not_of(" \t");
    return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}

// The lines between the two `// [tag]` lines of the file, less their common indentation.
std::vector<std::string> region(const std::filesystem::path& file, const std::string& tag) {
    const auto lines = lines_of(pv::test::read_text(file));
    std::vector<std::size_t> marks;
    for (std::size_t i = 0; i < lines.size(); ++i)
        if (trimmed(lines[i]) == "// [" + tag + "]") marks.push_back(i);
    BOOST_TEST_REQUIRE(marks.size() == 2u, file << " has " << marks.size() << " lines // [" << tag << "]");
    std::vector<std::string> body(lines.begin() + static_cast<std::ptrdiff_t>(marks[0]) + 1,
                                  lines.begin() + static_cast<std::ptrdiff_t>(marks[1]));
    std::size_t indent = std::string::npos;
    for (const auto& l : body)
        if (!trimmed(l).empty()) indent = std::min(indent, l.find_first_not_of(' '));
    for (auto& l : body) l = l.size() >= indent ? l.substr(indent) : trimmed(l);
    return body;
}

}  // namespace

BOOST_AUTO_TEST_SUITE(readme)

BOOST_AUTO_TEST_CASE(cpp_snippets_are_the_examples_own_lines) {
    const std::filesystem::path root(PALOVERDE_SOURCE_DIR);
    const auto readme = lines_of(pv::test::read_text(root / "README.md"));
    const std::string open = "<!-- examples/";
    int snippets = 0;
    for (std::size_t i = 0; i < readme.size(); ++i) {
        if (readme[i].rfind(open, 0) != 0) continue;
        const auto space = readme[i].find(" [");
        const auto close = readme[i].find("] -->");
        BOOST_TEST_REQUIRE((space != std::string::npos && close != std::string::npos), "README line " << i + 1);
        const std::string file = readme[i].substr(5, space - 5);
        const std::string tag = readme[i].substr(space + 2, close - space - 2);
        BOOST_TEST_REQUIRE(i + 1 < readme.size());
        BOOST_TEST_REQUIRE(readme[i + 1] == "```cpp", "README line " << i + 2 << ": a ```cpp block after the mark");
        std::vector<std::string> block;
        std::size_t j = i + 2;
        for (; j < readme.size() && readme[j] != "```"; ++j) block.push_back(readme[j]);
        BOOST_TEST_CONTEXT("README line " << i + 1 << ": " << file << " [" << tag << "]") {
            BOOST_TEST(block == region(root / file, tag), boost::test_tools::per_element());
        }
        ++snippets;
        i = j;
    }
    BOOST_TEST(snippets >= 5);  // ex1, ex1p, ex2 and ex3's registration and run
}

BOOST_AUTO_TEST_SUITE_END()
