#include "support/io_checks.hpp"

#include <boost/test/unit_test.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <utility>

#include "paloverde/core/error.hpp"
#include "paloverde/io/mesh_io.hpp"

namespace paloverde::test {

namespace fs = std::filesystem;

// Built with += (GCC 12 warns, wrongly, on ":" + string).
std::string line_tag(std::size_t line) {
    std::string tag = ":";
    tag += std::to_string(line);
    tag += ':';
    return tag;
}

std::string last_line(const std::string& text) {
    return line_tag(1 + static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n')));
}

std::string line_of(const std::string& text, std::string_view needle) {
    const std::size_t at = text.find(needle);
    BOOST_REQUIRE(at != std::string::npos);
    return last_line(text.substr(0, at));
}

std::string replaced(std::string text, std::string_view from, std::string_view to) {
    const std::size_t at = text.find(from);
    BOOST_REQUIRE(at != std::string::npos);
    return text.replace(at, from.size(), to);
}

std::string read_text(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void check_read_error(const fs::path& path, std::string_view named, std::initializer_list<std::string_view> fragments) {
    try {
        read_mesh(path);
        BOOST_ERROR("reading " << path.filename() << " did not throw");
    } catch (const FileError& e) {
        const std::string message = e.what();
        BOOST_TEST_MESSAGE(message);
        BOOST_TEST(message.find(named) != std::string::npos, "'" << message << "' does not name " << named);
        for (std::string_view fragment : fragments)
            BOOST_TEST(message.find(fragment) != std::string::npos, "'" << message << "' lacks '" << fragment << "'");
    }
}

void check_error(const fs::path& path, std::initializer_list<std::string_view> fragments) {
    check_read_error(path, path.string(), fragments);
}

void check_error_text(const ScratchDir& dir, const std::string& name, const std::string& text,
                      std::initializer_list<std::string_view> fragments) {
    write_file(dir / name, text);
    check_read_error(dir / name, name, fragments);
}

void check_error_in_new_file(const ScratchDir& dir, std::string_view extension, const std::string& text,
                             std::initializer_list<std::string_view> fragments) {
    static int counter = 0;
    std::string name = "bad" + std::to_string(counter++);
    name += extension;
    const fs::path path = dir / name;
    write_file(path, text);
    check_error(path, fragments);
}

double signed_volume(const Mesh& mesh, ElementId e) {
    const auto t = mesh.element(e);
    const Vec3 a = mesh.point(t[0]), b = mesh.point(t[1]), c = mesh.point(t[2]), d = mesh.point(t[3]);
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
    return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0]);
}

int count_tets(const Mesh& mesh, bool positive) {
    int count = 0;
    for (ElementId e = 0; e < mesh.num_elements(); ++e) count += positive ? signed_volume(mesh, e) > 0.0 : signed_volume(mesh, e) < 0.0;
    return count;
}

bool same_bits(std::span<const double> a, std::span<const double> b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

void check_same_values(const std::vector<double>& a, const std::vector<double>& b) {
    BOOST_REQUIRE_EQUAL(a.size(), b.size());
    BOOST_TEST(std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

void check_same_mesh(const Mesh& a, const Mesh& b) {
    BOOST_TEST(static_cast<int>(a.kind()) == static_cast<int>(b.kind()));
    BOOST_REQUIRE_EQUAL(a.num_vertices(), b.num_vertices());
    BOOST_REQUIRE_EQUAL(a.num_elements(), b.num_elements());
    BOOST_TEST(std::memcmp(a.coordinates().data(), b.coordinates().data(), a.coordinates().size_bytes()) == 0);
    BOOST_TEST(std::equal(a.connectivity().begin(), a.connectivity().end(), b.connectivity().begin()));
}

Mesh awkward_triangles() {
    const int nx = 5, ny = 4;
    std::vector<double> xyz;
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i)
            xyz.insert(xyz.end(), {i / 3.0, j * std::sqrt(2.0) / 7.0, 1e-3 * std::sin(i + 2.0 * j)});
    xyz[0] = -0.0;
    xyz[1] = 4.9e-320;
    std::vector<VertexId> triangles;
    for (int j = 0; j + 1 < ny; ++j)
        for (int i = 0; i + 1 < nx; ++i) {
            const VertexId v = j * nx + i;
            triangles.insert(triangles.end(), {v, v + 1, v + nx + 1, v, v + nx + 1, v + nx});
        }
    return Mesh(ElementKind::Triangle, std::move(xyz), std::move(triangles));
}

}  // namespace paloverde::test
