#include "paloverde/parallel/mesh_part.hpp"

#include <algorithm>
#include <optional>

#include "paloverde/core/error.hpp"
#include "paloverde/mesh/boundary_surface.hpp"
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

void set_targets(MeshPart part, const TargetOptions& options, const Mesh* reference) {
    if (!options.any()) {
        part.mesh().clear_targets();
        return;
    }
    const Mesh& mesh = part.mesh();
    // Without one given, the reference is the part itself at its reference coordinates (those of
    // the whole mesh's reference travel with a part like its coordinates).
    std::optional<Mesh> own;
    if (!reference && options.uses(TargetSource::Reference) && !mesh.reference_coordinates().empty()) {
        own.emplace(mesh);
        std::copy(mesh.reference_coordinates().begin(), mesh.reference_coordinates().end(), own->coordinates().begin());
        reference = &*own;
    }
    std::vector<std::uint8_t> counted(static_cast<std::size_t>(mesh.num_elements()));
    for (ElementId e = 0; e < mesh.num_elements(); ++e) counted[static_cast<std::size_t>(e)] = part.counts(e);
    // A part of a surface mesh may lie in one plane: the whole mesh says what it is.
    const bool surface = part.reducer().max(is_surface_mesh(mesh) ? 1.0 : 0.0) > 0.0;
    const double sum = part.reducer().total(ideal_size_sum(mesh, counted, surface));
    const double elements = part.reducer().total(static_cast<double>(std::count(counted.begin(), counted.end(), 1)));
    std::vector<double> metrics = vertex_metrics(mesh, options, reference, surface);
    if (!metrics.empty()) part.halo().update(metrics, Mesh::kMetricValues);
    set_targets(part.mesh(), options, reference, elements > 0.0 ? sum / elements : 1.0, metrics, surface);
}

}  // namespace paloverde
