#pragma once
#include <array>
#include <cstdint>
#include <string_view>

namespace paloverde {

// Local (per-process) indices are 32-bit: a rank holds at most ~2 billion vertices or elements,
// and halving the index size halves the connectivity traffic of every pass.
using VertexId = std::int32_t;
using ElementId = std::int32_t;
// Global ids span the whole (possibly distributed) mesh.
using GlobalId = std::int64_t;

using Vec3 = std::array<double, 3>;

// Paloverde meshes hold one kind of simplex. The enumerator value is the corner count.
enum class ElementKind : std::uint8_t { Triangle = 3, Tetrahedron = 4 };

constexpr int corner_count(ElementKind kind) noexcept { return static_cast<int>(kind); }
constexpr std::string_view to_string(ElementKind kind) noexcept {
    return kind == ElementKind::Triangle ? "triangle" : "tetrahedron";
}

}  // namespace paloverde
