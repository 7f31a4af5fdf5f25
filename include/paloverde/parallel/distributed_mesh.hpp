#pragma once
// A mesh distributed over the ranks of an MPI communicator.
//
// Every vertex has one owner rank (METIS k-way partition of the vertex graph). A rank holds every
// element that touches a vertex it owns, and the other vertices of those elements as ghosts:
// copies refreshed from their owners through the exchange schedule. Each element is counted in
// global sums by exactly one rank, the owner of its vertex with the smallest canonical id.
// A mesh with cells (quadrilaterals, hexahedra, wedges, pyramids) is split into whole cells: a
// rank holds every cell that touches a vertex it owns, the cell is counted by the owner of its
// vertex with the smallest canonical id, and so are all its corners (the part's elements).
//
// Canonical ids: the vertices of the whole mesh in reverse Cuthill-McKee order (for locality).
// A rank's vertices are in increasing canonical id, which `mesh.global_ids()` holds.
#include <mpi.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "paloverde/mesh/boundary_surface.hpp"
#include "paloverde/mesh/mesh.hpp"
#include "paloverde/mesh/orientation.hpp"
#include "paloverde/parallel/halo.hpp"
#include "paloverde/parallel/reducer.hpp"

namespace paloverde {

// How ghost values travel. Colored: the process graph's edges are colored so that no two edges
// at a rank share a color, and the exchange runs color by color, each rank trading with at most
// one partner per color (the paper's schedule). RootRelayed: every rank sends to rank 0, which
// forwards (the paper's baseline).
enum class ExchangeMode { Colored, RootRelayed };

struct ExchangePartner {
    int rank = 0;
    int color = 0;                 // of the process-graph edge to this partner
    std::vector<VertexId> send;    // owned vertices the partner holds as ghosts
    std::vector<VertexId> receive; // ghosts the partner owns
};

struct ExchangeSchedule {
    ExchangeMode mode = ExchangeMode::Colored;
    std::vector<ExchangePartner> partners;  // ordered by color
    int colors = 0;                         // colors used over the whole process graph
};

struct DistributeOptions {
    ExchangeMode exchange = ExchangeMode::Colored;
    // read_pieces: the pieces' orientation convention, decided over all of them together (one
    // total signed volume, summed across ranks), so that every rank flips alike.
    OrientationMode orientation = OrientationMode::Auto;
    void validate() const {}
};

// Timings of getting the mesh onto the ranks (seconds, on rank 0), as in the paper's Table 1.
struct DistributeTimings {
    double partition = 0.0;   // canonical order and METIS
    double distribute = 0.0;  // sending each rank its part, building it there
    double schedule = 0.0;    // process graph, edge coloring, send/receive lists
};

class DistributedMesh {
public:
    // Collective over `comm`. Rank 0 passes the whole mesh (fixed flags set), the other ranks
    // nullptr. Throws (on every rank) when the mesh has fewer vertices than there are ranks.
    static DistributedMesh scatter(MPI_Comm comm, const Mesh* whole, const DistributeOptions& options = {});

    // Collective: reads pre-partitioned pieces, one per rank: a .pvtu and the .vtu files it lists,
    // or Mesquite-style per-rank files OUT_<rank>.vtk for a path OUT.vtk. Each piece holds the
    // elements (whole cells) around the vertices it owns, with the point fields GlobalNodeIds (or
    // GLOBAL_ID), OwnerRank (or PROCESSOR_ID) and `fixed`. Pieces that disagree (an id owned twice
    // or by no piece, a ghost placed elsewhere than by its owner, missing elements, the wrong
    // number of pieces) are an error on every rank.
    static DistributedMesh read_pieces(MPI_Comm comm, const std::filesystem::path& path,
                                       const DistributeOptions& options = {});
    // Collective: writes this distributed mesh as pieces (see read_pieces); rank 0 writes the
    // .pvtu. Each piece has a PartitionId cell field, and vtkGhostType marks the elements (cells)
    // another piece counts, so ParaView shows each element once, colored by rank.
    void write_pieces(const std::filesystem::path& path) const;
    // Serial: cuts `whole` into `parts` pieces as scatter() would, and writes them.
    static void write_partitioned(const Mesh& whole, int parts, const std::filesystem::path& path);

    // Collective: rank 0 passes the mesh it gave to scatter(), whose coordinates become the
    // owners' current ones; the other ranks pass nullptr.
    void gather_coordinates(Mesh* whole) const;
    // Collective: rank 0 gets the whole mesh built from the parts (for runs from pieces, where no
    // rank has it), the other ranks an empty mesh. Vertices come in global id order, elements (or
    // cells) in their canonical order, with the current coordinates and the fixed flags. Rank 0
    // holds the whole mesh and, while it builds it, the gathered values of either the vertices (40
    // bytes each) or the elements (8 bytes per corner, plus 8; a cell's plus 16).
    Mesh gather_whole() const;

    // Collective: the whole mesh's boundary at the current coordinates, in global ids, on every
    // rank (a part's own boundary also has the faces where it was cut from the others'). Refused
    // (MeshError on every rank) for a volume mesh with cells, as BoundaryFacets::of refuses it.
    // With `surface` (the whole mesh is a surface mesh), the whole surface: every triangle (cells
    // cut into triangles, with their cuts).
    BoundaryFacets gather_boundary(bool surface = false) const;

    // Collective: refreshes ghost coordinates from their owners.
    void update_ghost_coordinates();

    // Element e becomes the element now at order[e]; element_order and counted go with them. All
    // or nothing.
    void reorder_elements(std::span<const ElementId> order);
    // Collective: rank 0 gets `width` values per vertex of the whole mesh, in global id order,
    // each from the vertex's owner; the other ranks get nothing.
    std::vector<double> gather_vertex_field(std::span<const double> field, int width) const;
    // Collective: every rank gets rank 0's bytes.
    void broadcast(std::string& bytes) const;
    // Collective: runs `work` on rank 0 alone; a failure there is thrown on every rank.
    void on_root(const std::function<void()>& work) const;

    const Reducer& reducer() const { return *reducer_; }
    const Halo& halo() const { return *halo_; }

    MPI_Comm comm() const { return comm_; }
    int rank() const { return rank_; }
    int ranks() const { return ranks_; }
    // This rank's elements and the vertices they touch.
    Mesh& mesh() { return mesh_; }
    const Mesh& mesh() const { return mesh_; }
    // Per local vertex: its owner.
    std::span<const int> vertex_owner() const { return vertex_owner_; }
    // Per local element: its canonical position, and whether this rank counts it in sums.
    std::span<const GlobalId> element_order() const { return element_order_; }
    std::span<const std::uint8_t> counted() const { return counted_; }
    // A mesh with cells, per local cell: its canonical position (the cells sorted by their sorted
    // global ids, then type); empty without cells.
    std::span<const GlobalId> cell_order() const { return cell_order_; }
    // The whole mesh's; global_cells is global_elements for a mesh without cells.
    GlobalId global_vertices() const { return global_vertices_; }
    GlobalId global_elements() const { return global_elements_; }
    GlobalId global_cells() const { return global_cells_; }
    // Triangle meshes: the whole mesh's plane.
    const Vec3& plane_normal() const { return plane_normal_; }
    // read_pieces: whether the elements were flipped, and why (the same on every rank). scatter()
    // takes the whole mesh's orientation as it is; the parts keep its elements_flipped() mark.
    const OrientationDecision& orientation() const { return orientation_; }
    // Partners and send/receive lists. (Held on the heap: the halo refers to it, and a moved
    // DistributedMesh must keep working.)
    const ExchangeSchedule& schedule() const { return *schedule_; }
    const DistributeTimings& timings() const { return timings_; }

    // Communication counts (this rank): ghost values it receives per exchange, messages per exchange.
    std::int64_t received_vertices() const;
    std::int64_t sent_vertices() const;

    DistributedMesh();
    ~DistributedMesh();
    DistributedMesh(DistributedMesh&&) noexcept;
    DistributedMesh& operator=(DistributedMesh&&) noexcept;

private:
    MPI_Comm comm_ = MPI_COMM_NULL;
    int rank_ = 0, ranks_ = 1;
    Mesh mesh_;
    std::vector<int> vertex_owner_;
    std::vector<GlobalId> element_order_;
    std::vector<std::uint8_t> counted_;
    std::vector<GlobalId> cell_order_;
    GlobalId global_vertices_ = 0, global_elements_ = 0, global_cells_ = 0;
    Vec3 plane_normal_{0.0, 0.0, 1.0};
    OrientationDecision orientation_;
    DistributeTimings timings_;
    // Builds the part from its arrays (an internal type), then the schedule and the reductions.
    void assemble(void* arrays, ElementKind kind, ExchangeMode mode);
    void build_schedule(ExchangeMode mode);
    void owned_vertices(std::vector<std::int64_t>& ids, std::vector<double>& xyz) const;
    std::unique_ptr<ExchangeSchedule> schedule_;
    std::unique_ptr<Reducer> reducer_;
    std::unique_ptr<Halo> halo_;
    // Rank 0 only: for each canonical vertex id, its index in the mesh given to scatter().
    std::vector<VertexId> original_vertex_;
};

}  // namespace paloverde
