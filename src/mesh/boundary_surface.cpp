#include "paloverde/mesh/boundary_surface.hpp"

#include <CGAL/AABB_segment_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "paloverde/core/error.hpp"

namespace paloverde {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Triangles = std::vector<Kernel::Triangle_3>;
using Segments = std::vector<Kernel::Segment_3>;
using TriangleTree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, CGAL::AABB_triangle_primitive<Kernel, Triangles::const_iterator>>>;
using SegmentTree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, CGAL::AABB_segment_primitive<Kernel, Segments::const_iterator>>>;

Vec3 minus(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3 cross(const Vec3& a, const Vec3& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }

// The angle between two vectors, in degrees; 0 when either has no length.
double angle_between(const Vec3& a, const Vec3& b) {
    const double la = norm(a), lb = norm(b);
    if (!(la > 0.0) || !(lb > 0.0)) return 0.0;
    return std::atan2(norm(cross(a, b)), dot(a, b)) * (180.0 / std::numbers::pi);
}

// A boundary facet: a triangle of a tet mesh's boundary, or an edge of a triangle mesh's (the
// third vertex then -1), its corners in the order that makes it face outward.
struct Facet {
    std::array<GlobalId, 3> corner;
    std::array<GlobalId, 3> key;  // the corners sorted
    std::size_t source = 0;       // its place in BoundaryFacets::facets
};

// The outward faces of a positively oriented tetrahedron (0, 1, 2, 3), and the outward edges of a
// positively oriented triangle: the mesh's own corner order decides, not its tangled geometry.
constexpr int kTetFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
constexpr int kTriEdges[3][2] = {{0, 1}, {1, 2}, {2, 0}};

// The diagonal of the points' bounding box; 0 for none.
double diagonal_of(std::span<const double> xyz) {
    if (xyz.empty()) return 0.0;
    Vec3 low = {xyz[0], xyz[1], xyz[2]}, high = low;
    for (std::size_t i = 0; i < xyz.size(); ++i) low[i % 3] = std::min(low[i % 3], xyz[i]), high[i % 3] = std::max(high[i % 3], xyz[i]);
    return norm(minus(high, low));
}

// Facets sorted by key.
void sort_by_key(std::vector<Facet>& facets) {
    std::sort(facets.begin(), facets.end(), [](const Facet& a, const Facet& b) { return a.key < b.key; });
}

Vec3 unit(const Vec3& a) {
    const double l = norm(a);
    return l > 0.0 ? Vec3{a[0] / l, a[1] / l, a[2] / l} : Vec3{0.0, 0.0, 0.0};
}

// Union-find over 0..n-1 with path halving: patches from faces, curves from feature edges.
class Groups {
public:
    explicit Groups(std::size_t n) : parent_(n) {
        for (std::size_t i = 0; i < n; ++i) parent_[i] = i;
    }
    std::size_t find(std::size_t i) {
        while (parent_[i] != i) i = parent_[i] = parent_[parent_[i]];
        return i;
    }
    void join(std::size_t a, std::size_t b) { parent_[find(a)] = find(b); }
    // Dense ids 0..k-1 of the groups, by first appearance; returns k.
    std::size_t number(std::vector<std::int32_t>& id) {
        id.assign(parent_.size(), -1);
        std::vector<std::int32_t> of_root(parent_.size(), -1);
        std::int32_t next = 0;
        for (std::size_t i = 0; i < parent_.size(); ++i) {
            auto& root = of_root[find(i)];
            if (root < 0) root = next++;
            id[i] = root;
        }
        return static_cast<std::size_t>(next);
    }

private:
    std::vector<std::size_t> parent_;
};

// The crease chains of at most three edges with a loose end, none on an open edge, made smooth
// again (see the caller). `creases`: per vertex, its crease edges.
template <class Edge>
void drop_short_loose_creases(std::vector<Edge>& edges, const std::vector<int>& creases,
                              const std::vector<std::uint8_t>& on_open) {
    constexpr std::size_t kShort = 3;
    auto is_crease = [](const Edge& e) { return e.feature && e.count == 2; };
    Groups chains(edges.size());
    std::vector<std::int64_t> first_at(creases.size(), -1);  // per vertex, a crease edge through it
    for (std::size_t i = 0; i < edges.size(); ++i) {
        if (!is_crease(edges[i])) continue;
        for (auto v : edges[i].ends) {
            auto& first = first_at[static_cast<std::size_t>(v)];
            if (first < 0) first = static_cast<std::int64_t>(i);
            else chains.join(static_cast<std::size_t>(first), i);
        }
    }
    std::vector<std::int32_t> chain_of;
    const std::size_t count = chains.number(chain_of);
    std::vector<std::size_t> length(count, 0);
    std::vector<std::uint8_t> loose(count, 0), open(count, 0);
    for (std::size_t i = 0; i < edges.size(); ++i) {
        if (!is_crease(edges[i])) continue;
        const auto c = static_cast<std::size_t>(chain_of[i]);
        ++length[c];
        for (auto v : edges[i].ends) {
            loose[c] |= creases[static_cast<std::size_t>(v)] == 1;
            open[c] |= on_open[static_cast<std::size_t>(v)];
        }
    }
    for (std::size_t i = 0; i < edges.size(); ++i) {
        if (!is_crease(edges[i])) continue;
        const auto c = static_cast<std::size_t>(chain_of[i]);
        if (length[c] <= kShort && loose[c] && !open[c]) edges[i].feature = false;
    }
}

// An AABB tree over its own primitives (the tree refers to them, so they live beside it).
template <class Primitives, class Tree>
struct Piece {
    Primitives primitives;
    Tree tree;
    void build() {
        if (primitives.empty()) return;
        tree.insert(primitives.cbegin(), primitives.cend());
        tree.accelerate_distance_queries();
    }
};
using Patch = Piece<Triangles, TriangleTree>;
using Curve = Piece<Segments, SegmentTree>;

// Per facet, +1 or -1: the turn that makes it agree with its neighbours across every edge of
// exactly two facets (they then run along it in opposite directions), by a breadth-first walk
// from the lowest facet of each connected piece. On a surface that cannot be oriented (a Moebius
// strip) the walk's first choice stands. `uses`: each facet's edges, sorted by edge.
template <class EdgeUse>
std::vector<double> consistent_turns(std::size_t count, const std::vector<EdgeUse>& uses) {
    std::vector<std::vector<std::pair<std::size_t, bool>>> next(count);  // (neighbour, same direction)
    for (std::size_t i = 0; i + 1 < uses.size(); ++i) {
        if (uses[i].key != uses[i + 1].key || (i + 2 < uses.size() && uses[i + 2].key == uses[i].key) ||
            (i > 0 && uses[i - 1].key == uses[i].key))
            continue;
        const bool same = uses[i].forward == uses[i + 1].forward;
        next[uses[i].facet].push_back({uses[i + 1].facet, same});
        next[uses[i + 1].facet].push_back({uses[i].facet, same});
    }
    std::vector<double> turn(count, 0.0);
    std::vector<std::size_t> queue;
    for (std::size_t start = 0; start < count; ++start) {
        if (turn[start] != 0.0) continue;
        turn[start] = 1.0;
        queue.assign(1, start);
        for (std::size_t at = 0; at < queue.size(); ++at)
            for (const auto& [g, same] : next[queue[at]])
                if (turn[g] == 0.0) {
                    turn[g] = same ? -turn[queue[at]] : turn[queue[at]];
                    queue.push_back(g);
                }
    }
    return turn;
}

// Per facet of a surface mesh: 1 where the input turned it over. A vertex slid past its
// neighbours turns a few triangles over in a surface that faces one way around them: of the
// facets that share a corner with such a triangle, at least two thirds face against it (normals
// more than 90 degrees apart; `normal(f)` is turned to agree with the neighbours), those agree
// among themselves (their unit normals' mean is at least 3/4 long) and their mean makes more
// than 120 degrees with its own. A tetrahedron's faces (their neighbours disagree) and a thin
// fin's sides (its own side shares its corners too) are not turned over.
template <class Normal>
std::vector<std::uint8_t> turned_over_facets(std::span<const Facet> facets, Normal normal) {
    std::size_t vertices = 0;
    for (const Facet& f : facets) vertices = std::max(vertices, static_cast<std::size_t>(f.key[2]) + 1);
    std::vector<std::size_t> start(vertices + 1, 0), at;
    for (const Facet& f : facets)
        for (GlobalId v : f.key) ++start[static_cast<std::size_t>(v) + 1];
    for (std::size_t v = 0; v < vertices; ++v) start[v + 1] += start[v];
    at.resize(start.back());
    std::vector<std::size_t> next(start.begin(), start.end() - 1);
    for (std::size_t f = 0; f < facets.size(); ++f)
        for (GlobalId v : facets[f].key) at[next[static_cast<std::size_t>(v)]++] = f;
    std::vector<Vec3> unit_normal(facets.size());
    for (std::size_t f = 0; f < facets.size(); ++f) unit_normal[f] = unit(normal(f));
    std::vector<std::uint8_t> turned(facets.size(), 0);
    std::vector<std::size_t> around;
    for (std::size_t f = 0; f < facets.size(); ++f) {
        around.clear();
        for (GlobalId v : facets[f].key)
            for (std::size_t k = start[static_cast<std::size_t>(v)]; k < start[static_cast<std::size_t>(v) + 1]; ++k)
                if (at[k] != f) around.push_back(at[k]);
        std::sort(around.begin(), around.end());
        around.erase(std::unique(around.begin(), around.end()), around.end());
        Vec3 against{0.0, 0.0, 0.0};
        std::size_t count = 0;
        for (std::size_t g : around)
            if (dot(unit_normal[f], unit_normal[g]) < 0.0) {
                for (int k = 0; k < 3; ++k) against[k] += unit_normal[g][k];
                ++count;
            }
        const double length = norm(against);
        turned[f] = count > 0 && 3 * count >= 2 * around.size() && length >= 0.75 * static_cast<double>(count) &&
                    dot(unit_normal[f], against) < -0.5 * length;
    }
    return turned;
}

// A surface mesh's triangles' normals to rate them about (BoundarySurface::element_normals), from
// the input's places, roles and surface vertices' normals (`direction`), by facet source.
std::vector<Vec3> smoothed_normals(std::span<const Facet> facets, std::span<const double> turn,
                                   std::span<const std::uint8_t> turned, std::span<const Vec3> original_,
                                   std::span<const BoundaryRole> roles_, std::span<const Vec3> direction_) {
    // The mean of the corners' normals, each the area-weighted normal of its patch at that
    // corner (a crease or corner vertex gives the triangle's own), in the triangle's own turn.
    // A turned-over triangle keeps the surface's mean, against which it is inverted; a crease
    // or corner vertex then gives its own turned back.
    std::vector<Vec3> out(facets.size());
    for (std::size_t f = 0; f < facets.size(); ++f) {
        const auto& c = facets[f].corner;
        const Vec3 own = unit(cross(minus(original_[static_cast<std::size_t>(c[1])], original_[static_cast<std::size_t>(c[0])]),
                                    minus(original_[static_cast<std::size_t>(c[2])], original_[static_cast<std::size_t>(c[0])])));
        if (own == Vec3{0.0, 0.0, 0.0})
            throw MeshError("triangle " + std::to_string(facets[f].source) +
                            " has no area, so the surface has no normal there: remove or repair it first");
        const bool over = turned[f] != 0;
        const Vec3 side = over ? Vec3{-own[0], -own[1], -own[2]} : own;
        Vec3 sum = {0.0, 0.0, 0.0};
        for (GlobalId v : c) {
            const auto i = static_cast<std::size_t>(v);
            const Vec3 n = roles_[i] == BoundaryRole::Surface ? Vec3{turn[f] * direction_[i][0], turn[f] * direction_[i][1],
                                                                     turn[f] * direction_[i][2]}
                                                              : side;
            for (int k = 0; k < 3; ++k) sum[k] += n[k];
        }
        const Vec3 mean = unit(sum);
        out[facets[f].source] = over ? (mean == Vec3{0.0, 0.0, 0.0} ? side : mean) : dot(mean, own) > 0.0 ? mean : own;
    }
    return out;
}

// The input's vertices must lie on an analytic domain: a vertex far off it would jump at its
// first move. Float rounding of the file's coordinates is allowed, nothing more (as for a planar
// mesh). Throws MeshError naming the first vertex off it.
void check_on_domain(const BoundaryFacets& boundary, const SurfaceDomain& domain) {
    const double tolerance = 1e-6 * boundary.diagonal;
    for (std::size_t i = 0; i < boundary.ids.size(); ++i) {
        const Vec3 x{boundary.xyz[3 * i], boundary.xyz[3 * i + 1], boundary.xyz[3 * i + 2]};
        const double off = domain.distance(x);
        if (!(off <= tolerance))
            throw MeshError(domain.off_message(boundary.ids[i], off) +
                            ": give the shape the mesh lies on, or no domain to slide on the mesh itself");
    }
}

// On an analytic domain each triangle is rated about the shape's normal at its centroid, turned
// to the side of the normal the input gave it (`normals`, which follow the file's orientation).
void turn_to_domain(std::span<const Facet> facets, std::span<const Vec3> original, const SurfaceDomain& domain,
                    std::span<Vec3> normals) {
    for (const Facet& f : facets) {
        Vec3 centroid{0.0, 0.0, 0.0};
        for (GlobalId v : f.corner)
            for (int k = 0; k < 3; ++k) centroid[k] += original[static_cast<std::size_t>(v)][k] / 3.0;
        Vec3& n = normals[f.source];
        const Vec3 g = domain.normal(centroid);
        n = dot(g, n) < 0.0 ? Vec3{-g[0], -g[1], -g[2]} : g;
    }
}

}  // namespace

struct BoundarySurface::Trees {
    std::vector<std::unique_ptr<Patch>> patches;  // by patch id
    std::vector<std::unique_ptr<Curve>> curves;   // by curve id
    Patch all_faces;                              // tetrahedra: every boundary face
    Curve all_edges;                              // triangles: every boundary edge
};

void SurfaceOptions::validate() const {
    if (!(feature_angle > 0.0 && feature_angle < 180.0))
        throw OptionError("feature_angle must lie in (0, 180) degrees (got " + std::to_string(feature_angle) + ")");
    try {
        domain.validate();
    } catch (const OptionError& e) {
        throw OptionError("domain: " + std::string(e.what()));
    }
}

BoundarySurface::~BoundarySurface() = default;
BoundarySurface::BoundarySurface(BoundarySurface&&) noexcept = default;
BoundarySurface& BoundarySurface::operator=(BoundarySurface&&) noexcept = default;

bool is_surface_mesh(const Mesh& mesh) {
    return mesh.kind() == ElementKind::Triangle && !mesh.is_planar() && mesh.num_elements() > 0;
}

BoundaryFacets BoundaryFacets::of(const Mesh& mesh) { return of(mesh, is_surface_mesh(mesh)); }

BoundaryFacets BoundaryFacets::of(const Mesh& mesh, bool surface) {
    BoundaryFacets out;
    out.kind = mesh.kind();
    const bool tets = out.kind == ElementKind::Tetrahedron;
    if (surface && !tets) {
        // A surface mesh is its own surface: every triangle a facet, every quadrilateral two
        // (cut along its diagonal from its first corner), every vertex on it.
        out.surface = true;
        const auto xyz = mesh.coordinates();
        for (ElementId c = 0; c < mesh.num_cells(); ++c) {
            const auto k = mesh.cell(c);
            for (std::size_t i = 2; i < k.size(); ++i) out.facets.push_back({k[0], k[i - 1], k[i]});
            for (std::size_t i = 2; i + 1 < k.size(); ++i) out.cuts.push_back({k[0], k[i]});
        }
        for (VertexId v = 0; v < mesh.num_vertices(); ++v) {
            if (mesh.elements_of(v).empty()) continue;
            out.ids.push_back(static_cast<GlobalId>(v));
            out.xyz.insert(out.xyz.end(), xyz.begin() + 3 * static_cast<std::ptrdiff_t>(v),
                           xyz.begin() + 3 * static_cast<std::ptrdiff_t>(v) + 3);
        }
        out.diagonal = diagonal_of(xyz);
        return out;
    }
    if (mesh.has_cells())
        throw MeshError("boundary vertices slide on meshes of triangles and tetrahedra only, for now");
    std::vector<Facet> all;
    all.reserve(static_cast<std::size_t>(mesh.num_elements()) * (tets ? 4 : 3));
    for (ElementId e = 0; e < mesh.num_elements(); ++e) {
        const auto c = mesh.element(e);
        for (int f = 0; f < (tets ? 4 : 3); ++f) {
            Facet facet;
            facet.corner = tets ? std::array<GlobalId, 3>{c[kTetFaces[f][0]], c[kTetFaces[f][1]], c[kTetFaces[f][2]]}
                                : std::array<GlobalId, 3>{c[kTriEdges[f][0]], c[kTriEdges[f][1]], -1};
            facet.key = facet.corner;
            std::sort(facet.key.begin(), facet.key.end());
            all.push_back(facet);
        }
    }
    sort_by_key(all);
    const auto xyz = mesh.coordinates();
    std::vector<std::uint8_t> on_boundary(static_cast<std::size_t>(mesh.num_vertices()), 0);
    for (std::size_t i = 0; i < all.size();) {
        std::size_t j = i + 1;
        while (j < all.size() && all[j].key == all[i].key) ++j;
        if (j - i == 1) {
            out.facets.push_back(all[i].corner);
            for (GlobalId v : all[i].corner)
                if (v >= 0) on_boundary[static_cast<std::size_t>(v)] = 1;
        }
        i = j;
    }
    for (std::size_t v = 0; v < on_boundary.size(); ++v) {
        if (!on_boundary[v]) continue;
        out.ids.push_back(static_cast<GlobalId>(v));
        out.xyz.insert(out.xyz.end(), xyz.begin() + static_cast<std::ptrdiff_t>(3 * v),
                       xyz.begin() + static_cast<std::ptrdiff_t>(3 * v + 3));
    }
    out.diagonal = diagonal_of(xyz);
    return out;
}

namespace {
std::vector<GlobalId> identity(VertexId n) {
    std::vector<GlobalId> ids(static_cast<std::size_t>(n));
    for (std::size_t v = 0; v < ids.size(); ++v) ids[v] = static_cast<GlobalId>(v);
    return ids;
}
}  // namespace

BoundarySurface::BoundarySurface(const Mesh& mesh, const SurfaceOptions& options)
    : BoundarySurface(BoundaryFacets::of(mesh), identity(mesh.num_vertices()), options) {}

BoundarySurface::BoundarySurface(const BoundaryFacets& boundary, std::span<const GlobalId> vertex_ids,
                                 const SurfaceOptions& options)
    : kind_(boundary.kind), surface_(boundary.surface),
      // A planar mesh keeps to its plane without one (the solvers check a plane domain there).
      domain_(boundary.surface || boundary.kind == ElementKind::Tetrahedron ? options.domain : SurfaceDomain{}),
      diagonal_(boundary.diagonal), trees_(std::make_unique<Trees>()) {
    options.validate();
    // The facets are triangles (a tet mesh's boundary faces, or a surface mesh's own triangles),
    // else a planar triangle mesh's boundary edges.
    const bool tets = kind_ == ElementKind::Tetrahedron || surface_;
    // Boundary vertices numbered by their coordinates (ties by id), so that neither the numbering
    // nor the corner order of the elements changes which facet comes first, which corner a
    // normal is taken from, or in which order sums are made.
    const std::size_t n = boundary.ids.size();
    auto place = [&](std::size_t i) { return Vec3{boundary.xyz[3 * i], boundary.xyz[3 * i + 1], boundary.xyz[3 * i + 2]}; };
    std::vector<std::size_t> by_place(n);
    for (std::size_t i = 0; i < n; ++i) by_place[i] = i;
    std::sort(by_place.begin(), by_place.end(), [&](std::size_t a, std::size_t b) {
        const Vec3 pa = place(a), pb = place(b);
        return pa != pb ? pa < pb : boundary.ids[a] < boundary.ids[b];
    });
    std::vector<std::int32_t> rank_of(n);
    original_.resize(n);
    for (std::size_t r = 0; r < n; ++r) {
        rank_of[by_place[r]] = static_cast<std::int32_t>(r);
        original_[r] = place(by_place[r]);
    }
    auto boundary_vertex = [&](GlobalId id) -> std::int32_t {
        const auto at = std::lower_bound(boundary.ids.begin(), boundary.ids.end(), id);
        if (at == boundary.ids.end() || *at != id) return -1;
        return rank_of[static_cast<std::size_t>(at - boundary.ids.begin())];
    };
    index_.resize(vertex_ids.size());
    for (std::size_t v = 0; v < vertex_ids.size(); ++v) index_[v] = boundary_vertex(vertex_ids[v]);
    auto id_of = [&](GlobalId r) { return boundary.ids[by_place[static_cast<std::size_t>(r)]]; };
    roles_.assign(n, BoundaryRole::Surface);

    // The facets in boundary vertices, each turned to start at its first corner (keeping its
    // orientation), in the order of their sorted corners.
    std::vector<Facet> facets(boundary.facets.size());
    for (std::size_t f = 0; f < facets.size(); ++f) {
        auto& c = facets[f].corner;
        for (int k = 0; k < 3; ++k) {
            const GlobalId id = boundary.facets[f][k];
            c[k] = id < 0 ? -1 : boundary_vertex(id);
            if (id >= 0 && c[k] < 0)
                throw MeshError("boundary vertex " + std::to_string(id) + " of a boundary face has no coordinates");
        }
        if (tets) std::rotate(c.begin(), std::min_element(c.begin(), c.end()), c.end());
        facets[f].source = f;
        facets[f].key = c;
        std::sort(facets[f].key.begin(), facets[f].key.end());
    }
    sort_by_key(facets);
    face_count_ = facets.size();
    // Boundary edges with the facets on them: for a tet mesh, the edges of its boundary faces;
    // for a triangle mesh, the boundary edges themselves (each on a curve).
    struct EdgeUse {
        std::array<GlobalId, 2> key;
        std::size_t facet;
        bool forward;  // the facet runs along the edge from key[0] to key[1]
    };
    std::vector<EdgeUse> uses;
    for (std::size_t f = 0; f < facets.size(); ++f) {
        const auto& c = facets[f].corner;
        for (int i = 0; i < (tets ? 3 : 1); ++i) {
            const GlobalId a = c[i], b = c[(i + 1) % (tets ? 3 : 2)];
            uses.push_back({{std::min(a, b), std::max(a, b)}, f, a < b});
        }
    }
    std::sort(uses.begin(), uses.end(), [](const EdgeUse& a, const EdgeUse& b) {
        return a.key != b.key ? a.key < b.key : a.facet < b.facet;
    });
    // A surface mesh's triangles need not turn the same way (a file's CAD faces each keep their
    // own): each is turned to agree with the first of its connected piece across the edges of
    // two, so that the normals compared at an edge and summed at a vertex face one side.
    const std::vector<double> turn = surface_ ? consistent_turns(facets.size(), uses) : std::vector<double>(facets.size(), 1.0);
    auto normal = [&](std::size_t f) {
        const auto& c = facets[f].corner;
        const Vec3 n = cross(minus(original_[c[1]], original_[c[0]]), minus(original_[c[2]], original_[c[0]]));
        return Vec3{turn[f] * n[0], turn[f] * n[1], turn[f] * n[2]};
    };
    // A surface mesh's triangles that the input turned over (see turned_over_facets), and each
    // facet's normal turned back where it was: the side of the surface it lies on. Creases, folds
    // and vertex normals are read from these, so that a tangle makes no crease of its own.
    const std::vector<std::uint8_t> turned = surface_ ? turned_over_facets(facets, normal) : std::vector<std::uint8_t>{};
    auto facing = [&](std::size_t f) {
        const Vec3 n = normal(f);
        return !turned.empty() && turned[f] ? Vec3{-n[0], -n[1], -n[2]} : n;
    };
    // Feature edges, each vertex's feature edges by the vertex at their other end, and the faces
    // joined into patches across the smooth edges.
    struct Edge {
        std::array<GlobalId, 2> ends;
        std::size_t first, count;  // its facets: uses[first, first + count)
        bool feature;
    };
    std::vector<Edge> edges_of_facets;
    std::vector<std::array<GlobalId, 2>> cuts;  // in boundary vertices, each pair ascending, sorted
    for (const auto& [a, b] : boundary.cuts) {
        const GlobalId ra = boundary_vertex(a), rb = boundary_vertex(b);
        cuts.push_back({std::min(ra, rb), std::max(ra, rb)});
    }
    std::sort(cuts.begin(), cuts.end());
    std::vector<int> creases(n, 0);  // per vertex, its edges that are features by their angle alone
    std::vector<std::uint8_t> on_open(n, 0);  // per vertex: on an open (or a planar mesh's boundary) edge
    for (std::size_t i = 0; i < uses.size();) {
        std::size_t j = i + 1;
        while (j < uses.size() && uses[j].key == uses[i].key) ++j;
        const auto [a, b] = uses[i].key;
        if (tets && j - i > 2)
            throw MeshError((surface_ ? "the surface is not a manifold: " : "the boundary is not a manifold surface: ") +
                            std::to_string(j - i) + (surface_ ? " triangles" : " boundary faces") +
                            " meet at the edge of vertices " + std::to_string(id_of(a)) + " and " +
                            std::to_string(id_of(b)) + ", so no surface to slide on is defined there");
        const bool open = !tets || j - i != 2;
        const bool crease = !open && !std::binary_search(cuts.begin(), cuts.end(), std::array<GlobalId, 2>{a, b}) &&
                            angle_between(facing(uses[i].facet), facing(uses[i + 1].facet)) > options.feature_angle;
        if (crease) ++creases[static_cast<std::size_t>(a)], ++creases[static_cast<std::size_t>(b)];
        if (open) on_open[static_cast<std::size_t>(a)] = on_open[static_cast<std::size_t>(b)] = 1;
        edges_of_facets.push_back({{a, b}, i, j - i, open || crease});
        i = j;
    }
    // On a surface mesh, a triangle creased against every neighbour (cuts of a quadrilateral
    // aside) while those neighbours agree among themselves is read as a fold of its own, not as a
    // face of the part: a sliver on a smooth surface can face anywhere. Its edges are made smooth
    // again. (A face of one triangle between faces that meet at creases themselves, as on a
    // tetrahedron, stays.)
    if (surface_) {
        auto is_cut = [&](const Edge& e) { return std::binary_search(cuts.begin(), cuts.end(), e.ends); };
        std::vector<std::vector<std::size_t>> across(facets.size());  // neighbours across creases
        std::vector<int> smooth(facets.size(), 0);                    // shared edges that are not creases
        for (const Edge& e : edges_of_facets) {
            if (e.count != 2 || is_cut(e)) continue;
            const std::size_t f = uses[e.first].facet, g = uses[e.first + 1].facet;
            if (e.feature) across[f].push_back(g), across[g].push_back(f);
            else ++smooth[f], ++smooth[g];
        }
        // Neighbours agree when their normals are at most twice the feature angle apart (the
        // sliver's own fold aside, a coarse curved surface turns by up to that across two
        // triangles), and never more than a right angle (faces of a part meeting at creases).
        const double agree = std::min(2.0 * options.feature_angle, 90.0);
        auto fold = [&](std::size_t f) {
            if (smooth[f] > 0 || across[f].size() < 2) return false;
            for (std::size_t i = 0; i < across[f].size(); ++i)
                for (std::size_t j = i + 1; j < across[f].size(); ++j)
                    if (angle_between(facing(across[f][i]), facing(across[f][j])) > agree) return false;
            return true;
        };
        std::vector<std::uint8_t> folds(facets.size());
        for (std::size_t f = 0; f < facets.size(); ++f) folds[f] = fold(f);
        for (Edge& e : edges_of_facets)
            if (e.feature && e.count == 2 && (folds[uses[e.first].facet] || folds[uses[e.first + 1].facet])) {
                e.feature = false;
                --creases[static_cast<std::size_t>(e.ends[0])], --creases[static_cast<std::size_t>(e.ends[1])];
            }
    }
    // So is a short crease chain with a loose end (a vertex on no other crease): the creases of a
    // part run on, from corner to corner or round a loop. Kept, either would hold the sliver's
    // corners, and the sliver could never be mended.
    if (surface_) {
        drop_short_loose_creases(edges_of_facets, creases, on_open);
        on_open_ = on_open;
    }
    std::vector<std::array<GlobalId, 2>> features;
    std::vector<std::vector<GlobalId>> along(n);
    Groups faces(facets.size());
    for (const Edge& e : edges_of_facets) {
        const auto [a, b] = e.ends;
        if (e.feature) {
            along[static_cast<std::size_t>(a)].push_back(b);
            along[static_cast<std::size_t>(b)].push_back(a);
            features.push_back({a, b});
        } else {
            faces.join(uses[e.first].facet, uses[e.first + 1].facet);
        }
    }
    feature_count_ = features.size();
    for (std::size_t v = 0; v < n; ++v) {
        if (along[v].empty()) continue;
        bool corner = along[v].size() != 2;
        if (!corner) {
            // A curve through v turns by 180 degrees less the angle between its two edges there.
            const double turn = 180.0 - angle_between(minus(original_[along[v][0]], original_[v]),
                                                      minus(original_[along[v][1]], original_[v]));
            corner = turn > options.feature_angle;
        }
        roles_[v] = corner ? BoundaryRole::Corner : BoundaryRole::Curve;
    }

    auto point = [&](GlobalId v) {
        const Vec3& x = original_[static_cast<std::size_t>(v)];
        return Kernel::Point_3(x[0], x[1], x[2]);
    };
    direction_.assign(n, Vec3{0.0, 0.0, 0.0});
    piece_.assign(n, -1);
    // Patches: a surface vertex's faces all lie in one (none of its edges is a feature edge);
    // its normal is their area-weighted normal.
    std::vector<std::pair<std::int32_t, std::int32_t>> touching;  // (boundary vertex, primitive of its piece)
    std::vector<std::int32_t> patch_of;
    trees_->patches.resize(tets ? faces.number(patch_of) : 0);
    for (auto& patch : trees_->patches) patch = std::make_unique<Patch>();
    for (std::size_t f = 0; f < facets.size(); ++f) {
        if (!tets) break;
        const auto& c = facets[f].corner;
        const Vec3 nf = facing(f);
        for (GlobalId v : c)
            if (roles_[static_cast<std::size_t>(v)] == BoundaryRole::Surface) {
                auto& d = direction_[static_cast<std::size_t>(v)];
                for (int k = 0; k < 3; ++k) d[k] += nf[k];
                piece_[static_cast<std::size_t>(v)] = patch_of[f];
            }
        const Kernel::Triangle_3 t(point(c[0]), point(c[1]), point(c[2]));
        if (t.is_degenerate()) continue;
        auto& triangles = trees_->patches[static_cast<std::size_t>(patch_of[f])]->primitives;
        for (GlobalId v : c)
            if (roles_[static_cast<std::size_t>(v)] == BoundaryRole::Surface)
                touching.push_back({static_cast<std::int32_t>(v), static_cast<std::int32_t>(triangles.size())});
        triangles.push_back(t);
        trees_->all_faces.primitives.push_back(t);
    }
    // Curves: feature edges joined at curve vertices (corners end them); a curve vertex's tangent
    // bisects its two edges' directions.
    Groups edges(features.size());
    std::vector<std::int32_t> first_edge(n, -1);
    for (std::size_t e = 0; e < features.size(); ++e)
        for (GlobalId v : features[e]) {
            if (roles_[static_cast<std::size_t>(v)] != BoundaryRole::Curve) continue;
            auto& first = first_edge[static_cast<std::size_t>(v)];
            if (first < 0) first = static_cast<std::int32_t>(e);
            else edges.join(static_cast<std::size_t>(first), e);
        }
    std::vector<std::int32_t> curve_of;
    trees_->curves.resize(edges.number(curve_of));
    for (auto& curve : trees_->curves) curve = std::make_unique<Curve>();
    for (std::size_t e = 0; e < features.size(); ++e) {
        const auto [a, b] = features[e];
        const Kernel::Segment_3 s(point(a), point(b));
        if (s.is_degenerate()) continue;
        auto& segments = trees_->curves[static_cast<std::size_t>(curve_of[e])]->primitives;
        for (GlobalId v : {a, b})
            if (roles_[static_cast<std::size_t>(v)] == BoundaryRole::Curve)
                touching.push_back({static_cast<std::int32_t>(v), static_cast<std::int32_t>(segments.size())});
        segments.push_back(s);
        if (kind_ == ElementKind::Triangle && !surface_) trees_->all_edges.primitives.push_back(s);
    }
    for (std::size_t v = 0; v < n; ++v) {
        if (roles_[v] == BoundaryRole::Surface) direction_[v] = unit(direction_[v]);
        if (roles_[v] != BoundaryRole::Curve) continue;
        piece_[v] = curve_of[static_cast<std::size_t>(first_edge[v])];
        const Vec3 in = unit(minus(original_[v], original_[static_cast<std::size_t>(along[v][0])]));
        const Vec3 out = unit(minus(original_[static_cast<std::size_t>(along[v][1])], original_[v]));
        direction_[v] = unit({in[0] + out[0], in[1] + out[1], in[2] + out[2]});
    }
    if (domain_.analytic()) {
        check_on_domain(boundary, domain_);
        // A patch vertex's tangent plane is the shape's; its normal keeps the side the
        // input's triangles gave it.
        for (std::size_t v = 0; v < n; ++v) {
            if (roles_[v] != BoundaryRole::Surface) continue;
            const Vec3 g = domain_.normal(original_[v]);
            direction_[v] = dot(g, direction_[v]) < 0.0 ? Vec3{-g[0], -g[1], -g[2]} : g;
        }
    }
    std::stable_sort(touching.begin(), touching.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    star_start_.assign(n + 1, 0);
    for (const auto& [v, primitive] : touching) ++star_start_[static_cast<std::size_t>(v) + 1];
    for (std::size_t v = 0; v < n; ++v) star_start_[v + 1] += star_start_[v];
    star_.clear();
    for (const auto& [v, primitive] : touching) star_.push_back(primitive);
    if (surface_) {
        element_normals_ = smoothed_normals(facets, turn, turned, original_, roles_, direction_);
        if (domain_.analytic()) turn_to_domain(facets, original_, domain_, element_normals_);
        turned_over_ = std::count(turned.begin(), turned.end(), std::uint8_t{1});
        for (std::size_t f = 0; f < boundary.facets.size(); ++f) {
            auto key = boundary.facets[f];
            std::sort(key.begin(), key.end());
            facet_keys_.push_back({key, f});
        }
        std::sort(facet_keys_.begin(), facet_keys_.end());
    }
    for (auto& patch : trees_->patches) patch->build();
    for (auto& curve : trees_->curves) curve->build();
    trees_->all_faces.build();
    trees_->all_edges.build();
}

std::vector<Vec3> BoundarySurface::normals_of(const Mesh& mesh) const {
    return normals_of(mesh, identity(mesh.num_vertices()));
}

std::vector<Vec3> BoundarySurface::normals_of(const Mesh& mesh, std::span<const GlobalId> vertex_ids) const {
    if (!surface_) throw MeshError("normals_of: the surface is not a surface mesh's own");
    auto normal_of = [&](std::array<GlobalId, 3> key) {
        std::sort(key.begin(), key.end());
        const auto at = std::lower_bound(facet_keys_.begin(), facet_keys_.end(), std::make_pair(key, std::size_t{0}));
        if (at == facet_keys_.end() || at->first != key)
            throw MeshError("normals_of: a triangle of the mesh is not on the surface it was built from");
        return element_normals_[at->second];
    };
    // Each cell's triangles (cut as BoundaryFacets::of cuts them) give their mean normal to every
    // corner element of the cell; a triangle cell is its own.
    std::vector<Vec3> cell_normal(static_cast<std::size_t>(mesh.num_cells()));
    for (ElementId c = 0; c < mesh.num_cells(); ++c) {
        const auto k = mesh.cell(c);
        auto id = [&](std::size_t i) { return vertex_ids[static_cast<std::size_t>(k[i])]; };
        Vec3 sum = {0.0, 0.0, 0.0};
        for (std::size_t i = 2; i < k.size(); ++i) {
            const Vec3 n = normal_of({id(0), id(i - 1), id(i)});
            for (int j = 0; j < 3; ++j) sum[j] += n[j];
        }
        cell_normal[static_cast<std::size_t>(c)] = k.size() == 3 ? sum : unit(sum);
    }
    std::vector<Vec3> out(static_cast<std::size_t>(mesh.num_elements()));
    for (ElementId e = 0; e < mesh.num_elements(); ++e)
        out[static_cast<std::size_t>(e)] = cell_normal[static_cast<std::size_t>(mesh.cell_of(e))];
    return out;
}

int BoundarySurface::freedom(VertexId v) const {
    switch (role(v)) {
        case BoundaryRole::Interior: return kind_ == ElementKind::Tetrahedron ? 3 : 2;  // (none on a surface mesh)
        case BoundaryRole::Surface: return 2;
        case BoundaryRole::Curve: return 1;
        case BoundaryRole::Corner: return 0;
    }
    return 0;
}

Vec3 BoundarySurface::project(VertexId v, const Vec3& p) const {
    const auto i = static_cast<std::size_t>(index_[static_cast<std::size_t>(v)]);
    const Kernel::Point_3 q(p[0], p[1], p[2]);
    auto nearest = [&](const auto& piece) {
        if (piece.primitives.empty()) return original_[i];
        // The first guess: the nearest point of the primitives that touched the vertex in the
        // input (its place in the input if none is nearer). A vertex rarely strays beyond them,
        // so the search through the tree, which still finds any nearer point, prunes nearly all
        // of it. The guess depends on v and p only: owners and ghosts project alike.
        Kernel::Point_3 guess(original_[i][0], original_[i][1], original_[i][2]);
        double nearest_squared = CGAL::squared_distance(q, guess);
        const auto projected = Kernel().construct_projected_point_3_object();
        for (auto k = star_start_[i]; k < star_start_[i + 1]; ++k) {
            const auto candidate = projected(piece.primitives[static_cast<std::size_t>(star_[static_cast<std::size_t>(k)])], q);
            const double squared = CGAL::squared_distance(q, candidate);
            if (squared < nearest_squared) {
                nearest_squared = squared;
                guess = candidate;
            }
        }
        const auto r = piece.tree.closest_point(q, guess);
        return Vec3{r.x(), r.y(), r.z()};
    };
    switch (role(v)) {
        case BoundaryRole::Interior: return p;
        case BoundaryRole::Surface:
            if (domain_.analytic()) return domain_.nearest(p);
            return nearest(*trees_->patches[static_cast<std::size_t>(piece_[i])]);
        case BoundaryRole::Curve: {
            const Vec3 q = nearest(*trees_->curves[static_cast<std::size_t>(piece_[i])]);
            return domain_.analytic() ? domain_.nearest(q) : q;
        }
        case BoundaryRole::Corner: return original_[i];
    }
    return p;
}

Vec3 BoundarySurface::tangent(VertexId v, const Vec3& d) const {
    const BoundaryRole r = role(v);
    if (r == BoundaryRole::Interior) return d;
    const Vec3& u = direction_[static_cast<std::size_t>(index_[static_cast<std::size_t>(v)])];
    const double along = dot(d, u);
    switch (r) {
        case BoundaryRole::Interior: return d;
        case BoundaryRole::Surface: return {d[0] - along * u[0], d[1] - along * u[1], d[2] - along * u[2]};
        case BoundaryRole::Curve: return {along * u[0], along * u[1], along * u[2]};
        case BoundaryRole::Corner: return {0.0, 0.0, 0.0};
    }
    return d;
}

double BoundarySurface::distance(const Vec3& p) const {
    if (domain_.analytic()) return domain_.distance(p);
    const Kernel::Point_3 q(p[0], p[1], p[2]);
    const auto& faces = trees_->all_faces;
    const auto& edges = trees_->all_edges;
    if (!faces.primitives.empty()) return std::sqrt(faces.tree.squared_distance(q));
    if (!edges.primitives.empty()) return std::sqrt(edges.tree.squared_distance(q));
    return std::numeric_limits<double>::infinity();
}

std::size_t BoundarySurface::count(BoundaryRole r) const {
    std::size_t count = 0;
    for (std::size_t v = 0; v < index_.size(); ++v) count += role(static_cast<VertexId>(v)) == r;
    return count;
}

}  // namespace paloverde
