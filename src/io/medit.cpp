// Medit .mesh files (ASCII), as written by MMG, TetWild, Medit and many others.
//
// Orientation: Medit files (TetWild's among them) have det(v1-v0, v2-v0, v3-v0) > 0 for every
// tetrahedron, the convention Paloverde uses, so elements are read as written. Quadrilaterals,
// hexahedra and pyramids have VTK's vertex order; a prism's first triangle points towards the
// second, the mirror of a VTK wedge (CellInfo::gmsh_order, as in Gmsh).
#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <ostream>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "paloverde/core/error.hpp"
#include "raw_mesh.hpp"
#include "text_scanner.hpp"

namespace paloverde::io {

namespace {

std::string lower(std::string_view s) {
    std::string out(s);
    for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return out;
}

// Medit allows '#' comments wherever whitespace may appear; a comment runs to the end of its
// line. The TextScanner underneath skips them; this adds Medit's number messages and counts.
class MeditScanner {
public:
    explicit MeditScanner(const std::string& path) : s_(path, '#') {}

    std::string_view token() { return s_.token(); }
    std::string_view expect_token(std::string_view what) { return s_.expect_token(what); }
    std::int64_t integer(std::string_view what) { return s_.integer(what); }
    double real(std::string_view what) {
        const std::string_view t = expect_token(what);
        double value = 0.0;
        if (!parse_real(t, value))
            s_.fail("expected " + std::string(what) + " (a number), found '" + std::string(t.substr(0, 64)) + "'" +
                    s_.in_entry());
        return value;
    }
    // A count of items that each take at least `min_bytes`: a corrupt count fails here, before
    // anything is allocated.
    std::int64_t count(std::string_view what, std::size_t min_bytes) {
        const std::int64_t value = integer(what);
        if (value < 0) s_.fail(std::string(what) + " is negative (" + std::to_string(value) + ")");
        if (static_cast<std::uint64_t>(value) > s_.remaining() / min_bytes)
            s_.fail(std::string(what) + " of " + std::to_string(value) + " cannot fit in the rest of the file (" +
                    std::to_string(s_.remaining()) + " bytes)");
        return value;
    }
    [[noreturn]] void fail(const std::string& message) const { s_.fail(message); }
    void set_entry(std::function<std::string()> entry) { s_.set_entry(std::move(entry)); }

private:
    TextScanner s_;
};

// Sections whose content Paloverde does not need: the number of values per entry (d is the
// dimension). All of them are lower-dimensional or per-vertex decorations of the mesh.
int skipped_section_width(const std::string& keyword, int d) {
    if (keyword == "edges") return 3;
    if (keyword == "corners" || keyword == "ridges" || keyword == "requiredvertices" || keyword == "requirededges" ||
        keyword == "requiredtriangles")
        return 1;
    if (keyword == "normals" || keyword == "tangents") return d;
    if (keyword == "normalatvertices" || keyword == "tangentatvertices") return 2;
    return 0;
}

// The cell type of an element section ("hexahedra" for Hexahedra), or nullptr.
const CellInfo* section_cell(const std::string& keyword) {
    return find_cell([&](const CellInfo& c) { return lower(c.medit) == keyword; });
}

// How Medit calls one element of a section: "prism" for Prisms, else the cell's name.
std::string element_noun(const CellInfo& info) {
    return info.type == CellType::Wedge ? "prism" : std::string(info.name);
}

class MeditReader {
public:
    explicit MeditReader(const std::string& path) : s_(path) { starts_.fill(-1); }
    RawMesh read();

private:
    void read_vertices();
    void read_elements(const CellInfo& info);

    MeditScanner s_;
    int dimension_ = 0;
    std::int64_t vertices_ = -1;
    // Where each type's section starts in the elements of all sections; -1 before it is read.
    std::array<std::int64_t, kCellTypeCount> starts_;
    std::vector<double> vertex_refs_;
    std::vector<double> cell_refs_;  // one per element of every section, in file order
    RawMesh raw_;
};

RawMesh MeditReader::read() {
    const std::string_view first = s_.token();
    if (first.empty()) s_.fail("empty file: expected MeshVersionFormatted");
    if (lower(first) != "meshversionformatted")
        s_.fail("expected MeshVersionFormatted at the start of a Medit file, found '" + std::string(first.substr(0, 64)) + "'");
    const std::int64_t version = s_.integer("the MeshVersionFormatted number");
    // The versions differ only in the binary .meshb layout; the ASCII text is the same.
    if (version < 1 || version > 4) s_.fail("MeshVersionFormatted " + std::to_string(version) + " is not 1, 2, 3 or 4");

    for (;;) {
        const std::string_view t = s_.token();
        if (t.empty()) break;  // "End" is optional in practice
        const std::string keyword = lower(t);
        if (keyword == "end") break;
        if (keyword == "dimension") {
            if (dimension_ != 0) s_.fail("a second Dimension keyword");
            const std::int64_t d = s_.integer("the dimension");
            if (d != 2 && d != 3) s_.fail("Dimension " + std::to_string(d) + " is neither 2 nor 3");
            dimension_ = static_cast<int>(d);
        } else if (keyword == "vertices") {
            if (dimension_ == 0) s_.fail("Vertices comes before Dimension");
            if (vertices_ >= 0) s_.fail("a second Vertices section");
            read_vertices();
        } else if (const CellInfo* cell = section_cell(keyword)) {
            if (starts_[static_cast<std::size_t>(cell->type)] >= 0) s_.fail("a second " + std::string(cell->medit) + " section");
            read_elements(*cell);
        } else if (const int width = skipped_section_width(keyword, dimension_ == 0 ? 3 : dimension_); width > 0) {
            const std::int64_t n = s_.count("the number of " + std::string(t), 2 * static_cast<std::size_t>(width));
            const std::string what = "an entry of " + std::string(t);
            for (std::int64_t i = 0; i < n * width; ++i) s_.expect_token(what);
        } else {
            s_.fail("unknown Medit keyword '" + std::string(t.substr(0, 64)) + "'");
        }
    }
    if (vertices_ < 0) s_.fail("the file has no Vertices section");

    raw_.point_fields.push_back(Field{"ref", 1, std::move(vertex_refs_)});
    raw_.cell_fields.push_back(Field{"ref", 1, std::move(cell_refs_)});
    // Messages name an element by its section and number there, as Medit does: "hexahedron 3".
    raw_.cell_name = [starts = starts_](std::size_t position, CellType type) {
        const auto number = static_cast<std::int64_t>(position) - starts[static_cast<std::size_t>(type)] + 1;
        return element_noun(cell_info(type)) + " " + std::to_string(number);
    };
    return std::move(raw_);
}

void MeditReader::read_vertices() {
    const int d = dimension_;
    // d coordinates and a reference, each at least one character and a separator.
    const std::int64_t n = s_.count("the number of vertices", 2 * (static_cast<std::size_t>(d) + 1));
    if (n > std::numeric_limits<VertexId>::max()) s_.fail("too many vertices for one process (" + std::to_string(n) + ")");
    raw_.coordinates.reserve(3 * static_cast<std::size_t>(n));
    vertex_refs_.reserve(static_cast<std::size_t>(n));
    for (std::int64_t v = 1; v <= n; ++v) {
        double xyz[3] = {0.0, 0.0, 0.0};  // 2D meshes lie in the plane z = 0
        for (int c = 0; c < d; ++c) xyz[c] = s_.real("a vertex coordinate");
        if (!std::isfinite(xyz[0]) || !std::isfinite(xyz[1]) || !std::isfinite(xyz[2]))
            s_.fail("vertex " + std::to_string(v) + " has a non-finite coordinate");
        raw_.coordinates.insert(raw_.coordinates.end(), xyz, xyz + 3);
        vertex_refs_.push_back(static_cast<double>(s_.integer("a vertex reference")));
    }
    vertices_ = n;
}

void MeditReader::read_elements(const CellInfo& info) {
    const std::string section(info.medit);
    if (vertices_ < 0) s_.fail(section + " comes before Vertices");
    const auto corners = static_cast<std::size_t>(info.corners);
    const std::int64_t n = s_.count("the number of " + lower(section), 2 * (corners + 1));
    starts_[static_cast<std::size_t>(info.type)] = static_cast<std::int64_t>(cell_refs_.size());
    raw_.cell_connectivity.reserve(raw_.cell_connectivity.size() + static_cast<std::size_t>(n) * corners);
    VertexId vertices[kMaxCellCorners];
    std::int64_t e = 1;
    s_.set_entry([&] { return element_noun(info) + " " + std::to_string(e); });
    for (; e <= n; ++e) {
        for (std::size_t c = 0; c < corners; ++c) {
            const std::int64_t v = s_.integer("a vertex number");
            if (v < 1 || v > vertices_)
                s_.fail(element_noun(info) + " " + std::to_string(e) + " refers to vertex " + std::to_string(v) +
                        "; vertices are numbered 1 to " + std::to_string(vertices_));
            vertices[c] = static_cast<VertexId>(v - 1);
        }
        raw_.add_file_cell(info.type, vertices, cell_refs_.size());
        cell_refs_.push_back(static_cast<double>(s_.integer("an element reference")));
    }
    s_.set_entry({});
}

// Formats into one string and hands it to the stream in large pieces.
class Output {
public:
    explicit Output(std::ostream& out) : out_(out) { buffer_.reserve(kChunk + 4096); }
    void text(std::string_view s) {
        buffer_.append(s);
        if (buffer_.size() >= kChunk) flush();
    }
    void integer(std::int64_t value) {
        char digits[24];
        buffer_.append(digits, std::to_chars(digits, digits + sizeof digits, value).ptr);
    }
    // The shortest decimal form that reads back as the same double (at most 17 significant
    // digits), so round trips are exact.
    void real(double value) {
        char digits[32];
        buffer_.append(digits, std::to_chars(digits, digits + sizeof digits, value).ptr);
    }
    void flush() {
        out_.write(buffer_.data(), static_cast<std::streamsize>(buffer_.size()));
        buffer_.clear();
    }

private:
    static constexpr std::size_t kChunk = 1 << 20;
    std::ostream& out_;
    std::string buffer_;
};

// Medit references are integers: a `ref` field holding anything else cannot be written.
std::vector<std::int64_t> references(std::span<const Field> fields, std::size_t count, const char* kind) {
    std::vector<std::int64_t> refs(count, 0);
    const auto field = std::find_if(fields.begin(), fields.end(), [](const Field& f) { return f.name == "ref"; });
    if (field == fields.end()) return refs;
    if (field->components != 1)
        throw Error(std::string(kind) + " field 'ref' has " + std::to_string(field->components) +
                    " components; Medit references are single integers");
    for (std::size_t i = 0; i < count; ++i) {
        const double value = field->values[i];
        if (!(std::floor(value) == value && std::abs(value) <= 2147483647.0))
            throw Error(std::string(kind) + " field 'ref' holds " + std::to_string(value) + " at index " +
                        std::to_string(i) + "; Medit references are integers");
        refs[i] = static_cast<std::int64_t>(value);
    }
    return refs;
}

}  // namespace

RawMesh read_medit(const std::string& path) { return MeditReader(path).read(); }

// Always 3D, so that a triangle mesh off the xy plane keeps its z. Medit has no place for other
// fields; the fixed flags come back by boundary detection. Each cell type has a section of its
// own, in the order of cell_types.hpp: a mixed mesh's cells come back grouped by type.
void write_medit(std::ostream& stream, const MeshToWrite& data) {
    const Mesh& mesh = data.mesh;
    const auto n = static_cast<std::size_t>(mesh.num_vertices());
    const std::size_t m = data.cells();
    const std::vector<std::int64_t> vertex_refs = references(data.point_fields, n, "point");
    const std::vector<std::int64_t> cell_refs = references(data.cell_fields, m, "cell");
    const std::span<const double> xyz = mesh.coordinates();

    Output out(stream);
    out.text("MeshVersionFormatted 2\n\nDimension 3\n\nVertices\n");
    out.integer(static_cast<std::int64_t>(n));
    out.text("\n");
    for (std::size_t v = 0; v < n; ++v) {
        for (int c = 0; c < 3; ++c) {
            out.real(xyz[3 * v + c]);
            out.text(" ");
        }
        out.integer(vertex_refs[v]);
        out.text("\n");
    }
    std::array<std::size_t, kCellTypeCount> counts{};
    for (std::size_t c = 0; c < m; ++c) ++counts[static_cast<std::size_t>(data.type(c))];
    VertexId element[kMaxCellCorners];
    for (const CellInfo& info : all_cell_infos()) {
        const std::size_t count = counts[static_cast<std::size_t>(info.type)];
        if (count == 0) continue;
        out.text("\n");
        out.text(info.medit);
        out.text("\n");
        out.integer(static_cast<std::int64_t>(count));
        out.text("\n");
        for (std::size_t c = 0; c < m; ++c) {
            if (data.type(c) != info.type) continue;
            to_file_order(info.type, data.cell(c), element);
            for (int i = 0; i < info.corners; ++i) {
                out.integer(static_cast<std::int64_t>(element[i]) + 1);
                out.text(" ");
            }
            out.integer(cell_refs[c]);
            out.text("\n");
        }
    }
    out.text("\nEnd\n");
    out.flush();
}

}  // namespace paloverde::io
