#include "paloverde/parallel/mesh_part.hpp"

#include "paloverde/parallel/distributed_mesh.hpp"

namespace paloverde {

namespace {
// A serial run's reductions and ghost updates: every value is already global, and there are no
// ghosts.
const Reducer kWholeMeshReducer;
const Halo kNoGhosts;
}  // namespace

MeshPart::MeshPart(Mesh& whole) : mesh_(&whole), reducer_(&kWholeMeshReducer), halo_(&kNoGhosts) {}

MeshPart::MeshPart(DistributedMesh& part)
    : mesh_(&part.mesh), reducer_(&part.reducer()), halo_(&part.halo()), distributed_(&part) {}

bool MeshPart::owns(VertexId v) const {
    return !distributed_ || distributed_->vertex_owner[static_cast<std::size_t>(v)] == distributed_->rank;
}

bool MeshPart::counts(ElementId e) const {
    return !distributed_ || distributed_->counted[static_cast<std::size_t>(e)] != 0;
}

}  // namespace paloverde
