// paloverde_surface_tool: CGAL's surface smoothers and two surface measures, the baseline that
// examples/surface_study.py holds `paloverde improve` against on triangle surface meshes.
//
//   paloverde_surface_tool smooth IN.off OUT.off [--iterations N] [--method angle_area|tangential]
//                                                [--feature-angle DEG]
//   paloverde_surface_tool distance INPUT.off OUT.off     largest distance of OUT's vertices to INPUT
//   paloverde_surface_tool project SURFACE.off IN.off OUT.off   IN's vertices moved onto SURFACE
//
// Every output keeps its input's vertex order and (for smooth) its connectivity, so that a caller
// can compare vertex by vertex and triangle by triangle.
#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/angle_and_area_smoothing.h>
#include <CGAL/Polygon_mesh_processing/bbox.h>
#include <CGAL/Polygon_mesh_processing/detect_features.h>
#include <CGAL/Polygon_mesh_processing/tangential_relaxation.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/IO/polygon_mesh_io.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
using Vertex = Mesh::Vertex_index;
using Edge = Mesh::Edge_index;
using Primitive = CGAL::AABB_face_graph_triangle_primitive<Mesh>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;
namespace PMP = CGAL::Polygon_mesh_processing;

constexpr const char* kUsage =
    "usage: paloverde_surface_tool smooth IN.off OUT.off [--iterations N] [--method angle_area|tangential]"
    " [--feature-angle DEG]\n"
    "       paloverde_surface_tool distance INPUT.off OUT.off\n"
    "       paloverde_surface_tool project SURFACE.off IN.off OUT.off\n";

Mesh read_mesh(const std::string& path) {
  Mesh mesh;
  if (!CGAL::IO::read_polygon_mesh(path, mesh) || mesh.is_empty())
    throw std::runtime_error(path + ": could not read a polygon mesh");
  if (!CGAL::is_triangle_mesh(mesh)) throw std::runtime_error(path + ": not a triangle mesh");
  return mesh;
}

void write_mesh(const std::string& path, const Mesh& mesh) {
  // 17 digits: the caller measures displacements of fixed vertices, which must read back as 0.
  if (!CGAL::IO::write_polygon_mesh(path, mesh, CGAL::parameters::stream_precision(17)))
    throw std::runtime_error(path + ": could not write");
}

double bbox_diagonal(const Mesh& mesh) {
  const CGAL::Bbox_3 box = PMP::bbox(mesh);
  return std::sqrt(CGAL::square(box.xmax() - box.xmin()) + CGAL::square(box.ymax() - box.ymin()) +
                   CGAL::square(box.zmax() - box.zmin()));
}

int smooth(const std::vector<std::string>& args) {
  if (args.size() < 2) throw std::invalid_argument("smooth needs IN.off OUT.off");
  unsigned iterations = 1;
  std::string method = "angle_area";
  double feature_angle = 60.0;
  for (std::size_t i = 2; i < args.size(); ++i) {
    if (i + 1 >= args.size()) throw std::invalid_argument(args[i] + " needs a value");
    if (args[i] == "--iterations")
      iterations = static_cast<unsigned>(std::stoul(args[++i]));
    else if (args[i] == "--method")
      method = args[++i];
    else if (args[i] == "--feature-angle")
      feature_angle = std::stod(args[++i]);
    else
      throw std::invalid_argument("unknown option " + args[i]);
  }
  if (method != "angle_area" && method != "tangential") throw std::invalid_argument("unknown method " + method);

  Mesh mesh = read_mesh(args[0]);

  // Both smoothers freeze the vertices of constrained edges: sharp edges keep the part's corners and
  // crease lines, boundary edges keep an open surface's outline.
  auto is_constrained = mesh.add_property_map<Edge, bool>("e:constrained", false).first;
  PMP::detect_sharp_edges(mesh, feature_angle, is_constrained);
  std::size_t sharp = 0, border = 0;
  for (Edge e : mesh.edges()) {
    // detect_sharp_edges marks the border too; count it apart.
    if (mesh.is_border(e)) {
      is_constrained[e] = true;
      ++border;
    } else if (is_constrained[e]) {
      ++sharp;
    }
  }
  std::vector<bool> frozen(mesh.number_of_vertices(), false);
  for (Edge e : mesh.edges())
    if (is_constrained[e]) frozen[mesh.source(mesh.halfedge(e))] = frozen[mesh.target(mesh.halfedge(e))] = true;
  std::size_t moving = 0;
  for (Vertex v : mesh.vertices()) moving += frozen[v] ? 0 : 1;
  std::cout << "sharp edges " << sharp << " (feature angle " << feature_angle << " deg), boundary edges " << border
            << ", movable vertices " << moving << " of " << mesh.number_of_vertices() << "\n";

  const auto start = std::chrono::steady_clock::now();
  if (method == "angle_area") {
#ifndef CGAL_PMP_USE_CERES_SOLVER
    // Without Ceres CGAL drops area smoothing itself (and says so on stderr): ask for what runs.
    std::cout << "area smoothing off: this build has no Ceres; angle smoothing only\n";
    constexpr bool area = false;
#else
    constexpr bool area = true;
#endif
    // The Delaunay flips that follow area smoothing would change the connectivity, and the study
    // compares triangle by triangle with a method that only moves vertices.
    PMP::angle_and_area_smoothing(mesh, CGAL::parameters::number_of_iterations(iterations)
                                            .use_angle_smoothing(true)
                                            .use_area_smoothing(area)
                                            .use_Delaunay_flips(false)
                                            .use_safety_constraints(true)
                                            .do_project(true)
                                            .edge_is_constrained_map(is_constrained));
  } else {
    // CGAL 5.5's tangential_relaxation moves in each vertex's tangent plane but never projects
    // back (isotropic_remeshing does that itself), so curved surfaces would shrink: project onto
    // the input after each sweep, as angle_and_area_smoothing's do_project does.
    const Mesh input = mesh;
    Tree tree(faces(input).first, faces(input).second, input);
    tree.accelerate_distance_queries();
    for (unsigned i = 0; i < iterations; ++i) {
      PMP::tangential_relaxation(mesh,
                                 CGAL::parameters::number_of_iterations(1).edge_is_constrained_map(is_constrained));
      for (Vertex v : mesh.vertices())
        if (!frozen[v]) mesh.point(v) = tree.closest_point(mesh.point(v));
    }
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << "seconds " << seconds << "\n";
  write_mesh(args[1], mesh);
  return 0;
}

int distance(const std::vector<std::string>& args) {
  if (args.size() != 2) throw std::invalid_argument("distance needs INPUT.off OUT.off");
  const Mesh input = read_mesh(args[0]);
  const Mesh out = read_mesh(args[1]);
  Tree tree(faces(input).first, faces(input).second, input);
  tree.accelerate_distance_queries();
  double largest = 0.0;
  for (Vertex v : out.vertices()) largest = std::max(largest, tree.squared_distance(out.point(v)));
  largest = std::sqrt(largest);
  std::cout.precision(10);
  std::cout << "max_distance " << largest << "\n";
  std::cout << "relative " << largest / bbox_diagonal(input) << "\n";
  return 0;
}

int project(const std::vector<std::string>& args) {
  if (args.size() != 3) throw std::invalid_argument("project needs SURFACE.off IN.off OUT.off");
  const Mesh surface = read_mesh(args[0]);
  Mesh mesh = read_mesh(args[1]);
  Tree tree(faces(surface).first, faces(surface).second, surface);
  tree.accelerate_distance_queries();
  for (Vertex v : mesh.vertices()) mesh.point(v) = tree.closest_point(mesh.point(v));
  write_mesh(args[2], mesh);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << kUsage;
    return 2;
  }
  const std::string command = argv[1];
  const std::vector<std::string> args(argv + 2, argv + argc);
  try {
    if (command == "smooth") return smooth(args);
    if (command == "distance") return distance(args);
    if (command == "project") return project(args);
    if (command == "-h" || command == "--help") {
      std::cout << kUsage;
      return 0;
    }
    std::cerr << "unknown command " << command << "\n" << kUsage;
    return 2;
  } catch (const std::invalid_argument& error) {
    std::cerr << "paloverde_surface_tool: " << error.what() << "\n" << kUsage;
    return 2;
  } catch (const std::exception& error) {
    std::cerr << "paloverde_surface_tool: " << error.what() << "\n";
    return 1;
  }
}
