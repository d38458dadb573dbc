#include "tetrapage/runtime/BoxSearch.h"

#include <algorithm>
#include <cstdio>
#include <string>

#include "tetrapage/formats/Error.h"
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

}  // namespace

bool tetrahedron_intersects_box(const Tetrahedron& t, const Box& box) {
  if (inverted(box) || !boxes_overlap(box_of(t), box)) return false;  // the box's axes
  for (const Point& v : t)
    if (box_contains(box, v)) return true;

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

BoxSearchResult tets_overlapping_box(const TetMesh& mesh, std::uint32_t start_tet,
                                     const geometry::Box& box, BoxSearchScratch& scratch) {
  if (start_tet >= mesh.tet_count())
    throw InputError("box search: start tet " + std::to_string(start_tet) +
                     " is out of range (" + std::to_string(mesh.tet_count()) + " tets)");
  if (!geometry::is_finite(box.lo) || !geometry::is_finite(box.hi))
    throw InputError("box search: the box " + format_box(box) + " is not finite");
  scratch.found_.clear();
  BoxSearchResult result;
  if (geometry::inverted(box)) return result;
  if (!geometry::tetrahedron_intersects_box(mesh.corners(start_tet), box))
    throw InputError("box search: start tet " + std::to_string(start_tet) +
                     " does not meet the box " + format_box(box));

  if (scratch.stamps_.size() < mesh.tet_count()) {
    scratch.stamps_.assign(mesh.tet_count(), 0);
    scratch.stamp_ = 0;
  }
  if (++scratch.stamp_ == 0) {  // wrapped around: old stamps could collide
    std::fill(scratch.stamps_.begin(), scratch.stamps_.end(), 0u);
    scratch.stamp_ = 1;
  }
  const std::uint32_t stamp = scratch.stamp_;
  auto& found = scratch.found_;
  scratch.stamps_[start_tet] = stamp;
  found.push_back(start_tet);
  result.tets_visited = 1;
  result.exact_tests = 1;
  // Only tets that meet the box expand: the ones meeting it are connected through faces.
  for (std::size_t head = 0; head < found.size(); ++head) {
    for (const std::uint32_t next : mesh.neighbours[found[head]]) {
      if (next == TetMesh::no_neighbour || scratch.stamps_[next] == stamp) continue;
      scratch.stamps_[next] = stamp;
      ++result.tets_visited;
      if (!geometry::boxes_overlap(mesh.bounds(next), box)) continue;
      ++result.exact_tests;
      if (geometry::tetrahedron_intersects_box(mesh.corners(next), box)) found.push_back(next);
    }
  }
  result.tets = found;
  return result;
}

}  // namespace tetrapage
