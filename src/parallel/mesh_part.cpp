#include "paloverde/parallel/mesh_part.hpp"

#include <algorithm>
#include <optional>

#include "paloverde/core/error.hpp"
#include "paloverde/mesh/boundary_surface.hpp"
#if PALOVERDE_HAVE_MPI
#include "paloverde/parallel/distributed_mesh.hpp"
#endif

namespace paloverde {

namespace {
// A serial run's reductions and ghost updates: every value is already global, and there are no
// ghosts.
const Reducer kWholeMeshReducer;
const Halo kNoGhosts;
}  // namespace

MeshPart::MeshPart(Mesh& whole) : mesh_(&whole), reducer_(&kWholeMeshReducer), halo_(&kNoGhosts) {}

// A build without MPI (PALOVERDE_MPI=OFF) has no DistributedMesh: a part is always the whole
// mesh. This is the one place in the library that tells the two builds apart; the build leaves
// the distributed sources out.
#if PALOVERDE_HAVE_MPI
MeshPart::MeshPart(DistributedMesh& part)
    : mesh_(&part.mesh()), reducer_(&part.reducer()), halo_(&part.halo()), distributed_(&part) {}

bool MeshPart::owns(VertexId v) const {
    return !distributed_ || distributed_->vertex_owner()[static_cast<std::size_t>(v)] == distributed_->rank();
}

bool MeshPart::counts(ElementId e) const {
    return !distributed_ || distributed_->counted()[static_cast<std::size_t>(e)] != 0;
}

int MeshPart::rank() const { return distributed_ ? distributed_->rank() : 0; }

int MeshPart::ranks() const { return distributed_ ? distributed_->ranks() : 1; }

GlobalId MeshPart::global_vertices() const {
    return distributed_ ? distributed_->global_vertices() : static_cast<GlobalId>(mesh_->num_vertices());
}

GlobalId MeshPart::global_elements() const {
    return distributed_ ? distributed_->global_elements() : static_cast<GlobalId>(mesh_->num_elements());
}

std::span<const GlobalId> MeshPart::element_positions() const {
    if (!distributed_) return {};
    return distributed_->element_order();
}

std::span<const std::uint8_t> MeshPart::counted() const {
    if (!distributed_) return {};
    return distributed_->counted();
}

void MeshPart::reorder_elements(std::span<const ElementId> order) const {
    if (!distributed_) throw Error("MeshPart::reorder_elements: the whole mesh keeps the order it was given");
    distributed_->reorder_elements(order);
}

Vec3 MeshPart::plane_normal() const { return distributed_ ? distributed_->plane_normal() : mesh_->plane_normal(); }

BoundarySurface MeshPart::boundary_surface(bool surface_mesh, const SurfaceOptions& options) const {
    if (!distributed_) return BoundarySurface(*mesh_, options);
    return BoundarySurface(distributed_->gather_boundary(surface_mesh), mesh_->global_ids(), options);
}

std::vector<Vec3> MeshPart::normals_of(const BoundarySurface& surface, const Mesh& mesh) const {
    return distributed_ ? surface.normals_of(mesh, mesh_->global_ids()) : surface.normals_of(mesh);
}

std::vector<double> MeshPart::gather_to_root(std::span<const double> field, int width) const {
    if (!distributed_) return {field.begin(), field.end()};
    return distributed_->gather_vertex_field(field, width);
}

void MeshPart::broadcast(std::string& bytes) const {
    if (distributed_) distributed_->broadcast(bytes);
}

void MeshPart::on_root(const std::function<void()>& work) const {
    if (!distributed_) return work();
    distributed_->on_root(work);
}

#else
bool MeshPart::owns(VertexId) const { return true; }
bool MeshPart::counts(ElementId) const { return true; }
int MeshPart::rank() const { return 0; }
int MeshPart::ranks() const { return 1; }
GlobalId MeshPart::global_vertices() const { return static_cast<GlobalId>(mesh_->num_vertices()); }
GlobalId MeshPart::global_elements() const { return static_cast<GlobalId>(mesh_->num_elements()); }
std::span<const GlobalId> MeshPart::element_positions() const { return {}; }
std::span<const std::uint8_t> MeshPart::counted() const { return {}; }
void MeshPart::reorder_elements(std::span<const ElementId>) const {
    throw Error("MeshPart::reorder_elements: the whole mesh keeps the order it was given");
}
Vec3 MeshPart::plane_normal() const { return mesh_->plane_normal(); }
BoundarySurface MeshPart::boundary_surface(bool, const SurfaceOptions& options) const {
    return BoundarySurface(*mesh_, options);
}
std::vector<Vec3> MeshPart::normals_of(const BoundarySurface& surface, const Mesh& mesh) const {
    return surface.normals_of(mesh);
}
std::vector<double> MeshPart::gather_to_root(std::span<const double> field, int) const {
    return {field.begin(), field.end()};
}
void MeshPart::broadcast(std::string&) const {}
void MeshPart::on_root(const std::function<void()>& work) const { work(); }
#endif

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
