#include "paloverde/mesh/perturb.hpp"

#include <cmath>
#include <random>
#include <string>

#include "paloverde/core/error.hpp"
#include "paloverde/mesh/renumber.hpp"

namespace paloverde {

void PerturbOptions::validate() const {
    if (!(fraction >= 0.0 && fraction <= 1.0)) throw OptionError("fraction must lie in [0, 1] (got " + std::to_string(fraction) + ")");
    if (!(amount >= 0.0) || !std::isfinite(amount)) throw OptionError("amount must be >= 0 (got " + std::to_string(amount) + ")");
    if (!interior && !boundary) throw OptionError("choose interior vertices, boundary vertices or both");
}

VertexId perturb(Mesh& mesh, const PerturbOptions& options) {
    options.validate();
    const VertexGraph graph = vertex_graph(mesh, true);
    const bool planar = mesh.kind() == ElementKind::Triangle;
    const Vec3 normal = mesh.plane_normal();
    std::mt19937_64 rng(options.seed);
    std::uniform_real_distribution<double> unit(-1.0, 1.0), coin(0.0, 1.0);
    const std::vector<double> original(mesh.coordinates().begin(), mesh.coordinates().end());
    auto xyz = mesh.coordinates();
    VertexId moved = 0;
    for (VertexId v = 0; v < mesh.num_vertices(); ++v) {
        // Draw for every vertex, eligible or not, so a vertex's move depends only on the seed.
        const double pick = coin(rng);
        Vec3 d{};
        double length2 = 2.0;
        while (length2 > 1.0) {  // uniform in the unit ball (disk for planar triangles)
            d = {unit(rng), unit(rng), unit(rng)};
            if (planar) {
                const double along = d[0] * normal[0] + d[1] * normal[1] + d[2] * normal[2];
                for (int c = 0; c < 3; ++c) d[c] -= along * normal[c];
            }
            length2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        }
        const bool eligible = mesh.fixed()[v] ? options.boundary : options.interior;
        if (!eligible || pick >= options.fraction) continue;
        double edge = 0.0;
        const auto begin = graph.offsets[v], end = graph.offsets[v + 1];
        for (auto i = begin; i < end; ++i) {
            const VertexId w = graph.neighbours[i];
            edge += std::hypot(original[3 * w] - original[3 * v], original[3 * w + 1] - original[3 * v + 1],
                               original[3 * w + 2] - original[3 * v + 2]);
        }
        if (end == begin) continue;
        edge /= static_cast<double>(end - begin);
        for (int c = 0; c < 3; ++c) xyz[3 * static_cast<std::size_t>(v) + c] += options.amount * edge * d[c];
        ++moved;
    }
    return moved;
}

}  // namespace paloverde
