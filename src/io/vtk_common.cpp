#include "vtk_common.hpp"

#include <charconv>
#include <set>

#include "paloverde/core/error.hpp"

namespace paloverde::io::vtk {

std::string_view cell_type_name(std::int64_t type) {
    switch (type) {
        case 0: return "empty cell";
        case 1: return "vertex";
        case 2: return "poly-vertex";
        case 3: return "line";
        case 4: return "poly-line";
        case 5: return "triangle";
        case 6: return "triangle strip";
        case 7: return "polygon";
        case 8: return "pixel";
        case 9: return "quad";
        case 10: return "tetrahedron";
        case 11: return "voxel";
        case 12: return "hexahedron";
        case 13: return "wedge";
        case 14: return "pyramid";
        case 15: return "pentagonal prism";
        case 16: return "hexagonal prism";
        case 21: return "quadratic edge";
        case 22: return "quadratic triangle";
        case 23: return "quadratic quad";
        case 24: return "quadratic tetrahedron";
        case 25: return "quadratic hexahedron";
        case 26: return "quadratic wedge";
        case 27: return "quadratic pyramid";
        case 28: return "biquadratic quad";
        case 29: return "triquadratic hexahedron";
        case 30: return "quadratic-linear quad";
        case 31: return "quadratic-linear wedge";
        case 32: return "biquadratic-quadratic wedge";
        case 33: return "biquadratic-quadratic hexahedron";
        case 34: return "biquadratic triangle";
        case 35: return "cubic line";
        case 36: return "quadratic polygon";
        case 37: return "triquadratic pyramid";
        case 41: return "convex point set";
        case 42: return "polyhedron";
        case 68: return "Lagrange curve";
        case 69: return "Lagrange triangle";
        case 70: return "Lagrange quadrilateral";
        case 71: return "Lagrange tetrahedron";
        case 72: return "Lagrange hexahedron";
        case 73: return "Lagrange wedge";
        case 74: return "Lagrange pyramid";
        case 75: return "Bezier curve";
        case 76: return "Bezier triangle";
        case 77: return "Bezier quadrilateral";
        case 78: return "Bezier tetrahedron";
        case 79: return "Bezier hexahedron";
        case 80: return "Bezier wedge";
        case 81: return "Bezier pyramid";
        default: return "unknown";
    }
}

namespace {
const CellInfo* vtk_cell(std::int64_t type) {
    return find_cell([&](const CellInfo& c) { return c.vtk == type; });
}
}  // namespace

std::string cell_problem(std::size_t cell, std::int64_t type, std::int64_t corners) {
    const CellInfo* info = vtk_cell(type);
    if ((type >= 0 && type <= 4) || (info && corners == info->corners)) return {};
    const std::string which = "cell " + std::to_string(cell) + " has VTK type " + std::to_string(type) + " (" +
                              std::string(cell_type_name(type)) + ")";
    if (info)
        return which + " but " + std::to_string(corners) + " points; a " + std::string(info->name) + " has " +
               std::to_string(info->corners);
    return which + "; Paloverde handles " + handled_cells(&CellInfo::vtk);
}

void add_cell(RawMesh& raw, std::size_t cell, std::int64_t type, const std::int64_t* ids) {
    const CellInfo* info = vtk_cell(type);
    if (!info) return;
    VertexId vertices[kMaxCellCorners];
    for (int i = 0; i < info->corners; ++i) vertices[i] = static_cast<VertexId>(ids[i]);
    raw.add_cell(info->type, vertices, cell);
}

std::size_t size_of(ValueType type) {
    switch (type) {
        case ValueType::Int8:
        case ValueType::UInt8:
        case ValueType::Bit: return 1;
        case ValueType::Int16:
        case ValueType::UInt16: return 2;
        case ValueType::Int32:
        case ValueType::UInt32:
        case ValueType::Float32: return 4;
        case ValueType::Int64:
        case ValueType::UInt64:
        case ValueType::Float64: return 8;
    }
    return 8;
}

bool is_integer(ValueType type) { return type != ValueType::Float32 && type != ValueType::Float64; }

std::string legacy_name(std::string_view name) {
    if (name.empty()) return "unnamed";
    std::string out;
    for (char c : name) {
        const auto u = static_cast<unsigned char>(c);
        if (u <= ' ' || u == 0x7F)
            out += '_';
        else if (c == '%')
            out += "%25";
        else
            out += c;
    }
    return out;
}

std::string decode_legacy_name(std::string_view name) {
    std::string out;
    for (std::size_t i = 0; i < name.size(); ++i) {
        unsigned value = 0;
        if (name[i] == '%' && i + 2 < name.size()) {
            const auto r = std::from_chars(name.data() + i + 1, name.data() + i + 3, value, 16);
            if (r.ec == std::errc() && r.ptr == name.data() + i + 3) {
                out += static_cast<char>(value);
                i += 2;
                continue;
            }
        }
        out += name[i];
    }
    return out;
}

void check_unique_names(std::span<const Field> fields, std::string_view kind, bool legacy) {
    std::set<std::string> seen;
    for (const Field& f : fields) {
        const std::string written = legacy ? legacy_name(f.name) : f.name;
        if (!seen.insert(written).second)
            throw Error("two " + std::string(kind) + " fields would both be written as '" + written +
                        "'; rename one so that a reader can tell them apart");
    }
}

Output::Output(std::ostream& out) : out_(out) { buffer_.reserve(kChunk); }

Output& Output::text(std::string_view s) {
    reserve(s.size());
    buffer_.append(s);
    return *this;
}

Output& Output::text(char c) {
    reserve(1);
    buffer_ += c;
    return *this;
}

Output& Output::real(double value) {
    char digits[32];
    const auto r = std::to_chars(digits, digits + sizeof digits, value, std::chars_format::general, 17);
    return text(std::string_view(digits, static_cast<std::size_t>(r.ptr - digits)));
}

Output& Output::integer(std::int64_t value) {
    char digits[24];
    const auto r = std::to_chars(digits, digits + sizeof digits, value);
    return text(std::string_view(digits, static_cast<std::size_t>(r.ptr - digits)));
}

void Output::flush() {
    out_.write(buffer_.data(), static_cast<std::streamsize>(buffer_.size()));
    buffer_.clear();
}

}  // namespace paloverde::io::vtk
