#pragma once
// A solver (vertex mover) improves a mesh in place and says what it did. Whatever stops it, the
// mesh it leaves is never worse than the one it got: no more inverted elements, and no lower
// worst quality among the elements it could move.
#include <string_view>

#include "paloverde/mesh/simplex_mesh.hpp"
#include "paloverde/solvers/summary.hpp"

namespace paloverde {

class Solver {
public:
    virtual ~Solver() = default;
    virtual std::string_view name() const = 0;
    virtual Summary improve(SimplexMesh& mesh) = 0;
};

}  // namespace paloverde
