#include "paloverde/mesh/cell_types.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "small_matrix.hpp"

namespace paloverde {

namespace {
using Frame = std::array<int, 4>;
constexpr int X = -1;  // no vertex

constexpr Frame kTriangleFrames[] = {{0, 1, 2, X}};
constexpr Frame kQuadFrames[] = {{0, 1, 3, X}, {1, 2, 0, X}, {2, 3, 1, X}, {3, 0, 2, X}};
constexpr Frame kTetFrames[] = {{0, 1, 2, 3}};
constexpr Frame kHexFrames[] = {{0, 1, 3, 4}, {1, 2, 0, 5}, {2, 3, 1, 6}, {3, 0, 2, 7},
                                {4, 7, 5, 0}, {5, 4, 6, 1}, {6, 5, 7, 2}, {7, 6, 4, 3}};
constexpr Frame kWedgeFrames[] = {{0, 2, 1, 3}, {1, 0, 2, 4}, {2, 1, 0, 5}, {3, 4, 5, 0}, {4, 5, 3, 1}, {5, 3, 4, 2}};
constexpr Frame kPyramidFrames[] = {{0, 1, 3, 4}, {1, 2, 0, 4}, {2, 3, 1, 4}, {3, 0, 2, 4}};

constexpr Frame kTriangleFaces[] = {{0, 1, X, X}, {1, 2, X, X}, {2, 0, X, X}};
constexpr Frame kQuadFaces[] = {{0, 1, X, X}, {1, 2, X, X}, {2, 3, X, X}, {3, 0, X, X}};
constexpr Frame kTetFaces[] = {{1, 2, 3, X}, {0, 2, 3, X}, {0, 1, 3, X}, {0, 1, 2, X}};
constexpr Frame kHexFaces[] = {{0, 1, 2, 3}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
constexpr Frame kWedgeFaces[] = {{0, 1, 2, X}, {3, 4, 5, X}, {0, 1, 4, 3}, {1, 2, 5, 4}, {2, 0, 3, 5}};
constexpr Frame kPyramidFaces[] = {{0, 1, 2, 3}, {0, 1, 4, X}, {1, 2, 4, X}, {2, 3, 4, X}, {3, 0, 4, X}};

constexpr std::array<int, kMaxCellCorners> kSame = {0, 1, 2, 3, 4, 5, 6, 7};

const CellInfo kInfos[kCellTypeCount] = {
    {CellType::Triangle, "triangle", 2, 3, ElementKind::Triangle, kTriangleFrames, kTriangleFaces,
     {0, 2, 1}, 5, 2, "Triangles", kSame},
    {CellType::Quadrilateral, "quadrilateral", 2, 4, ElementKind::Triangle, kQuadFrames, kQuadFaces,
     {0, 3, 2, 1}, 9, 3, "Quadrilaterals", kSame},
    {CellType::Tetrahedron, "tetrahedron", 3, 4, ElementKind::Tetrahedron, kTetFrames, kTetFaces,
     {0, 1, 3, 2}, 10, 4, "Tetrahedra", kSame},
    {CellType::Hexahedron, "hexahedron", 3, 8, ElementKind::Tetrahedron, kHexFrames, kHexFaces,
     {0, 3, 2, 1, 4, 7, 6, 5}, 12, 5, "Hexahedra", kSame},
    // Gmsh and Medit order a prism's first triangle towards the second one: the mirror of VTK's.
    {CellType::Wedge, "wedge", 3, 6, ElementKind::Tetrahedron, kWedgeFrames, kWedgeFaces,
     {0, 2, 1, 3, 5, 4}, 13, 6, "Prisms", {0, 2, 1, 3, 5, 4}},
    {CellType::Pyramid, "pyramid", 3, 5, ElementKind::Tetrahedron, kPyramidFrames, kPyramidFaces,
     {0, 3, 2, 1, 4}, 14, 7, "Pyramids", kSame},
};

constexpr double kR3 = std::numbers::sqrt3;
const std::array<double, 3> kIdealTriangle[] = {{0, 0, 0}, {1, 0, 0}, {0.5, kR3 / 2, 0}};
const std::array<double, 3> kIdealQuad[] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
const std::array<double, 3> kIdealTet[] = {{0, 0, 0}, {1, 0, 0}, {0.5, kR3 / 2, 0}, {0.5, kR3 / 6, 0.81649658092772603273}};
const std::array<double, 3> kIdealHex[] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                           {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
const std::array<double, 3> kIdealWedge[] = {{0, 0, 0}, {0.5, kR3 / 2, 0}, {1, 0, 0},
                                             {0, 0, 1}, {0.5, kR3 / 2, 1}, {1, 0, 1}};
const std::array<double, 3> kIdealPyramid[] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                               {0.5, 0.5, std::numbers::sqrt2 / 2}};

using Matrix = detail::SmallMatrix;  // m[row][column]

using detail::determinant;
using detail::inverse;

// The frame's edge vectors as columns: m[row = coordinate][column = neighbour].
Matrix frame_matrix(std::span<const std::array<double, 3>> x, const Frame& f, int d) {
    Matrix m{};
    for (int j = 0; j < d; ++j)
        for (int r = 0; r < 3; ++r) m[r][j] = x[f[j + 1]][r] - x[f[0]][r];
    return m;
}

struct MapTable {
    std::vector<CornerMap> maps;     // [0]: identity
    std::vector<CellType> cell;      // per map
    std::array<int, kCellTypeCount> first{};  // first map id of each type
};

const MapTable& map_table() {
    static const MapTable table = [] {
        MapTable t;
        CornerMap identity{};
        for (int i = 0; i < 3; ++i) identity[i][i] = 1.0;
        t.maps.push_back(identity);
        t.cell.push_back(CellType::Tetrahedron);
        for (const CellInfo& info : kInfos) {
            const auto type_index = static_cast<std::size_t>(info.type);
            if (is_simplex(info.type)) {
                t.first[type_index] = 0;
                continue;
            }
            t.first[type_index] = static_cast<int>(t.maps.size());
            const int d = info.dimension;
            const Matrix regular = frame_matrix(ideal_cell(simplex_cell(info.simplex)), kTetFrames[0], d);
            for (const Frame& f : info.frames) {
                const Matrix w = frame_matrix(ideal_cell(info.type), f, d);
                if (!(determinant(w, d) > 0.0))
                    throw std::logic_error("cell table: a frame of the ideal " + std::string(info.name) + " is not positive");
                const Matrix w_inverse = inverse(w, d);
                CornerMap m{};  // M = W^-1 W_regular, in the frame's own coordinates
                for (int j = 0; j < d; ++j)
                    for (int i = 0; i < d; ++i)
                        for (int k = 0; k < d; ++k) m[j][i] += w_inverse[j][k] * regular[k][i];
                t.maps.push_back(m);
                t.cell.push_back(info.type);
            }
        }
        return t;
    }();
    return table;
}
}  // namespace

const CellInfo& cell_info(CellType type) { return kInfos[static_cast<std::size_t>(type)]; }
std::span<const CellInfo> all_cell_infos() { return kInfos; }

std::uint8_t corner_map_id(CellType type, int frame) {
    if (is_simplex(type)) return 0;
    return static_cast<std::uint8_t>(map_table().first[static_cast<std::size_t>(type)] + frame);
}
const CornerMap& corner_map(std::uint8_t id) { return map_table().maps[id]; }
CellType corner_map_cell(std::uint8_t id) { return map_table().cell[id]; }
int corner_map_count() { return static_cast<int>(map_table().maps.size()); }

std::span<const std::array<double, 3>> ideal_cell(CellType type) {
    switch (type) {
        case CellType::Triangle: return kIdealTriangle;
        case CellType::Quadrilateral: return kIdealQuad;
        case CellType::Tetrahedron: return kIdealTet;
        case CellType::Hexahedron: return kIdealHex;
        case CellType::Wedge: return kIdealWedge;
        case CellType::Pyramid: return kIdealPyramid;
    }
    return {};
}

}  // namespace paloverde
