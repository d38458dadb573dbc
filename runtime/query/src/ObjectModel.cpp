#include "tetrapage/runtime/query/ObjectModel.h"

#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <string>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/formats/mesh/SurfaceComponents.h"
#include "tetrapage/runtime/geometry/ConvexHull.h"
#include "tetrapage/runtime/geometry/Predicates.h"

namespace tetrapage {
namespace {

using hull::distinct_triangle_vertices;
using hull::facet_planes;
using hull::hull_of;
using hull::Kernel;
using hull::to_point;

// Hill-climbing pays off on objects with many hull vertices; tiny ones are placed whole.
constexpr std::size_t kHillClimbMinimum = 32;
// Hulls of at most this many facets also prune by their planes (ObjectModel::hull_planes).
constexpr std::size_t kPruningPlanes = 24;

// The hull's vertex graph of a model (ObjectModel::hull_vertices, hull_offsets, hull_neighbours).
void build_hull_graph(ObjectModel& model, const TriangleSoup& object) {
  // The hull's vertex graph, for hill-climbing the world box. Vertices not on any triangle
  // do not matter; a flat object has no 3D hull and is placed whole.
  std::vector<Kernel::Point_3> points;
  std::map<std::array<double, 3>, std::uint32_t> id_of;
  distinct_triangle_vertices(object, points, id_of);
  bool few_facets = points.size() < kHillClimbMinimum;
  if (points.size() >= kHillClimbMinimum) {
    CGAL::Surface_mesh<Kernel::Point_3> hull;
    CGAL::convex_hull_3(points.begin(), points.end(), hull);
    few_facets = hull.number_of_faces() <= kPruningPlanes;
    if (hull.number_of_faces() > 0) {
      std::map<CGAL::Surface_mesh<Kernel::Point_3>::Vertex_index, std::uint32_t> position;
      for (const auto v : hull.vertices()) {
        const auto& p = hull.point(v);
        position[v] = std::uint32_t(model.hull_vertices.size());
        model.hull_vertices.push_back(id_of.at({p.x(), p.y(), p.z()}));
      }
      model.hull_offsets.push_back(0);
      for (const auto v : hull.vertices()) {
        for (const auto h : CGAL::halfedges_around_target(hull.halfedge(v), hull))
          model.hull_neighbours.push_back(position.at(hull.source(h)));
        model.hull_offsets.push_back(std::uint32_t(model.hull_neighbours.size()));
      }
    }
  }
  if (model.hull_vertices.empty()) {
    // No usable hull: every vertex, no graph (world_box scans them all).
    for (const auto& [point, id] : id_of) model.hull_vertices.push_back(id);
  }
  if (few_facets && points.size() >= 4) {
    // A hull of few facets prunes cheaply: what lies beyond one of its planes misses the
    // object. Only for a hull with volume (its centre well inside every plane).
    std::vector<Kernel::Point_3> hull_points;
    std::vector<std::array<std::size_t, 3>> faces;
    hull_of(points, hull_points, faces);
    if (faces.size() <= kPruningPlanes) {
      auto planes = facet_planes(hull_points, faces);
      Vec3 centre{0, 0, 0};
      for (const auto& p : hull_points)
        for (int a = 0; a < 3; ++a) centre[a] += to_point(p)[a] / double(hull_points.size());
      const bool solid =
          !planes.empty() && std::all_of(planes.begin(), planes.end(), [&](const auto& plane) {
            const auto& [n, offset] = plane;
            return offset - (n[0] * centre[0] + n[1] * centre[1] + n[2] * centre[2]) >
                   1e-9 * model.radius;
          });
      if (solid) model.hull_planes = std::move(planes);
    }
  }
}

// Whether the triangle's corners are collinear (exactly: its three projections have zero
// signed area), so that it has no area and no normal.
bool zero_area(const TriangleSoup& soup, std::size_t t) {
  const auto& a = soup.vertices[soup.triangles[t][0]];
  const auto& b = soup.vertices[soup.triangles[t][1]];
  const auto& c = soup.vertices[soup.triangles[t][2]];
  for (int u = 0; u < 3; ++u) {
    const int v = (u + 1) % 3;
    if (geometry::orient2d_cgal(a[u], a[v], b[u], b[v], c[u], c[v]) != geometry::Sign::zero)
      return false;
  }
  return true;
}

// Coordinates whose placement cannot overflow. Checked before the BVH is built: its boxes and
// centroids overflow too for coordinates near DBL_MAX (an infinite centroid put a triangle in
// bin INT_MIN: a crash).
TriangleSoup within_coordinate_limit(TriangleSoup soup) {
  // An infinite one is left to the BVH, which names every non-finite coordinate alike.
  if (const CoordinateBeyondLimit beyond = find_coordinate_beyond_limit(soup);
      beyond.found && std::isfinite(beyond.value)) {
    char text[200];
    std::snprintf(text, sizeof text,
                  "object: vertex %zu has coordinate %c = %g, beyond %g in magnitude: placing it "
                  "by a pose could overflow",
                  beyond.vertex, "xyz"[beyond.axis], beyond.value, kMaxCoordinateMagnitude);
    throw InputError(text);
  }
  return soup;
}

// What the BVH does not check but placing needs: some triangle with an area (a wholly
// degenerate object has no hull, normal or inside, and its queries would fail later on NaN
// points).
void check_placeable(const TriangleSoup& soup) {
  for (std::size_t t = 0; t < soup.triangle_count(); ++t)
    if (!zero_area(soup, t)) return;
  throw InputError(
      "object: all " + std::to_string(soup.triangle_count()) +
      " triangles have zero area (collinear or repeated corners): the object is degenerate");
}

}  // namespace

ObjectModel::ObjectModel(TriangleSoup object)
    : mesh(within_coordinate_limit(std::move(object))), bvh(mesh) {
  check_placeable(mesh);  // after the BVH, which checked the indices and finiteness
  for (const auto& v : mesh.vertices) {
    radius = std::max(radius, std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]));
    box.extend(v);
  }
  if (!mesh.vertices.empty()) {
    double farthest = 0;
    for (int a = 0; a < 3; ++a) ball_centre[a] = 0.5 * (box.lo[a] + box.hi[a]);
    for (const auto& v : mesh.vertices) {
      const double dx = v[0] - ball_centre[0], dy = v[1] - ball_centre[1],
                   dz = v[2] - ball_centre[2];
      farthest = std::max(farthest, dx * dx + dy * dy + dz * dz);
    }
    // Up by far more than the roundings of the squares and the root.
    ball_radius = std::sqrt(farthest) * (1 + 0x1p-40);
    const double ball_volume =
        4.0 / 3.0 * std::numbers::pi * ball_radius * ball_radius * ball_radius;
    const double box_volume =
        (box.hi[0] - box.lo[0]) * (box.hi[1] - box.lo[1]) * (box.hi[2] - box.lo[2]);
    ball_prunes = ball_volume < 0.7 * box_volume;
  }
  // The interior grid and the hull are independent: build them side by side (opening an
  // index and placing a large object must take milliseconds).
  tbb::parallel_invoke(
      [&] {
        const SurfaceComponents components = find_surface_components(mesh);
        std::vector<std::uint32_t> closed_index(components.components.size(),
                                                ClosedComponentOf::kOpen);
        for (std::size_t c = 0; c < components.components.size(); ++c) {
          const SurfaceComponent& component = components.components[c];
          component_vertices.push_back(mesh.triangles[component.first_triangle][0]);
          if (component.closed) closed_index[c] = closed_components.count++;
        }
        closed_components.of_triangle.resize(mesh.triangle_count());
        for (std::size_t t = 0; t < mesh.triangle_count(); ++t)
          closed_components.of_triangle[t] = closed_index[components.component_of[t]];
        closed = closed_components.count > 0;
        if (closed) interior_grid = ObjectInteriorGrid(bvh, closed_components);
      },
      [&] { build_hull_graph(*this, mesh); });
}

const ObjectModel::HullCandidates& ObjectModel::hull_candidates() const {
  std::call_once(hull_candidates_once_, [this] {
    std::vector<Kernel::Point_3> points;
    std::map<std::array<double, 3>, std::uint32_t> id_of;
    distinct_triangle_vertices(mesh, points, id_of);
    std::vector<Kernel::Point_3> hull_points;
    std::vector<std::array<std::size_t, 3>> faces;
    if (points.size() >= 4) hull_of(points, hull_points, faces);
    // Outward unit normals of a hull with volume; a flat or tiny object keeps every vertex.
    const std::vector<std::pair<Vec3, double>> planes = facet_planes(hull_points, faces);
    std::vector<bool> on_hull(mesh.vertices.size(), false);
    for (const auto& p : hull_points) {
      const std::uint32_t id = id_of.at({p.x(), p.y(), p.z()});
      on_hull[id] = true;
      hull_candidates_.on_hull.push_back(id);
    }
    for (const auto& [point, id] : id_of) {
      if (on_hull[id]) continue;
      // The distance to the hull's boundary: the nearest facet plane (0 without a 3D hull).
      double depth = planes.empty() ? 0.0 : 1e300;
      for (const auto& [n, offset] : planes)
        depth = std::min(depth, offset - (n[0] * point[0] + n[1] * point[1] + n[2] * point[2]));
      hull_candidates_.near_hull.emplace_back(std::max(depth, 0.0), id);
    }
    std::sort(hull_candidates_.near_hull.begin(), hull_candidates_.near_hull.end());
  });
  return hull_candidates_;
}

}  // namespace tetrapage
