// Distributed meshes of cells (quadrilaterals, hexahedra, wedges, pyramids, mixes): a part holds
// whole cells, each cell and its corners counted once; the global solver ends on the serial mesh
// bit for bit, the local smoother on the one-rank mesh; reports and gathers are the serial ones;
// pieces hold whole cells. Run by CTest on 1, 2 and 4 ranks with distributed_test.cpp.
#include <mpi.h>

#include <boost/test/data/test_case.hpp>
#include <boost/test/unit_test.hpp>
#include <algorithm>
#include <array>
#include <string>
#include <vector>

#include "paloverde/assess/quality_assessor.hpp"
#include "paloverde/core/error.hpp"
#include "paloverde/io/mesh_io.hpp"
#include "paloverde/mesh/orientation.hpp"
#include "paloverde/mesh/renumber.hpp"
#include "paloverde/parallel/distributed_mesh.hpp"
#include "paloverde/solvers/global_solver.hpp"
#include "paloverde/solvers/local_solver.hpp"
#include "distributed_checks.hpp"
#include "support/cell_meshes.hpp"

namespace pv = paloverde;
namespace bdata = boost::unit_test::data;
using pv::test::Fill;
using pv::test::rank;
using pv::test::ranks;
using pv::test::relative_difference;
using pv::test::scatter;

namespace {

const std::vector<int> kGrids{0, 1, 2, 3, 4, 5, 6};
const char* const kGridNames[] = {"quadrilaterals", "hexahedra", "wedges", "pyramids", "mixed",
                                  "tetrahedra and a hexahedron", "Mesquite's hexahedra, pyramids and tetrahedra"};

// Kuhn's tetrahedra in every cube but the corner one, a hexahedron: on 4 ranks some parts hold
// tetrahedra only, and must still hold them as cells to be rated as the whole mesh is. (The
// hexahedron's faces do not conform to the tetrahedra's: their vertices are fixed as boundary.)
pv::Mesh tetrahedra_and_a_hexahedron(int n) {
    const auto tets = pv::test::cube_grid(n, Fill::Tetrahedra), hexes = pv::test::cube_grid(n, Fill::Hexahedra);
    std::vector<pv::CellType> types{pv::CellType::Hexahedron};
    std::vector<pv::VertexId> cells(hexes.cell(0).begin(), hexes.cell(0).end());
    for (pv::ElementId e = 6; e < tets.num_elements(); ++e) {  // the corner cube's six are the first
        types.push_back(pv::CellType::Tetrahedron);
        cells.insert(cells.end(), tets.element(e).begin(), tets.element(e).end());
    }
    auto mesh = pv::Mesh::from_cells({tets.coordinates().begin(), tets.coordinates().end()}, types, std::move(cells));
    mesh.fix_boundary();
    return mesh;
}

pv::Mesh grid(int g) {
    if (g == 0) return pv::test::quad_grid(16);
    if (g < 5) return pv::test::cube_grid(6, static_cast<Fill>(g - 1));
    if (g == 5) return tetrahedra_and_a_hexahedron(6);
    return pv::test::shared_mesh("mesquite/mixed/mixed-hex-pyr-tet.vtk");
}

pv::Mesh tangled_grid(int g, int seed) {
    auto mesh = pv::test::tangled(grid(g), seed);
    BOOST_TEST_REQUIRE(pv::count_orientations(mesh).inverted > 0);
    return mesh;
}

void check_same_statistics(const pv::QualityStatistics& a, const pv::QualityStatistics& b) {
    BOOST_TEST(a.count == b.count);
    BOOST_TEST(a.min == b.min);
    BOOST_TEST(a.max == b.max);
    BOOST_TEST(a.mean == b.mean);
    BOOST_TEST(a.rms == b.rms);
    BOOST_TEST(a.histogram == b.histogram, boost::test_tools::per_element());
}

// Everything but the worst element's index (a local index means nothing in a distributed run).
void check_same_report(const pv::QualityReport& a, const pv::QualityReport& b) {
    BOOST_TEST(a.vertices == b.vertices);
    BOOST_TEST(a.free_vertices == b.free_vertices);
    BOOST_TEST(a.elements == b.elements);
    BOOST_TEST(a.frozen_elements == b.frozen_elements);
    BOOST_TEST(a.inverted == b.inverted);
    BOOST_TEST(a.inverted_frozen == b.inverted_frozen);
    BOOST_TEST(a.degenerate == b.degenerate);
    BOOST_REQUIRE(a.metrics.size() == b.metrics.size());
    for (std::size_t i = 0; i < a.metrics.size(); ++i) {
        BOOST_TEST_CONTEXT(a.metrics[i].name) {
            BOOST_TEST(a.metrics[i].name == b.metrics[i].name);
            check_same_statistics(a.metrics[i].all, b.metrics[i].all);
            check_same_statistics(a.metrics[i].movable, b.metrics[i].movable);
            check_same_statistics(a.metrics[i].frozen, b.metrics[i].frozen);
        }
    }
    BOOST_REQUIRE(a.by_type.size() == b.by_type.size());
    for (std::size_t i = 0; i < a.by_type.size(); ++i) {
        BOOST_TEST(a.by_type[i].type == b.by_type[i].type);
        BOOST_TEST(a.by_type[i].count == b.by_type[i].count);
        BOOST_TEST(a.by_type[i].inverted == b.by_type[i].inverted);
        BOOST_TEST((a.by_type[i].worst == b.by_type[i].worst));
    }
}

}  // namespace

BOOST_AUTO_TEST_SUITE(distributed_cells)

BOOST_DATA_TEST_CASE(a_part_holds_whole_cells_and_counts_each_once, bdata::make(kGrids), g) {
    BOOST_TEST_CONTEXT(kGridNames[g]) {
        const auto whole = grid(g);
        auto part = scatter(whole);
        const pv::Reducer& reducer = part.reducer();
        BOOST_TEST(part.global_cells() == whole.num_cells());
        BOOST_TEST(part.global_elements() == whole.num_elements());
        // Every part holds cells, even one of tetrahedra only.
        BOOST_TEST(reducer.min(part.mesh().has_cells() ? 1.0 : 0.0) == 1.0);
        // A cell's corners are counted together, every cell once.
        std::vector<int> cell_counted(static_cast<std::size_t>(part.mesh().num_cells()), -1);
        long corners = 0, cells = 0, split = 0;
        for (pv::ElementId e = 0; e < part.mesh().num_elements(); ++e) {
            int& c = cell_counted[static_cast<std::size_t>(part.mesh().cell_of(e))];
            corners += part.counted()[e];
            if (c < 0) c = part.counted()[e], cells += c;
            else split += c != part.counted()[e];
        }
        BOOST_TEST(reducer.total(static_cast<double>(corners)) == whole.num_elements());
        BOOST_TEST(reducer.total(static_cast<double>(cells)) == whole.num_cells());
        BOOST_TEST(reducer.total(static_cast<double>(split)) == 0.0);
        // The counted cells' canonical positions: each position once.
        std::vector<int> seen(static_cast<std::size_t>(whole.num_cells()), 0);
        for (pv::ElementId c = 0; c < part.mesh().num_cells(); ++c) seen[static_cast<std::size_t>(part.cell_order()[c])] += cell_counted[c];
        MPI_Allreduce(MPI_IN_PLACE, seen.data(), static_cast<int>(seen.size()), MPI_INT, MPI_SUM, MPI_COMM_WORLD);
        BOOST_TEST(std::all_of(seen.begin(), seen.end(), [](int n) { return n == 1; }));
        // The owner of a vertex holds every corner around it.
        const auto order = pv::locality_order(whole);
        long missing = 0;
        for (pv::VertexId v = 0; v < part.mesh().num_vertices(); ++v)
            if (part.vertex_owner()[v] == rank()) {
                const auto original = order.old_vertex[static_cast<std::size_t>(part.mesh().global_ids()[v])];
                missing += part.mesh().elements_of(v).size() != whole.elements_of(original).size();
            }
        BOOST_TEST(reducer.total(static_cast<double>(missing)) == 0.0);
    }
}

// The global solver on tangled grids of cells: the serial steps to the serial mesh, bit for bit.
BOOST_DATA_TEST_CASE(the_global_solver_gives_the_serial_mesh, bdata::make(kGrids), g) {
    BOOST_TEST_CONTEXT(kGridNames[g]) {
        pv::GlobalSolverOptions options;
        options.termination.max_iterations = 20;
        options.untangle_termination.max_iterations = 150;
        const auto input = tangled_grid(g, 1);
        const auto [serial, distributed] = pv::test::serial_and_distributed(input, options);
        BOOST_TEST(serial.before.elements == input.num_cells());
        BOOST_TEST(serial.before.inverted > 0);
        check_same_report(distributed.after, serial.after);
    }
}

// The local smoother colors by global ids: the same moves, so the same mesh, on any number of ranks.
BOOST_DATA_TEST_CASE(the_local_smoother_gives_the_one_rank_mesh, bdata::make(kGrids), g) {
    BOOST_TEST_CONTEXT(kGridNames[g]) {
        const auto input = tangled_grid(g, 2);
        pv::LocalSolverOptions options;
        options.termination.max_iterations = 8;
        auto part = scatter(input);
        const auto summary = pv::LocalSolver(options).improve(part);
        BOOST_TEST_MESSAGE(kGridNames[g] << ", " << ranks() << " ranks: " << summary.brief_report());
        BOOST_TEST(summary.before.inverted > 0);
        pv::test::check_never_worse(summary);
        auto alone = pv::DistributedMesh::scatter(MPI_COMM_SELF, &input);
        const auto alone_summary = pv::LocalSolver(options).improve(alone);
        BOOST_TEST(summary.iterations == alone_summary.iterations);
        BOOST_TEST(summary.worst_after == alone_summary.worst_after);
        check_same_report(summary.after, alone_summary.after);
        pv::Mesh from_one = input, from_all = input;
        alone.gather_coordinates(&from_one);
        part.gather_coordinates(rank() == 0 ? &from_all : nullptr);
        if (rank() == 0) BOOST_TEST(relative_difference(from_all, from_one) == 0.0);
    }
}

// Reports count cells (a cell is its worst corner, inverted if any corner is), each once.
BOOST_DATA_TEST_CASE(the_report_is_the_serial_one, bdata::make(kGrids), g) {
    BOOST_TEST_CONTEXT(kGridNames[g]) {
        const auto whole = tangled_grid(g, 1);
        auto part = scatter(whole);
        const pv::QualityAssessor assessor;
        const auto serial = assessor.assess(whole);
        BOOST_TEST(serial.elements == whole.num_cells());
        BOOST_TEST(!serial.by_type.empty());
        check_same_report(assessor.assess(part), serial);
    }
}

// gather_whole() builds on rank 0 the whole mesh with its cells: each once, in their canonical
// order, with their owners' coordinates.
BOOST_DATA_TEST_CASE(gather_whole_gives_back_the_cells, bdata::make(kGrids), g) {
    BOOST_TEST_CONTEXT(kGridNames[g]) {
        const auto input = grid(g);
        const pv::Mesh whole = pv::test::gathered_whole(input);
        if (rank() != 0) return;
        BOOST_REQUIRE(whole.has_cells());
        BOOST_REQUIRE(whole.num_cells() == input.num_cells());
        BOOST_TEST(whole.num_elements() == input.num_elements());
        const auto order = pv::locality_order(input);
        // The same cells, vertex for vertex in their own order, and sorted by their keys.
        using Cell = std::vector<pv::VertexId>;
        std::vector<Cell> a, b;
        std::vector<std::vector<std::int64_t>> keys;
        for (pv::ElementId c = 0; c < whole.num_cells(); ++c) {
            Cell cell{static_cast<pv::VertexId>(whole.cell_type(c))};
            for (pv::VertexId v : whole.cell(c)) cell.push_back(order.old_vertex[static_cast<std::size_t>(v)]);
            a.push_back(cell);
            std::vector<std::int64_t> key(whole.cell(c).begin(), whole.cell(c).end());
            std::sort(key.begin(), key.end());
            key.resize(pv::kMaxCellCorners, -1);
            key.push_back(static_cast<std::int64_t>(whole.cell_type(c)));
            keys.push_back(key);
        }
        for (pv::ElementId c = 0; c < input.num_cells(); ++c) {
            Cell cell{static_cast<pv::VertexId>(input.cell_type(c))};
            cell.insert(cell.end(), input.cell(c).begin(), input.cell(c).end());
            b.push_back(cell);
        }
        std::sort(a.begin(), a.end()), std::sort(b.begin(), b.end());
        BOOST_TEST((a == b));
        BOOST_TEST(std::is_sorted(keys.begin(), keys.end()));
    }
}

// The sliding boundary takes triangles and tetrahedra only: refused on every rank.
BOOST_AUTO_TEST_CASE(the_boundary_of_cells_is_refused_on_every_rank) {
    auto part = scatter(grid(1));
    BOOST_CHECK_THROW(part.gather_boundary(), pv::MeshError);
}

BOOST_AUTO_TEST_SUITE_END()

BOOST_AUTO_TEST_SUITE(pieces_of_cells)

// Written by write_partitioned, read one per rank: the serial report and the serial solve; the
// ghost flag of a piece is per cell; written back and read again, the same part.
BOOST_DATA_TEST_CASE(pieces_of_cells_give_the_serial_answer, bdata::make(kGrids), g) {
    BOOST_TEST_CONTEXT(kGridNames[g]) {
        const auto input = tangled_grid(g, 1);
        const pv::QualityAssessor assessor;
        pv::GlobalSolverOptions options;
        options.termination.max_iterations = 10;
        options.untangle_termination.max_iterations = 150;
        pv::Mesh serial = input;
        const auto serial_summary = pv::GlobalSolver(options).improve(serial);
        const auto order = pv::locality_order(input);
        for (const std::string name : {"cells.pvtu", "cells.vtk"}) {
            const auto path = pv::test::scratch(std::to_string(g) + name);
            if (rank() == 0) pv::DistributedMesh::write_partitioned(input, ranks(), path);
            MPI_Barrier(MPI_COMM_WORLD);
            auto part = pv::DistributedMesh::read_pieces(MPI_COMM_WORLD, path);
            BOOST_TEST(part.global_cells() == input.num_cells());
            BOOST_TEST(part.global_elements() == input.num_elements());
            BOOST_TEST(part.mesh().has_cells());
            check_same_report(assessor.assess(part), assessor.assess(input));
            const auto summary = pv::GlobalSolver(options).improve(part);
            BOOST_TEST(summary.iterations == serial_summary.iterations);
            BOOST_TEST(summary.worst_after == serial_summary.worst_after);
            // The whole mesh comes back in the canonical numbering: the serial mesh's vertices there.
            const auto whole = part.gather_whole();
            if (rank() == 0) {
                BOOST_REQUIRE(whole.num_vertices() == serial.num_vertices());
                BOOST_TEST(whole.num_cells() == serial.num_cells());
                long different = 0;
                for (pv::VertexId v = 0; v < whole.num_vertices(); ++v)
                    for (int c = 0; c < 3; ++c)
                        different += whole.coordinates()[3 * static_cast<std::size_t>(v) + c] !=
                                     serial.coordinates()[3 * static_cast<std::size_t>(order.old_vertex[v]) + c];
                BOOST_TEST(different == 0);
            }
            // This rank's piece flags the cells another piece counts, cell by cell.
            const std::string stem = path.stem().string() + "_" + std::to_string(rank());
            const auto piece = pv::read_mesh(path.extension() == ".pvtu" ? path.parent_path() / path.stem() / (stem + ".vtu")
                                                                         : path.parent_path() / (stem + ".vtk"));
            const pv::Field* ghost = piece.cell_field("vtkGhostType");
            BOOST_REQUIRE(ghost);
            BOOST_REQUIRE(ghost->values.size() == static_cast<std::size_t>(part.mesh().num_cells()));
            long flags_wrong = 0;
            for (pv::ElementId e = 0; e < part.mesh().num_elements(); ++e)
                flags_wrong += (ghost->values[static_cast<std::size_t>(part.mesh().cell_of(e))] == 0.0) != (part.counted()[e] != 0);
            BOOST_TEST(flags_wrong == 0);
            const auto again_path = pv::test::scratch(std::to_string(g) + "again_" + name);
            part.write_pieces(again_path);
            auto again = pv::DistributedMesh::read_pieces(MPI_COMM_WORLD, again_path);
            BOOST_TEST(again.mesh().num_cells() == part.mesh().num_cells());
            BOOST_TEST(std::equal(again.mesh().coordinates().begin(), again.mesh().coordinates().end(),
                                  part.mesh().coordinates().begin(), part.mesh().coordinates().end()));
            BOOST_TEST(std::ranges::equal(again.counted(), part.counted()));
        }
    }
}

BOOST_AUTO_TEST_SUITE_END()
