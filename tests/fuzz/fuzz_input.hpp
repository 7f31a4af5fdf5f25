#pragma once
// What the fuzz targets (tests/fuzz) and the regression replay (tests/io) share: one input, read
// as a mesh file of one format, and the checks on what the reader makes of it.
//
// The readers read files, so the input goes to a scratch file first. A paloverde::Error is the
// reader refusing bad input, which is its job. A crash, a sanitizer report, a leak, a giant
// allocation, a hang, any other exception, or a mesh that does not survive a write and a re-read
// is a finding; the checks report the last two by throwing CheckFailure.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "paloverde/core/error.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/mesh.hpp"

namespace paloverde::fuzz {

// Deliberately not a paloverde::Error, so that nothing that expects reader errors swallows it.
class CheckFailure : public std::logic_error {
public:
    using std::logic_error::logic_error;
};

// A TetGen mesh is two files; one fuzz input holds both, the .node text, this line, then the .ele
// text. Without the line the whole input is the .node file and the .ele file is empty.
inline constexpr std::string_view kTetgenSeparator = "\n-- .ele --\n";

struct TetgenParts {
    std::string_view node;
    std::string_view ele;
};

inline TetgenParts split_tetgen(std::string_view input) {
    const std::size_t at = input.find(kTetgenSeparator);
    if (at == std::string_view::npos) return {input, {}};
    return {input.substr(0, at), input.substr(at + kTetgenSeparator.size())};
}

inline void write_bytes(const std::filesystem::path& path, std::string_view bytes) {
    std::FILE* file = std::fopen(path.c_str(), "wb");
    if (!file) throw std::runtime_error("cannot create " + path.string());
    const bool written = std::fwrite(bytes.data(), 1, bytes.size(), file) == bytes.size();
    if (std::fclose(file) != 0 || !written) throw std::runtime_error("cannot write " + path.string());
}

// The file name an input of `format` is written to (TetGen: the .node file; its .ele sits beside).
inline std::string file_name(MeshFormat format) {
    switch (format) {
        case MeshFormat::VtkLegacy: return "input.vtk";
        case MeshFormat::Vtu: return "input.vtu";
        case MeshFormat::Gmsh: return "input.msh";
        case MeshFormat::Medit: return "input.mesh";
        case MeshFormat::TetGen: return "input.node";
        case MeshFormat::FromExtension: break;
    }
    throw std::logic_error("no file name for this format");
}

// Writes `input` as a file (TetGen: two files) of `format` in `dir`; returns the path to read.
inline std::filesystem::path write_input(const std::filesystem::path& dir, MeshFormat format, std::string_view input) {
    const std::filesystem::path path = dir / file_name(format);
    if (format == MeshFormat::TetGen) {
        const TetgenParts parts = split_tetgen(input);
        write_bytes(path, parts.node);
        write_bytes(dir / "input.ele", parts.ele);
    } else {
        write_bytes(path, input);
    }
    return path;
}

inline void check(bool condition, const std::string& message) {
    if (!condition) throw CheckFailure(message);
}

// What finish_mesh promises about a mesh it returns.
inline void check_mesh_file(const MeshFile& file) {
    const auto n = static_cast<std::size_t>(file.mesh.num_vertices());
    const auto m = static_cast<std::size_t>(file.mesh.num_cells());
    check(file.mesh.num_elements() > 0, "a mesh without elements was returned");
    check(file.mesh.fixed().size() == n, "the fixed flags do not cover the vertices");
    if (file.mesh.is_planar()) {
        const Vec3& normal = file.mesh.plane_normal();
        const double length = std::sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
        check(std::abs(length - 1.0) < 1e-9, "a planar mesh without a unit plane normal");
    }
    for (const Field& f : file.point_fields)
        check(f.components >= 1 && f.values.size() == n * static_cast<std::size_t>(f.components),
              "point field '" + f.name + "' does not have one tuple per vertex");
    for (const Field& f : file.cell_fields)
        check(f.components >= 1 && f.values.size() == m * static_cast<std::size_t>(f.components),
              "cell field '" + f.name + "' does not have one tuple per cell");
}

// A mesh's cells (its elements when it has none), as types and vertices.
struct Cells {
    std::vector<CellType> types;
    std::vector<VertexId> vertices;
};
inline Cells cells_of(const Mesh& mesh, std::span<const ElementId> order = {}) {
    Cells out;
    for (ElementId i = 0; i < mesh.num_cells(); ++i) {
        const ElementId c = order.empty() ? i : order[static_cast<std::size_t>(i)];
        out.types.push_back(mesh.cell_type(c));
        out.vertices.insert(out.vertices.end(), mesh.cell(c).begin(), mesh.cell(c).end());
    }
    return out;
}
// The cells in the order a Medit file holds them: grouped by type (in the order of
// cell_types.hpp), in mesh order within a type.
inline Cells grouped_by_type(const Mesh& mesh) {
    std::vector<ElementId> order(static_cast<std::size_t>(mesh.num_cells()));
    for (std::size_t c = 0; c < order.size(); ++c) order[c] = static_cast<ElementId>(c);
    std::stable_sort(order.begin(), order.end(),
                     [&](ElementId x, ElementId y) { return mesh.cell_type(x) < mesh.cell_type(y); });
    return cells_of(mesh, order);
}

// Writes `file` as `format`, reads it back and compares. The writer may refuse (Error) what it
// cannot represent, such as two field names that would be written alike; but what it writes
// must read back as the same mesh, bit for bit.
inline void check_round_trip(const MeshFile& file, const std::filesystem::path& dir, MeshFormat format,
                             Encoding encoding) {
    WriteOptions options;
    options.format = format;
    options.encoding = encoding;
    const std::filesystem::path path = dir / ("round_trip" + file_name(format).substr(5));
    try {
        write_mesh(path, file.mesh, options, file.point_fields, file.cell_fields);
    } catch (const Error&) {
        return;
    }
    const std::string how = std::string(to_string(format)) + (encoding == Encoding::Binary ? " (binary)" : " (ascii)");
    MeshFile back;
    try {
        ReadOptions read_options;
        read_options.format = format;
        back = read_mesh(path, read_options);
    } catch (const Error& e) {
        throw CheckFailure("a mesh written as " + how + " cannot be read back: " + e.what());
    }
    const Mesh& a = file.mesh;
    const Mesh& b = back.mesh;
    check(a.kind() == b.kind(), "the element kind changed in a round trip through " + how);
    // Medit holds a section per cell type: a mixed mesh comes back with its cells grouped by type.
    const Cells cells_a = format == MeshFormat::Medit ? grouped_by_type(a) : cells_of(a);
    const Cells cells_b = cells_of(b);
    check(cells_a.types == cells_b.types, "the cell types changed in a round trip through " + how);
    check(cells_a.vertices == cells_b.vertices, "the connectivity changed in a round trip through " + how);
    const auto xa = a.coordinates(), xb = b.coordinates();
    check(xa.size() == xb.size() && std::equal(xa.begin(), xa.end(), xb.begin(),
                                               [](double u, double v) {
                                                   std::uint64_t bu = 0, bv = 0;
                                                   std::memcpy(&bu, &u, sizeof u);
                                                   std::memcpy(&bv, &v, sizeof v);
                                                   return bu == bv;
                                               }),
          "the coordinates changed in a round trip through " + how);
    // Medit has no place for the fixed flags: they come back from the boundary.
    if (format != MeshFormat::Medit)
        check(std::equal(a.fixed().begin(), a.fixed().end(), b.fixed().begin(), b.fixed().end()),
              "the fixed flags changed in a round trip through " + how);
    else
        check(file.point_fields.size() <= back.point_fields.size() &&
                  file.cell_fields.size() <= back.cell_fields.size(),
              "fields were lost in a round trip through " + how);
}

// The formats a mesh read as `format` is written back to: its own, or (TetGen, which is read
// only) .vtu.
inline MeshFormat round_trip_format(MeshFormat format) { return format == MeshFormat::TetGen ? MeshFormat::Vtu : format; }

// Reads `input` as `format` in `dir`. Returns whether a mesh was read (false: a paloverde::Error,
// the expected outcome for most inputs). Throws CheckFailure, or lets any other exception out.
inline bool read_input(const std::filesystem::path& dir, MeshFormat format, std::string_view input) {
    const std::filesystem::path path = write_input(dir, format, input);
    MeshFile file;
    try {
        ReadOptions options;
        options.format = format;
        file = read_mesh(path, options);
    } catch (const Error&) {
        return false;
    }
    check_mesh_file(file);
    // Both encodings, one per input (chosen by its size) to halve the cost.
    check_round_trip(file, dir, round_trip_format(format), input.size() % 2 ? Encoding::Binary : Encoding::Ascii);
    return true;
}

}  // namespace paloverde::fuzz
