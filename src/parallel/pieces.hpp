#pragma once
// Piece files (docs/parallel.md): one .vtu per rank, listed by a .pvtu, or Mesquite's per-rank
// .vtk files; each holds its part's mesh with the global ids, owners and which elements it counts.
#include <filesystem>
#include <span>

#include "paloverde/mesh/mesh.hpp"
#include "parallel/parts.hpp"

namespace paloverde::parallel {

// Writes one piece: the part's mesh with its global ids, owners, piece number and ghost cells
// (the cells, or elements, counted by another piece: `counted_cells` per cell); Mesquite's field
// names for its .vtk pattern.
void write_piece(const std::filesystem::path& path, const Mesh& mesh, std::span<const int> owner,
                 std::span<const std::uint8_t> counted_cells, int piece, bool mesquite_names);
// Where piece p of `path` lives: OUT.pvtu -> OUT/OUT_p.vtu; OUT.vtk (Mesquite style) -> OUT_p.vtk.
std::filesystem::path piece_path(const std::filesystem::path& path, int piece);
// The .pvtu that lists `pieces` pieces.
void write_pvtu(const std::filesystem::path& path, int pieces);
// The piece files a .pvtu lists (relative to its folder), or the per-rank files of a pattern.
std::vector<std::filesystem::path> piece_files(const std::filesystem::path& path, int ranks);
// One rank's piece file as part arrays, vertices sorted by global id; `kind` is set.
PartArrays read_piece(const std::filesystem::path& file, int ranks, ElementKind& kind);

}  // namespace paloverde::parallel
