#pragma once
// The part of a mesh that one process works on: its mesh, which of its vertices it moves and
// which of its elements it counts in global sums, the reductions over all processes and the ghost
// updates. A serial run's part is the whole mesh: every vertex owned, every element counted,
// reductions and ghost updates that do nothing. Solvers, queues and assessments take a part, so
// a serial run is the one-part case of a distributed one.
//
// It is the whole interface a solver or an assessment sees of the split: element order, gathers
// to rank 0, the whole mesh's boundary and plane, reductions and ghost updates. What a part holds
// beyond its mesh stays in the DistributedMesh.
//
// A view, cheap to copy: it refers to the mesh (and the DistributedMesh) it was made from, which
// must outlive it. Made implicitly from either, so `solver.improve(mesh)` reads as it should.
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "paloverde/mesh/boundary_surface.hpp"
#include "paloverde/mesh/mesh.hpp"
#include "paloverde/metrics/targets.hpp"
#include "paloverde/parallel/halo.hpp"
#include "paloverde/parallel/reducer.hpp"

namespace paloverde {

class DistributedMesh;  // distributed_mesh.hpp, which brings in MPI

class MeshPart {
public:
    MeshPart(Mesh& whole);     // the whole mesh, serially
    MeshPart(DistributedMesh& part);  // this rank's part; what the part does with it is collective (MPI builds)

    Mesh& mesh() const { return *mesh_; }
    const Reducer& reducer() const { return *reducer_; }
    const Halo& halo() const { return *halo_; }
    // This process owns vertex v: computes its gradient and moves it (if it can move); other
    // processes hold it as a ghost.
    bool owns(VertexId v) const;
    // This process counts element e in sums over the whole mesh (each element has one counter).
    bool counts(ElementId e) const;

    // The whole mesh of a serial run, numbered as it was given. A part of a distributed mesh (a
    // one-rank run's too) is numbered canonically instead: its vertices in global id order
    // (Mesh::global_ids), its elements with canonical positions.
    bool whole() const { return distributed_ == nullptr; }
    int rank() const;   // 0 for the whole mesh
    int ranks() const;  // 1 for the whole mesh
    bool root() const { return rank() == 0; }
    // The whole mesh's counts.
    GlobalId global_vertices() const;
    GlobalId global_elements() const;
    // Per element: its canonical position; empty for the whole mesh.
    std::span<const GlobalId> element_positions() const;
    // Per element: counted here (counts()); empty for the whole mesh, whose elements all count.
    std::span<const std::uint8_t> counted() const;
    // Element e becomes the element now at order[e]; positions and counted flags go with them.
    // All or nothing: should memory run out, the part stays as it was.
    void reorder_elements(std::span<const ElementId> order) const;
    // Triangles: the whole mesh's plane (a part may lie in another).
    Vec3 plane_normal() const;

    // Collective: the whole mesh's boundary, as a surface over the part's vertices (a part's own
    // boundary also has the faces where it was cut from the others'). `surface_mesh`: the whole
    // mesh is a surface mesh, and the surface is all of it (the whole mesh tells for itself).
    BoundarySurface boundary_surface(bool surface_mesh, const SurfaceOptions& options = {}) const;
    // The surface's normal at each vertex of `mesh`, which is numbered as the part is.
    std::vector<Vec3> normals_of(const BoundarySurface& surface, const Mesh& mesh) const;

    // Collective: rank 0 gets `width` values per vertex of the whole mesh, in global id order,
    // each from the vertex's owner; the other ranks get nothing. The whole mesh's is a copy.
    std::vector<double> gather_to_root(std::span<const double> field, int width) const;
    // Collective: every rank gets rank 0's bytes.
    void broadcast(std::string& bytes) const;
    // Collective: runs `work` on rank 0 alone; a failure there is thrown on every rank.
    void on_root(const std::function<void()>& work) const;

private:
    Mesh* mesh_;
    const Reducer* reducer_;
    const Halo* halo_;
    DistributedMesh* distributed_ = nullptr;
};

// Sets the targets of the part's elements (metrics/targets.hpp), the ideal size being the whole
// mesh's: the same targets, bit for bit, however the mesh is split. Collective. `reference` has the
// part's own connectivity; without it, factors from the reference come from the part's mesh at its
// reference coordinates (Mesh::reference_coordinates, which a DistributedMesh's parts get from the
// whole mesh's).
void set_targets(MeshPart part, const TargetOptions& options, const Mesh* reference = nullptr);

}  // namespace paloverde
