#pragma once
// The part of a mesh that one process works on: its mesh, which of its vertices it moves and
// which of its elements it counts in global sums, the reductions over all processes and the ghost
// updates. A serial run's part is the whole mesh: every vertex owned, every element counted,
// reductions and ghost updates that do nothing. Solvers, queues and assessments take a part, so
// a serial run is the one-part case of a distributed one.
//
// A view, cheap to copy: it refers to the mesh (and the DistributedMesh) it was made from, which
// must outlive it. Made implicitly from either, so `solver.improve(mesh)` reads as it should.
#include "paloverde/mesh/mesh.hpp"
#include "paloverde/metrics/targets.hpp"
#include "paloverde/parallel/halo.hpp"
#include "paloverde/parallel/reducer.hpp"

namespace paloverde {

class DistributedMesh;  // distributed_mesh.hpp, which brings in MPI

class MeshPart {
public:
    MeshPart(Mesh& whole);     // the whole mesh, serially
    MeshPart(DistributedMesh& part);  // this rank's part; what the part does with it is collective

    Mesh& mesh() const { return *mesh_; }
    const Reducer& reducer() const { return *reducer_; }
    const Halo& halo() const { return *halo_; }
    // This process owns vertex v: computes its gradient and moves it (if it can move); other
    // processes hold it as a ghost.
    bool owns(VertexId v) const;
    // This process counts element e in sums over the whole mesh (each element has one counter).
    bool counts(ElementId e) const;
    // The DistributedMesh the part belongs to; nullptr for the whole mesh of a serial run.
    DistributedMesh* distributed() const { return distributed_; }

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
