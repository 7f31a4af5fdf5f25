#include "parallel/pieces.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numeric>
#include <string>

#include "io/xml_reader.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/io/atomic_file.hpp"
#include "paloverde/io/mesh_io.hpp"

namespace paloverde::parallel {

// Piece files: the part's mesh with its global ids, owners and which elements it counts.
constexpr const char* kGlobalIds = "GlobalNodeIds";
constexpr const char* kOwner = "OwnerRank";
constexpr const char* kGhostCells = "vtkGhostType";  // 1: counted by another piece (ParaView hides those)
constexpr const char* kPartition = "PartitionId";

void write_piece(const std::filesystem::path& path, const Mesh& mesh, std::span<const int> owner,
                 std::span<const std::uint8_t> counted_cells, int piece, bool mesquite_names) {
    std::vector<Field> points(2), cells(2);
    points[0].name = mesquite_names ? "GLOBAL_ID" : kGlobalIds;
    points[1].name = mesquite_names ? "PROCESSOR_ID" : kOwner;
    for (VertexId v = 0; v < mesh.num_vertices(); ++v) {
        points[0].values.push_back(static_cast<double>(mesh.global_ids()[v]));
        points[1].values.push_back(owner[v]);
    }
    cells[0].name = kPartition;
    cells[1].name = kGhostCells;
    for (ElementId c = 0; c < mesh.num_cells(); ++c) {
        cells[0].values.push_back(piece);
        cells[1].values.push_back(counted_cells[c] ? 0.0 : 1.0);
    }
    write_mesh(path, mesh, {}, points, cells);
}

// Where piece p of `path` lives: OUT.pvtu -> OUT/OUT_p.vtu; OUT.vtk (Mesquite style) -> OUT_p.vtk.
std::filesystem::path piece_path(const std::filesystem::path& path, int piece) {
    const std::string stem = path.stem().string(), number = std::to_string(piece);
    if (path.extension() == ".pvtu") return path.parent_path() / stem / (stem + "_" + number + ".vtu");
    return path.parent_path() / (stem + "_" + number + path.extension().string());
}

void write_pvtu(const std::filesystem::path& path, int pieces) {
    std::string text =
        "<?xml version=\"1.0\"?>\n"
        "<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
        "  <PUnstructuredGrid GhostLevel=\"1\">\n"
        "    <PPointData>\n";
    for (const char* name : {"fixed", kGlobalIds, kOwner})
        text += "      <PDataArray type=\"Float64\" Name=\"" + std::string(name) + "\"/>\n";
    text += "    </PPointData>\n    <PCellData>\n";
    for (const char* name : {kPartition, kGhostCells})
        text += "      <PDataArray type=\"Float64\" Name=\"" + std::string(name) + "\"/>\n";
    text += "    </PCellData>\n    <PPoints>\n      <PDataArray type=\"Float64\" NumberOfComponents=\"3\"/>\n    </PPoints>\n";
    for (int p = 0; p < pieces; ++p)
        text += "    <Piece Source=\"" + piece_path(path.filename(), p).generic_string() + "\"/>\n";
    text += "  </PUnstructuredGrid>\n</VTKFile>\n";
    write_text_file(path, text);
}

// The piece files a .pvtu lists (relative to its folder), or the per-rank files of a pattern.
std::vector<std::filesystem::path> piece_files(const std::filesystem::path& path, int ranks) {
    std::vector<std::filesystem::path> files;
    if (path.extension() != ".pvtu") {
        for (int p = 0; p < ranks; ++p) files.push_back(piece_path(path, p));
        return files;
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) throw FileError(path.string(), 0, "cannot open the .pvtu file");
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const io::XmlDocument doc = io::parse_xml(text, path.string(), "AppendedData");
    for (const io::XmlElement& e : doc.elements)
        if (e.name == "Piece") {
            const std::string* source = e.attribute("Source");
            if (!source) throw FileError(path.string(), e.line, "<Piece> has no Source attribute");
            files.push_back(path.parent_path() / *source);
        }
    return files;
}

// One rank's piece file as part arrays, vertices sorted by global id.
PartArrays read_piece(const std::filesystem::path& file, int ranks, ElementKind& kind) {
    ReadOptions options;
    options.fix_boundary = false;
    options.orientation = OrientationMode::AsIs;  // decided over all pieces together, once assembled
    MeshFile piece = read_mesh(file, options);
    const Field* ids = piece.point_field(kGlobalIds);
    if (!ids) ids = piece.point_field("GLOBAL_ID");
    const Field* owners = piece.point_field(kOwner);
    if (!owners) owners = piece.point_field("PROCESSOR_ID");
    if (!ids || !owners)
        throw FileError(file.string(), 0, "a piece needs the point fields GlobalNodeIds (or GLOBAL_ID) and OwnerRank "
                                          "(or PROCESSOR_ID); write pieces with `paloverde partition`");
    if (!piece.fixed_from_file)
        throw FileError(file.string(), 0, "a piece needs a `fixed` point field: a piece alone cannot tell the "
                                          "boundary of the whole mesh");
    const Mesh& mesh = piece.mesh;
    kind = mesh.kind();
    const VertexId n = mesh.num_vertices();
    for (VertexId v = 0; v < n; ++v) {
        const double id = ids->values[v], owner = owners->values[v];
        if (!(id >= 0.0 && id < 9e15 && id == std::floor(id)))
            throw FileError(file.string(), 0, "vertex " + std::to_string(v) + " has global id " + std::to_string(id) +
                                                  ", not a non-negative integer");
        if (!(owner >= 0.0 && owner < ranks && owner == std::floor(owner)))
            throw FileError(file.string(), 0, "vertex " + std::to_string(v) + " has owner " + std::to_string(owner) +
                                                  ", not a rank in [0, " + std::to_string(ranks) + ")");
    }
    std::vector<VertexId> order(static_cast<std::size_t>(n));
    std::iota(order.begin(), order.end(), VertexId{0});
    std::sort(order.begin(), order.end(), [&](VertexId a, VertexId b) { return ids->values[a] < ids->values[b]; });
    std::vector<VertexId> local(static_cast<std::size_t>(n));
    PartArrays out;
    for (VertexId i = 0; i < n; ++i) {
        const VertexId v = order[i];
        local[v] = i;
        if (i > 0 && ids->values[v] == ids->values[order[i - 1]])
            throw FileError(file.string(), 0, "global id " + std::to_string(static_cast<GlobalId>(ids->values[v])) +
                                                  " appears twice in the piece");
        for (int c = 0; c < 3; ++c) out.coordinates.push_back(mesh.coordinates()[3 * static_cast<std::size_t>(v) + c]);
        out.fixed.push_back(mesh.fixed()[v]);
        out.canonical.push_back(static_cast<std::int64_t>(ids->values[v]));
        out.owner.push_back(static_cast<std::int32_t>(owners->values[v]));
    }
    // A mesh with cells: its cells, whose corners the part's mesh takes anew.
    for (VertexId v : mesh.has_cells() ? mesh.cell_connectivity() : mesh.connectivity())
        (mesh.has_cells() ? out.cell_connectivity : out.connectivity).push_back(local[v]);
    for (CellType type : mesh.cell_types()) out.cell_types.push_back(static_cast<std::uint8_t>(type));
    return out;
}

}  // namespace paloverde::parallel
