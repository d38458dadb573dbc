#include "tetrapage/runtime/paging/BoxSearch.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/runtime/geometry/PointTetrahedron.h"
#include "tetrapage/runtime/geometry/Predicates.h"

namespace tetrapage {
namespace geometry {
namespace {

bool inverted(const Box& box) {
  return box.lo[0] > box.hi[0] || box.lo[1] > box.hi[1] || box.lo[2] > box.hi[2];
}

// The box corners extreme along a direction whose component signs are n: `highest` maximises
// the dot product, `lowest` minimises it (either bound where a component is zero).
void extreme_corners(const Box& box, const Sign n[3], Point& highest, Point& lowest) {
  for (int k = 0; k < 3; ++k) {
    highest[k] = n[k] == Sign::positive ? box.hi[k] : box.lo[k];
    lowest[k] = n[k] == Sign::positive ? box.lo[k] : box.hi[k];
  }
}

constexpr int kEdges[6][4] = {{0, 1, 2, 3}, {0, 2, 1, 3}, {0, 3, 1, 2},
                              {1, 2, 0, 3}, {1, 3, 0, 2}, {2, 3, 0, 1}};  // edge, then the others

// Face k's normal u x v (unnormalised, u and v its edges from its first corner) and
// |u|_1 |v|_1, which bounds the normal's size and its rounding (relative to |u| |v|, not to
// |n|, which is tiny for a sliver face).
struct FaceNormal {
  Point normal;
  double size;
};

FaceNormal face_normal(const Tetrahedron& t, int k) {
  const auto& f = kTetrahedronFaces[k];
  const Point& a = t[f[0]];
  const Point u{t[f[1]][0] - a[0], t[f[1]][1] - a[1], t[f[1]][2] - a[2]};
  const Point v{t[f[2]][0] - a[0], t[f[2]][1] - a[1], t[f[2]][2] - a[2]};
  return {{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]},
          (std::fabs(u[0]) + std::fabs(u[1]) + std::fabs(u[2])) * (std::fabs(v[0]) + std::fabs(v[1]) + std::fabs(v[2]))};
}

enum class Filtered : std::uint8_t { disjoint, meet, unsure };

// The separating-axis test in double: the tet's four face normals and its six edges times
// the three axes (the box's own axes are the caller's). An axis decides only where the
// intervals part, or overlap, by more than a bound far beyond the roundings, which are
// relative to |axis| |x - origin| (differences round relative to themselves); overlap on
// every axis means the closed sets meet only for a tet that is certainly not flat.
Filtered separating_axes_in_double(const Tetrahedron& t, const Box& box) {
  double scale = 0;
  for (const Point& p : t)
    for (int a = 0; a < 3; ++a) scale = std::max(scale, std::fabs(p[a] - t[0][a]));
  for (int a = 0; a < 3; ++a)
    scale = std::max({scale, std::fabs(box.lo[a] - t[0][a]), std::fabs(box.hi[a] - t[0][a])});
  bool sure_overlap = true;
  // `d` from tet vertex `origin`; `size` bounds |d|_1 including its own rounding's source.
  auto separates = [&](const Point& d, const Point& origin, double size) {
    double tet_lo = 0, tet_hi = 0;
    for (const Point& p : t) {
      const double x = d[0] * (p[0] - origin[0]) + d[1] * (p[1] - origin[1]) + d[2] * (p[2] - origin[2]);
      tet_lo = std::min(tet_lo, x), tet_hi = std::max(tet_hi, x);
    }
    double box_lo = 0, box_hi = 0;
    for (int a = 0; a < 3; ++a) {
      const double l = d[a] * (box.lo[a] - origin[a]), h = d[a] * (box.hi[a] - origin[a]);
      box_lo += std::min(l, h), box_hi += std::max(l, h);
    }
    const double bound = size * scale * 0x1p-40;
    if (box_lo > tet_hi + bound || tet_lo > box_hi + bound) return true;
    if (!(box_lo < tet_hi - bound && tet_lo < box_hi - bound)) sure_overlap = false;
    return false;
  };
  for (int k = 0; k < 4; ++k) {
    const Point& a = t[kTetrahedronFaces[k][0]];
    const auto [n, size] = face_normal(t, k);
    if (separates(n, a, size)) return Filtered::disjoint;
    // The opposite vertex far off the face's plane: the tet is not flat.
    const Point& o = t[k];
    const double height = n[0] * (o[0] - a[0]) + n[1] * (o[1] - a[1]) + n[2] * (o[2] - a[2]);
    if (!(std::fabs(height) > size * scale * 0x1p-40)) sure_overlap = false;
  }
  for (const auto& e : kEdges) {
    const Point& p = t[e[0]];
    const Point edge{t[e[1]][0] - p[0], t[e[1]][1] - p[1], t[e[1]][2] - p[2]};
    const double size = std::fabs(edge[0]) + std::fabs(edge[1]) + std::fabs(edge[2]);
    // edge x (unit axis k)
    if (separates({0, edge[2], -edge[1]}, p, size) || separates({-edge[2], 0, edge[0]}, p, size) ||
        separates({edge[1], -edge[0], 0}, p, size))
      return Filtered::disjoint;
  }
  return sure_overlap ? Filtered::meet : Filtered::unsure;
}

}  // namespace

bool tetrahedron_intersects_box(const Tetrahedron& t, const Box& box) {
  if (inverted(box) || !boxes_overlap(box_of(t), box)) return false;  // the box's axes
  for (const Point& v : t)
    if (box_contains(box, v)) return true;
  // Most tets are decided in double; near contact (touching, flat) the exact tests follow.
  switch (separating_axes_in_double(t, box)) {
    case Filtered::disjoint: return false;
    case Filtered::meet: return true;
    case Filtered::unsure: break;
  }

  const Sign orientation = orient3d(t[0], t[1], t[2], t[3]);
  if (orientation != Sign::zero) {
    // Face k: the box corner farthest towards the tet must not be strictly outside the face.
    for (int k = 0; k < 4; ++k) {
      const auto& f = kTetrahedronFaces[k];
      Sign inward[3];
      for (int a = 0; a < 3; ++a) inward[a] = normal_sign(t[f[0]], t[f[1]], t[f[2]], a) * orientation;
      Point highest, lowest;
      extreme_corners(box, inward, highest, lowest);
      if (orient3d(t[f[0]], t[f[1]], t[f[2]], highest) * orientation == Sign::negative) return false;
    }
  } else {
    // Flat: the tet is a planar polygon (or less), which either side of its plane can separate.
    for (int k = 0; k < 4; ++k) {
      const auto& f = kTetrahedronFaces[k];
      if (is_degenerate(t[f[0]], t[f[1]], t[f[2]])) continue;
      Sign normal[3];
      for (int a = 0; a < 3; ++a) normal[a] = normal_sign(t[f[0]], t[f[1]], t[f[2]], a);
      Point highest, lowest;
      extreme_corners(box, normal, highest, lowest);
      const OrientedPlane plane(t[f[0]], t[f[1]], t[f[2]]);
      if (plane.side(highest) == Sign::negative || plane.side(lowest) == Sign::positive)
        return false;
      break;
    }
  }

  // Edge times axis k: seen along axis k this is the 2D separating-axis test of the projected
  // tet (a convex polygon) against the projected box (a rectangle). Only hull edges of the
  // projection can separate, and only on the side away from the polygon; a projection that is
  // a segment can be separated on both sides.
  for (int k = 0; k < 3; ++k) {
    const int i = k == 2 ? 0 : k + 1;
    const int j = k == 0 ? 2 : k - 1;
    for (const auto& e : kEdges) {
      const Point& p = t[e[0]];
      const Point& q = t[e[1]];
      if (p[i] == q[i] && p[j] == q[j]) continue;  // the axis is zero
      const Sign r = orient2d(p[i], p[j], q[i], q[j], t[e[2]][i], t[e[2]][j]);
      const Sign s = orient2d(p[i], p[j], q[i], q[j], t[e[3]][i], t[e[3]][j]);
      if (r * s == Sign::negative) continue;  // not a hull edge of the projection
      const Sign side = r != Sign::zero ? r : s;
      // orient2d(p, q, x) grows with x along (-(q_j - p_j), q_i - p_i).
      const double max_i = q[j] < p[j] ? box.hi[i] : box.lo[i];
      const double max_j = q[i] > p[i] ? box.hi[j] : box.lo[j];
      const double min_i = q[j] < p[j] ? box.lo[i] : box.hi[i];
      const double min_j = q[i] > p[i] ? box.lo[j] : box.hi[j];
      if (side != Sign::negative &&
          orient2d(p[i], p[j], q[i], q[j], max_i, max_j) == Sign::negative)
        return false;
      if (side != Sign::positive &&
          orient2d(p[i], p[j], q[i], q[j], min_i, min_j) == Sign::positive)
        return false;
    }
  }
  return true;
}

}  // namespace geometry

namespace {

std::string format_box(const geometry::Box& box) {
  char buffer[200];
  std::snprintf(buffer, sizeof buffer, "[(%.17g, %.17g, %.17g), (%.17g, %.17g, %.17g)]",
                box.lo[0], box.lo[1], box.lo[2], box.hi[0], box.hi[1], box.hi[2]);
  return buffer;
}

}  // namespace

namespace {

// Breadth-first from start_tet through the tets `meets` accepts; those form a connected set
// when `meets` is exact (the tets meeting a convex box) or a superset of it (box overlaps).
template <bool kExact>
BoxSearchResult search(const TetMesh& mesh, const TetBoxFilter* filter, std::uint32_t start_tet,
                       const geometry::Box& box, std::vector<std::uint32_t>& stamps, std::uint32_t& stamp_counter,
                       std::vector<std::uint32_t>& found) {
  if (start_tet >= mesh.tet_count())
    throw InputError("box search: start tet " + std::to_string(start_tet) +
                     " is out of range (" + std::to_string(mesh.tet_count()) + " tets)");
  if (!geometry::is_finite(box.lo) || !geometry::is_finite(box.hi))
    throw InputError("box search: the box " + format_box(box) + " is not finite");
  found.clear();
  BoxSearchResult result;
  if (geometry::inverted(box)) return result;
  // The exact search has no filter: it computes the boxes. The filter's are floats, compared
  // with the box rounded outward to floats once.
  const geometry::FloatBox float_box = geometry::FloatBox::enclosing(box);
  const auto bounds_overlap = [&](std::uint32_t tet) {
    if constexpr (kExact) return geometry::boxes_overlap(mesh.bounds(tet), box);
    else return filter->bounds_overlap(tet, float_box);
  };
  const double box_magnitude = TetBoxFilter::magnitude(box);
  const auto meets = [&](std::uint32_t tet) {
    if constexpr (kExact) return geometry::tetrahedron_intersects_box(mesh.corners(tet), box);
    else return bounds_overlap(tet) && filter->planes_may_meet(tet, box, box_magnitude);
  };
  if (!meets(start_tet))
    throw InputError("box search: start tet " + std::to_string(start_tet) +
                     " does not meet the box " + format_box(box));

  if (stamps.size() < mesh.tet_count()) {
    stamps.assign(mesh.tet_count(), 0);
    stamp_counter = 0;
  }
  if (++stamp_counter == 0) {  // wrapped around: old stamps could collide
    std::fill(stamps.begin(), stamps.end(), 0u);
    stamp_counter = 1;
  }
  const std::uint32_t stamp = stamp_counter;
  stamps[start_tet] = stamp;
  found.push_back(start_tet);
  result.tets_visited = 1;
  result.exact_tests = kExact ? 1 : 0;
  // Only tets that meet the box expand: the ones meeting it are connected through faces.
  for (std::size_t head = 0; head < found.size(); ++head) {
    for (const std::uint32_t next : mesh.neighbours[found[head]]) {
      if (next == TetMesh::no_neighbour || stamps[next] == stamp) continue;
      stamps[next] = stamp;
      ++result.tets_visited;
      if (!bounds_overlap(next)) continue;
      if constexpr (kExact) {
        ++result.exact_tests;
        if (!geometry::tetrahedron_intersects_box(mesh.corners(next), box)) continue;
      } else {
        // Sliver tets' boxes reach far beyond them: a face plane keeps most of those out.
        if (!filter->planes_may_meet(next, box, box_magnitude)) continue;
      }
      found.push_back(next);
    }
  }
  result.tets = found;
  return result;
}

}  // namespace

BoxSearchResult tets_overlapping_box(const TetMesh& mesh, std::uint32_t start_tet,
                                     const geometry::Box& box, BoxSearchScratch& scratch) {
  return search<true>(mesh, nullptr, start_tet, box, scratch.stamps_, scratch.stamp_, scratch.found_);
}

BoxSearchResult tets_near_box(const TetMesh& mesh, const TetBoxFilter& filter, std::uint32_t start_tet,
                              const geometry::Box& box, BoxSearchScratch& scratch) {
  if (filter.tet_count() != mesh.tet_count())
    throw InputError("box search: a tet filter of " + std::to_string(filter.tet_count()) + " tets for " +
                     std::to_string(mesh.tet_count()) + " tets");
  return search<false>(mesh, &filter, start_tet, box, scratch.stamps_, scratch.stamp_, scratch.found_);
}

}  // namespace tetrapage
