#pragma once
// Makes tangled test meshes: moves vertices at random (reproducibly, by seed) by up to a
// multiple of their local edge length.
#include <cstdint>

#include "paloverde/mesh/mesh.hpp"

namespace paloverde {

struct PerturbOptions {
    double fraction = 1.0;   // of the eligible vertices, in [0, 1]
    double amount = 0.5;     // largest move, in local edge lengths (the mean edge length at the vertex)
    bool interior = true;    // free vertices are eligible
    bool boundary = false;   // fixed vertices are eligible (a planar triangle mesh stays in its plane)
    std::uint64_t seed = 1;
    void validate() const;   // throws OptionError
};

// Returns the number of vertices moved.
VertexId perturb(Mesh& mesh, const PerturbOptions& options);

}  // namespace paloverde
