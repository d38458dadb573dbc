#include "tetrapage/preprocess/RayParity.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <string>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/runtime/geometry/Predicates.h"

namespace tetrapage {

using geometry::Point;
using geometry::Sign;
using geometry::Triangle;

namespace {

// orient2d(p, r, q') in the (x, y) plane for q' = q + (e, e^2): the exact sign, else the
// first nonzero term of its expansion e (p_y - r_y) + e^2 (r_x - p_x). Antisymmetric in (p, r),
// so two triangles sharing an edge put q' on opposite sides of it. Zero only when p and r
// project to one point.
Sign perturbed_orient2d(const Point& p, const Point& r, const Point& q) {
  const Sign s = geometry::orient2d(p[0], p[1], r[0], r[1], q[0], q[1]);
  if (s != Sign::zero) return s;
  if (p[1] != r[1]) return p[1] > r[1] ? Sign::positive : Sign::negative;
  if (r[0] != p[0]) return r[0] > p[0] ? Sign::positive : Sign::negative;
  return Sign::zero;
}

// q lies on the closed triangle t (exactly).
bool on_triangle(const Point& q, const Triangle& t) {
  if (geometry::orient3d(t[0], t[1], t[2], q) != Sign::zero) return false;
  // Coplanar: inside the closed triangle seen along an axis the triangle is not parallel to.
  for (int axis = 2; axis >= 0; --axis) {
    const Sign n = geometry::normal_sign(t[0], t[1], t[2], axis);
    if (n == Sign::zero) continue;
    const int i = axis == 2 ? 0 : axis + 1;
    const int j = axis == 0 ? 2 : axis - 1;
    for (int e = 0; e < 3; ++e) {
      const Point& p = t[e];
      const Point& r = t[e == 2 ? 0 : e + 1];
      if (geometry::orient2d(p[i], p[j], r[i], r[j], q[i], q[j]) == -n) return false;
    }
    return true;
  }
  // A degenerate triangle (a segment or a point): preprocess drops those before this.
  return false;
}

}  // namespace

VerticalRayCrossing vertical_ray_crossing(const Point& q, const Triangle& t) {
  const auto [min_z, max_z] = std::minmax({t[0][2], t[1][2], t[2][2]});
  if (q[2] > max_z) return VerticalRayCrossing::none;  // q' is above every point of t
  for (int k = 0; k < 2; ++k) {
    const auto [lo, hi] = std::minmax({t[0][k], t[1][k], t[2][k]});
    if (q[k] < lo || q[k] > hi) return VerticalRayCrossing::none;
  }
  if (q[2] >= min_z && on_triangle(q, t)) return VerticalRayCrossing::touches;
  // Seen from above, t has orientation s; a vertical triangle (s = 0) is never crossed by the
  // perturbed ray, which misses every line.
  const Sign s = geometry::normal_sign(t[0], t[1], t[2], 2);
  if (s == Sign::zero) return VerticalRayCrossing::none;
  for (int e = 0; e < 3; ++e)
    if (perturbed_orient2d(t[e], t[e == 2 ? 0 : e + 1], q) != s) return VerticalRayCrossing::none;
  // Inside the projection: crossed when q' is below the plane, on the side the normal (whose
  // z component has sign s) does not point to.
  if (q[2] < min_z) return VerticalRayCrossing::crosses;
  return geometry::orient3d_perturbed_query(t[0], t[1], t[2], q) == -s
             ? VerticalRayCrossing::crosses
             : VerticalRayCrossing::none;
}

RayParity::RayParity(std::span<const Point> points,
                     const std::vector<std::vector<std::uint32_t>>& points_of_part) {
  offsets_.assign(points_of_part.size() + 1, 0);
  for (std::size_t p = 0; p < points_of_part.size(); ++p)
    offsets_[p + 1] = offsets_[p] + points_of_part[p].size();
  const std::uint64_t pairs = offsets_.back();
  point_index_.resize(pairs);
  points_.resize(pairs);
  state_ = std::vector<std::atomic<std::uint8_t>>(pairs);
  for (std::size_t p = 0; p < points_of_part.size(); ++p) {
    const auto first = point_index_.begin() + std::ptrdiff_t(offsets_[p]);
    std::copy(points_of_part[p].begin(), points_of_part[p].end(), first);
    for (const std::uint32_t i : points_of_part[p])
      if (i >= points.size())
        throw InputError("point " + std::to_string(i) + " of part " + std::to_string(p) +
                         " is beyond the " + std::to_string(points.size()) + " points");
    std::sort(first, first + std::ptrdiff_t(points_of_part[p].size()),
              [&](std::uint32_t a, std::uint32_t b) {
                return points[a][0] < points[b][0] || (points[a][0] == points[b][0] && a < b);
              });
    for (std::uint64_t i = offsets_[p]; i < offsets_[p + 1]; ++i)
      points_[i] = points[point_index_[i]];
  }
}

void RayParity::add_triangle(std::uint32_t part, const Triangle& t) {
  if (!wanted(part)) return;
  const auto [lo, hi] = std::minmax({t[0][0], t[1][0], t[2][0]});
  const auto begin = points_.begin() + std::ptrdiff_t(offsets_[part]);
  const auto end = points_.begin() + std::ptrdiff_t(offsets_[part + 1]);
  auto it = std::lower_bound(begin, end, lo, [](const Point& q, double x) { return q[0] < x; });
  for (; it != end && (*it)[0] <= hi; ++it) {
    const VerticalRayCrossing crossing = vertical_ray_crossing(*it, t);
    if (crossing == VerticalRayCrossing::none) continue;
    const auto pair = std::size_t(it - points_.begin());
    if (crossing == VerticalRayCrossing::crosses)
      state_[pair].fetch_xor(kOdd, std::memory_order_relaxed);
    else
      state_[pair].fetch_or(kTouched, std::memory_order_relaxed);
  }
}

}  // namespace tetrapage
