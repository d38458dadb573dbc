#include "tetrapage/tools/ObjectGenerator.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Count_stop_predicate.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>
#include <CGAL/boost/graph/helpers.h>
#include <CGAL/subdivision_method_3.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <string>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/tools/Random.h"

namespace tetrapage {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;
namespace PMP = CGAL::Polygon_mesh_processing;
namespace SMS = CGAL::Surface_mesh_simplification;

// A simplified mesh may miss the request by this fraction (plus a collapse's two faces).
constexpr double count_tolerance = 0.05;

TriangleSoup single_part(std::vector<Vec3> vertices, std::vector<TriangleIndices> triangles,
                         const std::string& name) {
  TriangleSoup soup;
  soup.vertices = std::move(vertices);
  soup.triangles = std::move(triangles);
  soup.part_of.assign(soup.triangles.size(), 0);
  soup.part_names = {name};
  return soup;
}

// Uniform scale and translation: the bounding box's longest side becomes `size`, its centre
// the origin.
void fit_to_cube(TriangleSoup& soup, double size) {
  const BoundingBox box = soup.bounds();
  const Vec3 extent = box.size();
  const double longest = std::max({extent[0], extent[1], extent[2]});
  const double scale = longest > 0.0 ? size / longest : 1.0;
  const Vec3 centre = box.center();
  for (auto& v : soup.vertices)
    for (int a = 0; a < 3; ++a) v[a] = (v[a] - centre[a]) * scale;
}

TriangleSoup tetrahedron() {
  // Alternate corners of the cube [-1,1]^3; (0,1,2,3) is positively oriented, and each face
  // omits one corner and faces away from it.
  return single_part({{1, 1, 1}, {-1, 1, -1}, {1, -1, -1}, {-1, -1, 1}},
                     {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}, "tetrahedron");
}

TriangleSoup uv_sphere(std::size_t slices, std::size_t stacks, const std::string& name) {
  std::vector<Vec3> vertices;
  vertices.push_back({0.0, 0.0, 1.0});
  for (std::size_t k = 1; k < stacks; ++k) {
    const double polar = std::numbers::pi * double(k) / double(stacks);
    for (std::size_t j = 0; j < slices; ++j) {
      const double azimuth = 2.0 * std::numbers::pi * double(j) / double(slices);
      vertices.push_back({std::sin(polar) * std::cos(azimuth), std::sin(polar) * std::sin(azimuth),
                          std::cos(polar)});
    }
  }
  vertices.push_back({0.0, 0.0, -1.0});
  const auto north = std::uint32_t{0};
  const auto south = static_cast<std::uint32_t>(vertices.size() - 1);
  const auto ring = [slices](std::size_t k, std::size_t j) {  // k in [1, stacks-1]
    return static_cast<std::uint32_t>(1 + (k - 1) * slices + j % slices);
  };
  // Counter-clockwise seen from outside: the north fan runs with increasing azimuth.
  std::vector<TriangleIndices> triangles;
  for (std::size_t j = 0; j < slices; ++j) triangles.push_back({north, ring(1, j), ring(1, j + 1)});
  for (std::size_t k = 1; k + 1 < stacks; ++k)
    for (std::size_t j = 0; j < slices; ++j) {
      const auto a = ring(k, j), b = ring(k, j + 1), c = ring(k + 1, j + 1), d = ring(k + 1, j);
      triangles.push_back({b, a, d});
      triangles.push_back({b, d, c});
    }
  for (std::size_t j = 0; j < slices; ++j)
    triangles.push_back({south, ring(stacks - 1, j + 1), ring(stacks - 1, j)});
  return single_part(std::move(vertices), std::move(triangles), name);
}

// Why a mesh could not be used; empty on success.
std::string to_surface_mesh(const TriangleSoup& soup, SurfaceMesh& mesh) {
  std::vector<Point> points;
  points.reserve(soup.vertices.size());
  for (const auto& v : soup.vertices) points.emplace_back(v[0], v[1], v[2]);
  std::vector<std::vector<std::size_t>> polygons;
  polygons.reserve(soup.triangles.size());
  for (const auto& t : soup.triangles) polygons.push_back({t[0], t[1], t[2]});
  try {
    PMP::repair_polygon_soup(points, polygons);
    // Vertices shared in a non-manifold way are duplicated here, so the mesh is valid.
    PMP::orient_polygon_soup(points, polygons);
    PMP::polygon_soup_to_polygon_mesh(points, polygons, mesh);
  } catch (const std::exception& e) {
    return std::string("polygon soup could not become a mesh: ") + e.what();
  }
  if (mesh.number_of_faces() == 0) return "no face left after repairing the polygon soup";
  if (!CGAL::is_triangle_mesh(mesh)) return "not a triangle mesh";
  if (!CGAL::is_valid_polygon_mesh(mesh)) return "not a valid polygon mesh";
  if (CGAL::is_closed(mesh)) PMP::orient(mesh);  // each component outward
  return {};
}

TriangleSoup to_soup(SurfaceMesh& mesh, const std::string& name) {
  mesh.collect_garbage();
  std::vector<Vec3> vertices;
  vertices.reserve(mesh.number_of_vertices());
  for (auto v : mesh.vertices()) {
    const Point& p = mesh.point(v);
    vertices.push_back({p.x(), p.y(), p.z()});
  }
  std::vector<TriangleIndices> triangles;
  triangles.reserve(mesh.number_of_faces());
  for (auto f : mesh.faces()) {
    // The face lies to the left of its halfedges: targets in this order are counter-clockwise.
    const auto h = mesh.halfedge(f);
    const auto corner = [&](SurfaceMesh::Halfedge_index e) {
      return static_cast<std::uint32_t>(mesh.target(e).idx());
    };
    triangles.push_back({corner(h), corner(mesh.next(h)), corner(mesh.next(mesh.next(h)))});
  }
  return single_part(std::move(vertices), std::move(triangles), name);
}

// Candidate library meshes in the order they are tried: those with at least `triangles`
// (closest first, or shuffled by the seed), then the smaller ones, largest first (they need
// subdividing).
std::vector<std::size_t> candidate_order(const MeshLibrary& library, std::uint64_t triangles,
                                         const std::optional<std::uint64_t>& seed) {
  std::vector<std::size_t> large, small;
  for (std::size_t m = 0; m < library.size(); ++m)
    (library[m].triangle_count() >= triangles ? large : small).push_back(m);
  const auto by_count = [&](std::size_t a, std::size_t b) {
    return library[a].triangle_count() < library[b].triangle_count();
  };
  std::stable_sort(large.begin(), large.end(), by_count);
  std::stable_sort(small.begin(), small.end(), by_count);
  std::reverse(small.begin(), small.end());
  if (seed) {
    Random random(*seed);
    for (std::size_t i = 0; i + 1 < large.size(); ++i)
      std::swap(large[i], large[i + random.below(large.size() - i)]);
  }
  large.insert(large.end(), small.begin(), small.end());
  return large;
}

// Simplifies `mesh` to about `target` faces; why it failed, or empty.
std::string simplify(SurfaceMesh& mesh, std::uint64_t target, int& subdivisions) {
  subdivisions = 0;
  try {
    // Loop subdivision multiplies the face count by 4.
    while (mesh.number_of_faces() < target) {
      CGAL::Subdivision_method_3::Loop_subdivision(mesh, CGAL::parameters::number_of_iterations(1));
      ++subdivisions;
    }
    if (mesh.number_of_faces() > target) {
      // The stop predicate counts edges: aim at the edges that `target` faces of this mesh
      // have (3/2 per face when closed) and stop as soon as the count drops to it.
      const double edges_per_face = double(mesh.number_of_edges()) / double(mesh.number_of_faces());
      const auto edge_target =
          static_cast<std::size_t>(std::llround(edges_per_face * double(target)));
      SMS::Count_stop_predicate<SurfaceMesh> stop(edge_target + 1);
      SMS::edge_collapse(mesh, stop);
    }
  } catch (const std::exception& e) {
    return std::string("simplification failed: ") + e.what();
  }
  const double faces = double(mesh.number_of_faces());
  if (std::abs(faces - double(target)) > count_tolerance * double(target) + 2.0)
    return "simplification stopped at " + std::to_string(mesh.number_of_faces()) +
           " triangles, asked " + std::to_string(target);
  if (!CGAL::is_valid_polygon_mesh(mesh)) return "simplification left an invalid mesh";
  return {};
}

void check_options(const ObjectOptions& options) {
  if (options.triangles == 0 || options.triangles > max_object_triangles)
    throw InputError("object: --triangles " + std::to_string(options.triangles) +
                     " is out of range [1, " + std::to_string(max_object_triangles) + "]");
  if (!(options.size > 0.0) || !std::isfinite(options.size))
    throw InputError("object: size " + std::to_string(options.size) + " must be positive");
}

bool closed_soup(const TriangleSoup& soup) {
  // Every directed edge must appear once and its reverse once.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
  edges.reserve(3 * soup.triangles.size());
  for (const auto& t : soup.triangles)
    for (int i = 0; i < 3; ++i) edges.emplace_back(t[i], t[(i + 1) % 3]);
  std::sort(edges.begin(), edges.end());
  if (std::adjacent_find(edges.begin(), edges.end()) != edges.end()) return false;
  for (const auto& [a, b] : edges)
    if (!std::binary_search(edges.begin(), edges.end(), std::make_pair(b, a))) return false;
  return true;
}

}  // namespace

std::pair<std::size_t, std::size_t> uv_sphere_resolution(std::uint64_t triangles) {
  std::pair<std::size_t, std::size_t> best{3, 2};
  double best_cost = 1e300;
  const double wanted = double(std::max<std::uint64_t>(triangles, 1));
  // Round spheres have slices ~ 2 stacks, i.e. stacks ~ sqrt(triangles / 4): searching up to
  // twice sqrt(triangles) stacks, and for each the two slice counts around the request,
  // covers every pair the cost below could prefer.
  const auto last_stacks = static_cast<std::size_t>(2.0 * std::sqrt(wanted)) + 3;
  for (std::size_t stacks = 2; stacks <= last_stacks; ++stacks) {
    const double ideal = wanted / double(2 * (stacks - 1));
    const auto below = static_cast<std::size_t>(std::floor(ideal));
    for (std::size_t slices : {below, below + 1}) {
      if (slices < 3) continue;
      const double count = double(2 * slices * (stacks - 1));
      const double aspect = std::log(double(slices) / double(2 * stacks));
      // The count matters most; among nearly equal counts take the rounder sphere.
      const double cost = std::abs(count - wanted) / wanted + 0.05 * std::abs(aspect);
      if (cost < best_cost) {
        best_cost = cost;
        best = {slices, stacks};
      }
    }
  }
  return best;
}

GeneratedObject generate_object(const ObjectOptions& options, const MeshLibrary* library) {
  check_options(options);
  GeneratedObject object;
  if (options.triangles <= 4) {
    object.soup = tetrahedron();
    object.source = "tetrahedron";
  } else if (!object_needs_meshes(options.triangles)) {
    const auto [slices, stacks] = uv_sphere_resolution(options.triangles);
    object.source = "uv-sphere " + std::to_string(slices) + "x" + std::to_string(stacks);
    object.soup = uv_sphere(slices, stacks, object.source);
  } else {
    if (library == nullptr)
      throw InputError("object: " + std::to_string(options.triangles) +
                       " triangles need a real mesh, and no mesh library was given");
    const std::vector<std::size_t> order =
        candidate_order(*library, options.triangles, options.seed);
    // Closed meshes first: an open object has no inside, so the study's "object inside an
    // obstacle" test and the convex-hull box updates mean less for it.
    std::vector<bool> given_up(library->size(), false);
    for (const bool want_closed : {true, false}) {
      for (std::size_t m : order) {
        if (given_up[m]) continue;
        const LibraryMesh& source = (*library)[m];
        SurfaceMesh mesh;
        if (std::string why = to_surface_mesh(source.soup, mesh); !why.empty()) {
          object.rejected.push_back(source.name + ": " + why);
          given_up[m] = true;
          continue;
        }
        const bool closed = CGAL::is_closed(mesh);
        if (closed != want_closed) continue;
        const std::size_t before = mesh.number_of_faces();
        int subdivisions = 0;
        if (std::string why = simplify(mesh, options.triangles, subdivisions); !why.empty()) {
          object.rejected.push_back(source.name + ": " + why);
          given_up[m] = true;
          continue;
        }
        object.source = source.name;
        if (subdivisions > 0)
          object.source += " subdivided " + std::to_string(subdivisions) + " times,";
        object.source +=
            mesh.number_of_faces() == before && subdivisions == 0 ? " as is" : " simplified";
        object.source_triangles = source.triangle_count();
        object.soup = to_soup(mesh, source.name);
        break;
      }
      if (!object.soup.triangles.empty()) break;
    }
    if (object.soup.triangles.empty()) {
      std::string message = "object: no mesh of the library could be simplified to " +
                            std::to_string(options.triangles) + " triangles";
      for (const auto& reason : object.rejected) message += "; " + reason;
      throw InputError(message);
    }
  }
  if (object.source_triangles == 0) object.source_triangles = object.soup.triangle_count();
  fit_to_cube(object.soup, options.size);
  object.closed = closed_soup(object.soup);
  return object;
}

}  // namespace tetrapage
