#include "tetrapage/runtime/paging/TetBoxFilter.h"

#include <algorithm>
#include <cmath>

#include "tetrapage/runtime/geometry/FloatRounding.h"
#include "tetrapage/runtime/geometry/PointTetrahedron.h"

namespace tetrapage {

double TetBoxFilter::magnitude(const geometry::Box& box) {
  return std::max({std::fabs(box.lo[0]), std::fabs(box.lo[1]), std::fabs(box.lo[2]), std::fabs(box.hi[0]),
                   std::fabs(box.hi[1]), std::fabs(box.hi[2])});
}

TetBoxFilter::TetBoxFilter(const TetMesh& mesh) {
  bounds_.resize(mesh.tet_count());
  planes_.resize(mesh.tet_count());
  for (std::uint32_t t = 0; t < mesh.tet_count(); ++t) {
    bounds_[t] = geometry::FloatBox::enclosing(mesh.bounds(t));
    const geometry::Tetrahedron corners = mesh.corners(t);
    double corner_magnitude = 0;
    for (const auto& p : corners)
      for (int a = 0; a < 3; ++a) corner_magnitude = std::max(corner_magnitude, std::fabs(p[a]));
    Planes& planes = planes_[t];
    for (int k = 0; k < 4; ++k) {
      const auto& f = geometry::kTetrahedronFaces[k];
      const geometry::Point& a = corners[f[0]];
      const geometry::Point u{corners[f[1]][0] - a[0], corners[f[1]][1] - a[1], corners[f[1]][2] - a[2]};
      const geometry::Point v{corners[f[2]][0] - a[0], corners[f[2]][1] - a[1], corners[f[2]][2] - a[2]};
      geometry::Point n{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
      const geometry::Point& opposite = corners[k];
      if (n[0] * (opposite[0] - a[0]) + n[1] * (opposite[1] - a[1]) + n[2] * (opposite[2] - a[2]) < 0)
        n = {-n[0], -n[1], -n[2]};
      const double size = std::fabs(n[0]) + std::fabs(n[1]) + std::fabs(n[2]);
      for (int i = 0; i < 3; ++i) planes.normal[i][k] = size > 0 ? float(n[i] / size) : 0.0f;
      // The smallest value over the corners bounds it over the tet (their convex hull).
      double lowest = INFINITY;
      for (const auto& p : corners)
        lowest = std::min(lowest, double(planes.normal[0][k]) * p[0] + double(planes.normal[1][k]) * p[1] +
                                      double(planes.normal[2][k]) * p[2]);
      planes.offset[k] = geometry::float_below(lowest - corner_magnitude * kRelativeMargin);
    }
  }
}

}  // namespace tetrapage
