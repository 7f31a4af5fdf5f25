#pragma once
// One rank's part as plain arrays: what rank 0 sends each rank when it splits a mesh, and what a
// piece file holds; DistributedMesh::assemble() moves them into the part's mesh.
#include <cstdint>
#include <string>
#include <vector>

#include "paloverde/core/error.hpp"
#include "paloverde/mesh/simplex_mesh.hpp"

namespace paloverde::parallel {

// The pieces of one rank's part, as rank 0 sends them or a piece file holds them.
struct PartArrays {
    std::vector<double> coordinates;
    std::vector<std::uint8_t> fixed;
    std::vector<std::int64_t> canonical;  // per vertex
    std::vector<std::int32_t> owner;      // per vertex
    std::vector<std::int32_t> connectivity;
    std::vector<std::int64_t> element_order;
};

// Parts hold simplices only so far: a mesh with quadrilaterals, hexahedra, wedges or pyramids
// runs on one process (issue 18).
inline void require_simplices(const SimplexMesh& mesh, const std::string& what) {
    for (CellType type : mesh.cell_types())
        if (!is_simplex(type))
            throw OptionError(what + ": a mesh with " + std::string(cell_info(type).name) +
                              " cells runs on one process for now; distributed runs take triangles and tetrahedra");
}

}  // namespace paloverde::parallel
