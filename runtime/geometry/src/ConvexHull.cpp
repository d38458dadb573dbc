#include "tetrapage/runtime/geometry/ConvexHull.h"

#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>

#include <cmath>

namespace tetrapage::hull {

// Through a Surface_mesh: CGAL 5.5's indexed-triangle-set output crashed on some inputs.
void hull_of(const std::vector<Kernel::Point_3>& points, std::vector<Kernel::Point_3>& vertices,
             std::vector<std::array<std::size_t, 3>>& faces) {
  CGAL::Surface_mesh<Kernel::Point_3> hull;
  CGAL::convex_hull_3(points.begin(), points.end(), hull);
  vertices.clear();
  faces.clear();
  for (const auto v : hull.vertices()) vertices.push_back(hull.point(v));
  for (const auto f : hull.faces()) {
    std::array<std::size_t, 3> corners{};
    int k = 0;
    for (const auto v : CGAL::vertices_around_face(hull.halfedge(f), hull)) {
      if (k == 3) break;
      corners[k++] = std::size_t(v.idx());
    }
    if (k == 3) faces.push_back(corners);
  }
}

void distinct_triangle_vertices(const TriangleSoup& object, std::vector<Kernel::Point_3>& points,
                                std::map<std::array<double, 3>, std::uint32_t>& id_of) {
  for (const auto& t : object.triangles)
    for (const auto v : t)
      if (id_of.emplace(object.vertices[v], v).second)
        points.emplace_back(object.vertices[v][0], object.vertices[v][1], object.vertices[v][2]);
}

std::vector<std::pair<Vec3, double>> facet_planes(
    const std::vector<Kernel::Point_3>& hull_points,
    const std::vector<std::array<std::size_t, 3>>& faces) {
  std::vector<std::pair<Vec3, double>> planes;
  if (faces.empty()) return planes;
  Vec3 centre{0, 0, 0};
  for (const auto& p : hull_points)
    for (int a = 0; a < 3; ++a) centre[a] += to_point(p)[a] / double(hull_points.size());
  for (const auto& f : faces) {
    const geometry::Point a = to_point(hull_points[f[0]]), b = to_point(hull_points[f[1]]),
                          c = to_point(hull_points[f[2]]);
    const Vec3 u{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    Vec3 n{u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
    const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(length > 0)) continue;
    for (auto& x : n) x /= length;
    double offset = n[0] * a[0] + n[1] * a[1] + n[2] * a[2];
    if (n[0] * centre[0] + n[1] * centre[1] + n[2] * centre[2] > offset) {
      for (auto& x : n) x = -x;
      offset = -offset;
    }
    planes.push_back({n, offset});
  }
  return planes;
}

}  // namespace tetrapage::hull
