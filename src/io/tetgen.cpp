// TetGen / Triangle .node + .ele files.
//
// Orientation: the format does not fix one. TetGen 1.6 writes tetrahedra with
// det(v1-v0, v2-v0, v3-v0) > 0, Paloverde's convention. Stellar writes the opposite: it keeps
// Shewchuk's orient3d(v0, v1, v2, v3) > 0, which is det(...) < 0. So the reader asks finish_mesh to
// orient the mesh by its total signed volume (the enclosed volume, positive in our convention
// even when some elements are tangled), which flips exactly the meshes written the other way.
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "paloverde/core/error.hpp"
#include "raw_mesh.hpp"
#include "text_scanner.hpp"

namespace paloverde::io {

namespace {

// TetGen allows '#' comments anywhere; a comment runs to the end of its line. The TextScanner
// underneath skips them; this adds TetGen's number messages and header checks.
class CommentedScanner {
public:
    explicit CommentedScanner(const std::string& path) : s_(path, '#') {}

    std::string_view token() { return s_.token(); }
    std::string_view expect_token(std::string_view what) { return s_.expect_token(what); }
    std::int64_t integer(std::string_view what) { return to_integer(expect_token(what), what); }
    std::int64_t to_integer(std::string_view t, std::string_view what) {
        std::int64_t value = 0;
        if (!parse_integer(t, value))
            s_.fail("expected " + std::string(what) + " (an integer), found '" + std::string(t.substr(0, 64)) + "'");
        return value;
    }
    double real(std::string_view what) {
        const std::string_view t = expect_token(what);
        double value = 0.0;
        if (!parse_real(t, value))
            s_.fail("expected " + std::string(what) + " (a number), found '" + std::string(t.substr(0, 64)) + "'");
        return value;
    }
    // The first number of a file, where the end of the file means an empty file.
    std::int64_t first_count(std::string_view what) {
        const std::string_view t = token();
        if (t.empty()) s_.fail("empty file: expected " + std::string(what));
        return check_non_negative(to_integer(t, what), what);
    }
    std::int64_t non_negative(std::string_view what) { return check_non_negative(integer(what), what); }
    std::int64_t check_non_negative(std::int64_t value, std::string_view what) {
        if (value < 0) s_.fail(std::string(what) + " is negative (" + std::to_string(value) + ")");
        return value;
    }
    // `entries` entries of `width` numbers each, every number at least one character and a
    // separator: a corrupt header fails here, before anything is allocated.
    void check_fits(std::int64_t entries, std::int64_t width, std::string_view what) {
        if (static_cast<std::uint64_t>(entries) > s_.remaining() / (2 * static_cast<std::uint64_t>(width)))
            s_.fail(std::to_string(entries) + " " + std::string(what) + " of " + std::to_string(width) +
                    " numbers each cannot fit in the rest of the file (" + std::to_string(s_.remaining()) + " bytes)");
    }
    [[noreturn]] void fail(const std::string& message) const { s_.fail(message); }

private:
    TextScanner s_;
};

std::string lower(std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

struct Nodes {
    std::int64_t count = 0;
    std::int64_t dimension = 3;
    std::int64_t base = 0;  // the first index, 0 or 1, which the .ele file uses too
};

// .node: "n dim nattr nmarkers", then "index x y [z] [attributes...] [marker]" per point.
Nodes read_node_file(const std::string& path, RawMesh& raw) {
    CommentedScanner header(path);
    const std::int64_t n = header.first_count("the number of points");
    const std::int64_t dim = header.integer("the dimension");
    if (dim != 2 && dim != 3) header.fail("dimension " + std::to_string(dim) + " is neither 2 nor 3");
    const std::int64_t attributes = header.non_negative("the number of point attributes");
    const std::int64_t markers = header.integer("the number of boundary markers");
    if (markers != 0 && markers != 1) header.fail("the number of boundary markers is " + std::to_string(markers) + ", not 0 or 1");
    if (n == 0) header.fail("the .node file holds no points");
    if (attributes > std::numeric_limits<std::int32_t>::max()) header.fail("too many point attributes");
    header.check_fits(n, 1 + dim + attributes + markers, "points");
    if (n > std::numeric_limits<VertexId>::max()) header.fail("too many points for one process (" + std::to_string(n) + ")");

    const auto count = static_cast<std::size_t>(n);
    const auto width = static_cast<std::size_t>(attributes);
    raw.coordinates.reserve(3 * count);
    const std::size_t first_field = raw.point_fields.size();
    for (std::size_t a = 0; a < width; ++a)
        raw.point_fields.push_back(Field{"attribute_" + std::to_string(a + 1), 1, std::vector<double>(count)});
    std::vector<double> marker_values(markers ? count : 0);
    Nodes nodes{n, dim, 0};
    for (std::int64_t i = 0; i < n; ++i) {
        const std::int64_t index = header.integer("a point index");
        if (i == 0) {
            if (index != 0 && index != 1) header.fail("the first point index is " + std::to_string(index) + "; it must be 0 or 1");
            nodes.base = index;
        } else if (index != nodes.base + i) {
            header.fail("point index " + std::to_string(index) + " is out of sequence (expected " +
                        std::to_string(nodes.base + i) + ")");
        }
        double xyz[3] = {0.0, 0.0, 0.0};  // 2D points lie in the plane z = 0
        for (std::int64_t c = 0; c < dim; ++c) xyz[c] = header.real("a point coordinate");
        if (!std::isfinite(xyz[0]) || !std::isfinite(xyz[1]) || !std::isfinite(xyz[2]))
            header.fail("point " + std::to_string(index) + " has a non-finite coordinate");
        raw.coordinates.insert(raw.coordinates.end(), xyz, xyz + 3);
        for (std::size_t a = 0; a < width; ++a)
            raw.point_fields[first_field + a].values[static_cast<std::size_t>(i)] = header.real("a point attribute");
        if (markers) marker_values[static_cast<std::size_t>(i)] = static_cast<double>(header.integer("a boundary marker"));
    }
    if (markers) raw.point_fields.push_back(Field{"boundary_marker", 1, std::move(marker_values)});
    return nodes;
}

// .ele: "m corners nattr", then "index v1 .. vk [attributes...]" per element. Tetrahedra have 4
// corners; Triangle's 2D meshes have triangles (3). Second-order elements (10 / 6 nodes) are
// refused rather than cut to their corners, which would strand the mid-edge points.
void read_ele_file(const std::string& path, const Nodes& nodes, RawMesh& raw) {
    CommentedScanner e(path);
    const std::int64_t m = e.first_count("the number of elements");
    const std::int64_t corners = e.integer("the number of nodes per element");
    if (corners == 10 || corners == 6)
        e.fail(std::to_string(corners) + "-node (second-order) elements cannot be read; write a linear mesh (without -o2)");
    if (corners != 4 && corners != 3) e.fail("the number of nodes per element is " + std::to_string(corners) + ", not 4 or 3");
    if (corners == 4 && nodes.dimension == 2) e.fail("tetrahedra need a 3D .node file, but the .node file is 2D");
    const std::int64_t attributes = e.non_negative("the number of element attributes");
    // Also what bounds the attribute count by the file's size (check_fits) before a field is made
    // for each attribute.
    if (m == 0) e.fail("the .ele file holds no elements");
    if (attributes > std::numeric_limits<std::int32_t>::max()) e.fail("too many element attributes");
    e.check_fits(m, 1 + corners + attributes, "elements");

    const auto count = static_cast<std::size_t>(m);
    const auto width = static_cast<std::size_t>(attributes);
    const auto k = static_cast<std::size_t>(corners);
    const CellType type = corners == 4 ? CellType::Tetrahedron : CellType::Triangle;
    raw.cell_types.reserve(count);
    raw.cell_connectivity.reserve(count * k);
    raw.cell_positions.reserve(count);
    // TetGen's -A writes one attribute per tetrahedron: the region it belongs to.
    const std::size_t first_field = raw.cell_fields.size();
    for (std::size_t a = 0; a < width; ++a)
        raw.cell_fields.push_back(Field{width == 1 ? "region" : "region_" + std::to_string(a + 1), 1, std::vector<double>(count)});
    const char* element = corners == 4 ? "tetrahedron" : "triangle";
    raw.cell_name = [element, base = nodes.base](std::size_t position, CellType) {
        std::string name = element;  // built with += (GCC 12 warns, wrongly, on const char* + string)
        name += ' ';
        name += std::to_string(base + static_cast<std::int64_t>(position));
        return name;
    };
    const std::int64_t last = nodes.base + nodes.count - 1;
    for (std::int64_t i = 0; i < m; ++i) {
        const std::int64_t index = e.integer("an element index");
        if (index != nodes.base + i)
            e.fail("element index " + std::to_string(index) + " is out of sequence (expected " + std::to_string(nodes.base + i) +
                   ", numbering from " + std::to_string(nodes.base) + " like the .node file)");
        VertexId vertices[4];
        for (std::size_t c = 0; c < k; ++c) {
            const std::int64_t v = e.integer("a point index");
            if (v < nodes.base || v > last)
                e.fail(std::string(element) + " " + std::to_string(index) + " refers to point " + std::to_string(v) +
                       ", outside " + std::to_string(nodes.base) + ".." + std::to_string(last));
            vertices[c] = static_cast<VertexId>(v - nodes.base);
        }
        raw.add_cell(type, vertices, static_cast<std::size_t>(i));
        for (std::size_t a = 0; a < width; ++a)
            raw.cell_fields[first_field + a].values[static_cast<std::size_t>(i)] = e.real("an element attribute");
    }
}

}  // namespace

RawMesh read_tetgen(const std::string& path) {
    const std::filesystem::path given(path);
    const std::string extension = lower(given.extension().string());
    if (extension != ".node" && extension != ".ele")
        throw FileError(path, 0, "a TetGen mesh is named by its .node or .ele file");
    // The sibling keeps the case of the extension given: x.NODE goes with x.ELE.
    const bool upper = given.extension().string() != extension;
    std::filesystem::path stem = given;
    const std::string node_path = stem.replace_extension(upper ? ".NODE" : ".node").string();
    const std::string ele_path = stem.replace_extension(upper ? ".ELE" : ".ele").string();
    for (const std::string& part : {node_path, ele_path})
        if (!std::filesystem::exists(part))
            throw FileError(part, 0, "no such file (a TetGen mesh is a .node file and an .ele file with the same name)");

    RawMesh raw;
    const Nodes nodes = read_node_file(node_path, raw);
    read_ele_file(ele_path, nodes, raw);
    return raw;
}

}  // namespace paloverde::io
