#include "paloverde/io/mesh_io.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <string>
#include <string_view>
#include <vector>

#include "paloverde/core/error.hpp"
#include "paloverde/io/atomic_file.hpp"
#include "core/prefetch.hpp"
#include "raw_mesh.hpp"

namespace paloverde {

namespace {
std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return s;
}

// Keeps the tuples of `field` that belong to the kept cells.
// Checked before anything is allocated: a file may declare a cell field of many components
// before it declares its cells (VTK legacy CELL_DATA 0 ahead of CELLS), so the declared width
// alone bounds nothing.
Field narrow_cell_field(const Field& field, std::span<const std::size_t> kept_cells, const std::string& path) {
    const std::size_t tuples = field.values.size() / static_cast<std::size_t>(field.components);
    for (std::size_t cell : kept_cells)
        if (cell >= tuples)
            throw FileError(path, 0, "cell field '" + field.name + "' has " + std::to_string(tuples) +
                                         " values, fewer than the cells");
    Field out{field.name, field.components, {}};
    out.values.reserve(kept_cells.size() * static_cast<std::size_t>(field.components));
    for (std::size_t cell : kept_cells) {
        const auto first = field.values.begin() + static_cast<std::ptrdiff_t>(cell * field.components);
        out.values.insert(out.values.end(), first, first + field.components);
    }
    return out;
}
// "a, b and c", naming at most six.
template <class Id>
std::string listed(const std::vector<Id>& ids) {
    std::string out;
    for (std::size_t c = 0; c < ids.size() && c < 6; ++c)
        out += (c == 0 ? "" : c + 1 == ids.size() ? " and " : ", ") + std::to_string(ids[c]);
    if (ids.size() > 6) out += ", ...";
    return out;
}

[[noreturn]] void refuse_shared_face(const std::string& path, const std::vector<VertexId>& face, bool faces,
                                     const std::vector<ElementId>& sharing, std::string_view kind) {
    throw FileError(path, 0, std::string(faces ? "the face of vertices " : "the edge of vertices ") + listed(face) +
                                 " belongs to " + std::to_string(sharing.size()) + " " + std::string(kind) + " (" +
                                 (kind == "cells" ? "" : "elements ") + listed(sharing) +
                                 "), but at most two can share it (a non-manifold mesh; numbers count from 0)");
}

// The boundary vertices (on a face, or a triangle's edge, of one element only), as
// boundary_vertices() finds them, and the checks that no two elements have the same vertices
// and that no face is in more than two elements: such a mesh no vertex placement can make valid
// (untangling could not succeed, and the face would pass for an interior one). Each vertex in
// turn lists the faces whose smallest vertex it is, and the elements whose smallest vertex it is,
// and sorts those short lists (the elements as check_no_duplicate_elements does, so the same pair
// is named). Only an element's two smallest vertices are the smallest of any of its faces, so each
// element is listed at those two (a counting sort of the element ids, in a pass in file order),
// not at all of its vertices. Those elements lie scattered in a mesh in file order, so their
// corners are asked for a few elements ahead; the loads overlap, where scattering every face into
// rows wrote to a cache line of its own at nearly every face (twice as slow).
std::vector<std::uint8_t> manifold_boundary(const Mesh& mesh, const std::string& path) {
    const int k = mesh.corners();
    const auto n = static_cast<std::size_t>(mesh.num_vertices());
    const auto m = static_cast<std::size_t>(mesh.num_elements());
    const VertexId* corners = mesh.connectivity().data();
    const auto ahead = static_cast<std::size_t>(detail::kPrefetchAroundAhead);
    std::vector<std::uint8_t> boundary(n, 0);
    const auto size = static_cast<std::size_t>(k - 1);
    constexpr VertexId kNone = std::numeric_limits<VertexId>::max();
    auto key = [](VertexId a, VertexId b) {  // a face's others, packed increasing (a triangle's edge: b = 0)
        return static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32 | static_cast<std::uint32_t>(b);
    };
    // An element's two smallest vertices, without branching on the ids.
    auto two_smallest = [&](const VertexId* c) {
        VertexId low = std::min(c[0], c[1]), second = std::max(c[0], c[1]);
        for (int j = 2; j < k; ++j) {
            second = std::min(second, std::max(low, c[j]));
            low = std::min(low, c[j]);
        }
        return std::pair{low, second};
    };
    std::vector<std::int64_t> first_listed(n + 1, 0);
    for (std::size_t e = 0; e < m; ++e) {
        const auto [low, second] = two_smallest(corners + k * e);
        ++first_listed[static_cast<std::size_t>(low) + 1];
        ++first_listed[static_cast<std::size_t>(second) + 1];
    }
    std::partial_sum(first_listed.begin(), first_listed.end(), first_listed.begin());
    std::vector<ElementId> listed_at(2 * m);
    {
        std::vector<std::int64_t> next(first_listed.begin(), first_listed.end() - 1);
        for (std::size_t e = 0; e < m; ++e) {
            const auto [low, second] = two_smallest(corners + k * e);
            listed_at[static_cast<std::size_t>(next[static_cast<std::size_t>(low)]++)] = static_cast<ElementId>(e);
            listed_at[static_cast<std::size_t>(next[static_cast<std::size_t>(second)]++)] = static_cast<ElementId>(e);
        }
    }
    std::int64_t most_listed = 0;
    for (std::size_t v = 0; v < n; ++v) most_listed = std::max(most_listed, first_listed[v + 1] - first_listed[v]);
    // At this vertex: the others of each face, packed increasing (at most three per element); the
    // elements whose smallest vertex it is, by their other corners, then the element.
    std::vector<std::uint64_t> faces(3 * static_cast<std::size_t>(most_listed));
    std::vector<std::pair<std::uint64_t, std::uint64_t>> own;
    // The table of one vertex's faces, at most half full: a slot belongs to the vertex whose stamp
    // it holds, so nothing is cleared between vertices.
    int table_bits = 6;
    while ((std::size_t{1} << table_bits) < 2 * faces.size()) ++table_bits;
    const std::size_t table_mask = (std::size_t{1} << table_bits) - 1;
    const int table_shift = 64 - table_bits;
    std::vector<std::uint64_t> table_key(table_mask + 1);
    std::vector<std::uint32_t> table_stamp(table_mask + 1, 0);
    std::vector<std::uint32_t> table_count(table_mask + 1);
    std::vector<std::uint32_t> used(faces.size());
    std::size_t used_count = 0;
    std::uint32_t stamp = 1;
    for (std::size_t v = 0; v < n; ++v) {
        const auto vertex = static_cast<VertexId>(v);
        const auto begin = static_cast<std::size_t>(first_listed[v]), end = static_cast<std::size_t>(first_listed[v + 1]);
        std::size_t listed = 0;
        own.clear();
        for (std::size_t i = begin; i < end; ++i) {
            if (i + ahead < listed_at.size()) __builtin_prefetch(corners + k * static_cast<std::size_t>(listed_at[i + ahead]));
            const VertexId* c = corners + k * static_cast<std::size_t>(listed_at[i]);
            // v is the smallest vertex of the faces through it whose other corners are all larger:
            // with L corners above v, a tetrahedron has C(L, 2) such faces, a triangle L edges. The
            // larger corners are gathered and sorted without branching on their values (which
            // would mispredict at nearly every corner); unused slots hold kNone.
            VertexId larger[4] = {kNone, kNone, kNone, kNone};
            int count = 0;
            for (int j = 0; j < k; ++j) {
                larger[count] = c[j];
                count += c[j] > vertex;
            }
            larger[count] = kNone;
            auto order = [&](int a, int b) {
                const VertexId low = std::min(larger[a], larger[b]), high = std::max(larger[a], larger[b]);
                larger[a] = low, larger[b] = high;
            };
            std::uint64_t* out = faces.data() + listed;
            if (k == 4) {
                order(0, 1), order(1, 2), order(0, 1);
                out[0] = key(larger[0], larger[1]);
                out[1] = key(larger[0], larger[2]);
                out[2] = key(larger[1], larger[2]);
                listed += static_cast<std::size_t>(count * (count - 1) / 2);
                if (count == 3) own.emplace_back(out[0], key(larger[2], static_cast<VertexId>(listed_at[i])));
            } else {
                out[0] = key(larger[0], 0);
                out[1] = key(larger[1], 0);
                listed += static_cast<std::size_t>(count);
                if (count == 2) {
                    order(0, 1);
                    own.emplace_back(key(larger[0], larger[1]), key(0, static_cast<VertexId>(listed_at[i])));
                }
            }
        }
        std::sort(own.begin(), own.end());
        for (std::size_t i = 0; i + 1 < own.size(); ++i)
            if (own[i + 1].first == own[i].first && own[i + 1].second >> 32 == own[i].second >> 32)
                throw FileError(path, 0, "elements " + std::to_string(own[i].second & 0xFFFFFFFFu) + " and " +
                                             std::to_string(own[i + 1].second & 0xFFFFFFFFu) +
                                             " have the same vertices (duplicate element)");
        // Each face counted in a small open-addressed table (sorting the list took most of the
        // check); a face of three or more elements is named as the sorted list names it.
        bool shared_too_often = false;
        for (std::size_t f = 0; f < listed; ++f) {
            std::size_t slot = static_cast<std::size_t>((faces[f] * 0x9E3779B97F4A7C15ull) >> table_shift);
            while (table_stamp[slot] == stamp && table_key[slot] != faces[f]) slot = (slot + 1) & table_mask;
            if (table_stamp[slot] != stamp) {
                table_stamp[slot] = stamp;
                table_key[slot] = faces[f];
                table_count[slot] = 0;
                used[used_count++] = static_cast<std::uint32_t>(slot);
            }
            ++table_count[slot];
        }
        for (std::size_t u = 0; u < used_count; ++u) {
            const std::size_t slot = used[u];
            shared_too_often |= table_count[slot] > 2;
            if (table_count[slot] != 1) continue;
            boundary[v] = 1;
            boundary[table_key[slot] >> 32] = 1;
            if (size == 3) boundary[table_key[slot] & 0xFFFFFFFFu] = 1;
        }
        used_count = 0;
        if (++stamp == 0) {  // the stamps wrapped: start the table afresh
            std::fill(table_stamp.begin(), table_stamp.end(), 0u);
            stamp = 1;
        }
        if (!shared_too_often) continue;
        const auto last = faces.begin() + static_cast<std::ptrdiff_t>(listed);
        std::sort(faces.begin(), last);
        for (auto i = faces.begin(); i != last;) {
            auto j = i + 1;
            while (j != last && *j == *i) ++j;
            const std::array<VertexId, 3> face{vertex, static_cast<VertexId>(*i >> 32), static_cast<VertexId>(*i & 0xFFFFFFFFu)};
            if (j - i == 1)
                for (std::size_t c = 0; c < size; ++c) boundary[static_cast<std::size_t>(face[c])] = 1;
            if (j - i > 2) {
                std::vector<ElementId> sharing;
                for (ElementId e : mesh.elements_of(vertex)) {
                    const auto element = mesh.element(e);
                    if (std::all_of(face.begin(), face.begin() + static_cast<std::ptrdiff_t>(size), [&](VertexId u) {
                            return std::find(element.begin(), element.end(), u) != element.end();
                        }))
                        sharing.push_back(e);
                }
                const bool tets = k == 4;
                refuse_shared_face(path, std::vector<VertexId>(face.begin(), face.begin() + static_cast<std::ptrdiff_t>(size)),
                                   tets, sharing, tets ? "tetrahedra" : "triangles");
            }
            i = j;
        }
    }
    return boundary;
}

// The same for a mesh with cells: every face (an edge in 2D) of every cell, as its sorted
// vertices, sorted together. A face of one cell is on the boundary; one of three or more is
// refused. (A triangle of a tetrahedron and of a pyramid or wedge are the same face.)
std::vector<std::uint8_t> manifold_cell_boundary(const Mesh& mesh, const std::string& path) {
    const std::vector<CellFace> faces = sorted_cell_faces(mesh);
    std::vector<std::uint8_t> boundary(static_cast<std::size_t>(mesh.num_vertices()), 0);
    for (std::size_t i = 0; i < faces.size();) {
        std::size_t j = i + 1;
        while (j < faces.size() && faces[j].vertices == faces[i].vertices) ++j;
        std::vector<VertexId> face;
        for (VertexId v : faces[i].vertices)
            if (v >= 0) face.push_back(v);
        if (j - i == 1)
            for (VertexId v : face) boundary[static_cast<std::size_t>(v)] = 1;
        if (j - i > 2) {
            std::vector<ElementId> sharing;
            for (std::size_t f = i; f < j; ++f) sharing.push_back(faces[f].cell);
            refuse_shared_face(path, face, mesh.kind() == ElementKind::Tetrahedron, sharing, "cells");
        }
        i = j;
    }
    return boundary;
}

// Drops the cells below `dimension` (the boundary triangles and quadrilaterals beside 3D cells).
void keep_dimension(io::RawMesh& raw, int dimension) {
    if (std::all_of(raw.cell_types.begin(), raw.cell_types.end(),
                    [&](CellType type) { return cell_info(type).dimension == dimension; }))
        return;
    std::size_t kept = 0, to = 0, from = 0;
    for (std::size_t c = 0; c < raw.cell_types.size(); ++c) {
        const CellInfo& info = cell_info(raw.cell_types[c]);
        const auto k = static_cast<std::size_t>(info.corners);
        if (info.dimension == dimension) {
            for (std::size_t i = 0; i < k; ++i) raw.cell_connectivity[to + i] = raw.cell_connectivity[from + i];
            raw.cell_types[kept] = raw.cell_types[c];
            raw.cell_positions[kept] = raw.cell_positions[c];
            ++kept;
            to += k;
        }
        from += k;
    }
    raw.cell_types.resize(kept);
    raw.cell_positions.resize(kept);
    raw.cell_connectivity.resize(to);
}

// A cell with a repeated vertex has no corner that can be made valid. Checked here, on the kept
// cells only, to name the cell as the file does.
void check_distinct_vertices(const io::RawMesh& raw, const std::string& path) {
    std::size_t at = 0;
    for (std::size_t c = 0; c < raw.cell_types.size(); ++c) {
        const CellInfo& info = cell_info(raw.cell_types[c]);
        const VertexId* v = raw.cell_connectivity.data() + at;
        for (int i = 0; i < info.corners; ++i)
            for (int j = 0; j < i; ++j)
                if (v[i] == v[j]) {
                    const std::size_t position = raw.cell_positions[c];
                    const std::string name = raw.cell_name ? raw.cell_name(position, info.type)
                                                           : "cell " + std::to_string(position) + " (" +
                                                                 std::string(info.name) + ")";
                    throw FileError(path, 0, name + " repeats vertex " + std::to_string(v[i]) +
                                                 " (points numbered from 0 in file order)");
                }
        at += static_cast<std::size_t>(info.corners);
    }
}

}  // namespace

MeshFormat format_from_extension(const std::filesystem::path& path) {
    const std::string ext = lower(path.extension().string());
    if (ext == ".vtk") return MeshFormat::VtkLegacy;
    if (ext == ".vtu") return MeshFormat::Vtu;
    if (ext == ".msh") return MeshFormat::Gmsh;
    if (ext == ".mesh") return MeshFormat::Medit;
    if (ext == ".node" || ext == ".ele") return MeshFormat::TetGen;
    throw FileError(path.string(), 0,
                    "unknown mesh file extension '" + ext + "' (expected .vtk, .vtu, .msh, .mesh, .node or .ele)");
}

std::string_view to_string(MeshFormat format) {
    switch (format) {
        case MeshFormat::FromExtension: return "from-extension";
        case MeshFormat::VtkLegacy: return "vtk";
        case MeshFormat::Vtu: return "vtu";
        case MeshFormat::Gmsh: return "gmsh";
        case MeshFormat::Medit: return "medit";
        case MeshFormat::TetGen: return "tetgen";
    }
    return "unknown";
}

void WriteOptions::validate(const std::filesystem::path& path) const {
    const MeshFormat f = format == MeshFormat::FromExtension ? format_from_extension(path) : format;
    if (f == MeshFormat::TetGen) throw OptionError("writing TetGen .node/.ele files is not supported; use .vtk, .vtu, .msh or .mesh");
}

const Field* MeshFile::point_field(std::string_view name) const {
    for (const Field& f : point_fields)
        if (f.name == name) return &f;
    return nullptr;
}

const Field* MeshFile::cell_field(std::string_view name) const {
    for (const Field& f : cell_fields)
        if (f.name == name) return &f;
    return nullptr;
}

namespace io {

void RawMesh::add_cell(CellType type, const VertexId* vertices, std::size_t position) {
    cell_types.push_back(type);
    cell_connectivity.insert(cell_connectivity.end(), vertices, vertices + cell_info(type).corners);
    cell_positions.push_back(position);
}

void RawMesh::add_file_cell(CellType type, const VertexId* file_vertices, std::size_t position) {
    const CellInfo& info = cell_info(type);
    cell_types.push_back(type);
    for (int i = 0; i < info.corners; ++i) cell_connectivity.push_back(file_vertices[info.gmsh_order[i]]);
    cell_positions.push_back(position);
}

std::string handled_cells(int CellInfo::*code) {
    std::string out;
    const auto infos = all_cell_infos();
    for (std::size_t i = 0; i < infos.size(); ++i)
        out += (i == 0 ? "" : i + 1 == infos.size() ? " and " : ", ") + std::string(infos[i].name) + " (" +
               std::to_string(infos[i].*code) + ")";
    return out;
}

void to_file_order(CellType type, std::span<const VertexId> cell, VertexId* out) {
    const CellInfo& info = cell_info(type);
    for (int i = 0; i < info.corners; ++i) out[info.gmsh_order[i]] = cell[static_cast<std::size_t>(i)];
}

MeshFile finish_mesh(RawMesh&& raw, const std::string& path, const ReadOptions& options) {
    int dimension = 0;
    for (CellType type : raw.cell_types) dimension = std::max(dimension, cell_info(type).dimension);
    if (dimension == 0)
        throw FileError(path, 0,
                        "the file holds no triangles, quadrilaterals, tetrahedra, hexahedra, wedges or pyramids (empty mesh)");
    keep_dimension(raw, dimension);
    check_distinct_vertices(raw, path);

    MeshFile out;
    try {
        out.mesh = Mesh::from_cells(std::move(raw.coordinates), raw.cell_types, std::move(raw.cell_connectivity));
        // A mesh of simplices is checked with its boundary (manifold_boundary).
        if (out.mesh.has_cells()) check_no_duplicate_elements(out.mesh);
    } catch (const MeshError& e) {
        throw FileError(path, 0, e.what());
    }
    out.orientation = orient(out.mesh, options.orientation);
    std::vector<std::uint8_t> boundary =
        out.mesh.has_cells() ? manifold_cell_boundary(out.mesh, path) : manifold_boundary(out.mesh, path);
    const auto n = static_cast<std::size_t>(out.mesh.num_vertices());
    for (Field& f : raw.point_fields) {
        if (f.components < 1 || f.values.size() != n * static_cast<std::size_t>(f.components))
            throw FileError(path, 0, "point field '" + f.name + "' has " + std::to_string(f.values.size()) +
                                         " values for " + std::to_string(n) + " points");
    }
    for (const Field& f : raw.cell_fields) out.cell_fields.push_back(narrow_cell_field(f, raw.cell_positions, path));
    out.point_fields = std::move(raw.point_fields);

    if (const Field* fixed = out.point_field("fixed"); fixed && fixed->components == 1) {
        std::vector<std::uint8_t> flags(n);
        for (std::size_t v = 0; v < n; ++v) {
            const double value = fixed->values[v];
            if (!std::isfinite(value)) throw FileError(path, 0, "point field 'fixed' is not finite at vertex " + std::to_string(v));
            flags[v] = value != 0.0;
        }
        out.mesh.set_fixed(std::move(flags));
        out.fixed_from_file = true;
    } else if (options.fix_boundary) {
        out.mesh.set_fixed(std::move(boundary));
    }
    for (const char* name : {"GlobalNodeIds", "GLOBAL_ID"}) {
        if (const Field* ids = out.point_field(name); ids && ids->components == 1) {
            std::vector<GlobalId> global(n);
            for (std::size_t v = 0; v < n; ++v) {
                const double id = ids->values[v];
                if (!(id >= 0.0 && id < 9.0e15 && std::floor(id) == id))
                    throw FileError(path, 0, std::string("point field '") + name + "' has an invalid id at vertex " + std::to_string(v));
                global[v] = static_cast<GlobalId>(id);
            }
            out.mesh.set_global_ids(std::move(global));
            break;
        }
    }
    return out;
}

}  // namespace io

MeshFile read_mesh(const std::filesystem::path& path, const ReadOptions& options) {
    const MeshFormat format = options.format == MeshFormat::FromExtension ? format_from_extension(path) : options.format;
    if (!std::filesystem::exists(path)) throw FileError(path.string(), 0, "no such file");
    const std::string name = path.string();
    io::RawMesh raw;
    switch (format) {
        case MeshFormat::VtkLegacy: raw = io::read_vtk_legacy(name); break;
        case MeshFormat::Vtu: raw = io::read_vtu(name); break;
        case MeshFormat::Gmsh: raw = io::read_gmsh(name); break;
        case MeshFormat::Medit: raw = io::read_medit(name); break;
        case MeshFormat::TetGen: raw = io::read_tetgen(name); break;
        case MeshFormat::FromExtension: break;
    }
    return io::finish_mesh(std::move(raw), name, options);
}

void write_mesh(const std::filesystem::path& path,
                const Mesh& mesh,
                const WriteOptions& options,
                std::span<const Field> point_fields,
                std::span<const Field> cell_fields) {
    options.validate(path);
    const MeshFormat format = options.format == MeshFormat::FromExtension ? format_from_extension(path) : options.format;
    if (mesh.num_elements() == 0) throw MeshError("refusing to write " + path.string() + ": the mesh has no elements");
    for (const Field& f : point_fields)
        if (f.components < 1 || f.values.size() != static_cast<std::size_t>(mesh.num_vertices()) * f.components)
            throw Error("point field '" + f.name + "' does not have one tuple per vertex");
    for (const Field& f : cell_fields)
        if (f.components < 1 || f.values.size() != static_cast<std::size_t>(mesh.num_cells()) * f.components)
            throw Error("cell field '" + f.name + "' does not have one tuple per cell");

    std::vector<Field> points(point_fields.begin(), point_fields.end());
    const bool has_fixed = std::any_of(points.begin(), points.end(), [](const Field& f) { return f.name == "fixed"; });
    if (options.write_fixed && !has_fixed) {
        Field fixed{"fixed", 1, std::vector<double>(mesh.fixed().begin(), mesh.fixed().end())};
        points.push_back(std::move(fixed));
    }
    // The file's order: a mesh flipped on reading is mirrored back (a copy of the cells only).
    std::vector<VertexId> file_order;
    std::span<const VertexId> connectivity = mesh.has_cells() ? mesh.cell_connectivity() : mesh.connectivity();
    if (mesh.elements_flipped()) {
        file_order.assign(connectivity.begin(), connectivity.end());
        const io::MeshToWrite cells{mesh, connectivity, {}, {}};
        for (std::size_t c = 0, at = 0; c < cells.cells(); ++c) {
            const CellInfo& info = cell_info(cells.type(c));
            const auto cell = cells.cell(c);
            for (int i = 0; i < info.corners; ++i) file_order[at + static_cast<std::size_t>(i)] = cell[info.mirror[i]];
            at += static_cast<std::size_t>(info.corners);
        }
        connectivity = file_order;
    }
    const io::MeshToWrite data{mesh, connectivity, points, cell_fields};

    AtomicFile file(path, true);
    switch (format) {
        case MeshFormat::VtkLegacy: io::write_vtk_legacy(file.stream(), data, options.encoding); break;
        case MeshFormat::Vtu: io::write_vtu(file.stream(), data, options.encoding); break;
        case MeshFormat::Gmsh: io::write_gmsh(file.stream(), data, options.encoding); break;
        case MeshFormat::Medit: io::write_medit(file.stream(), data); break;
        case MeshFormat::TetGen:
        case MeshFormat::FromExtension: break;
    }
    file.commit();
}

}  // namespace paloverde
