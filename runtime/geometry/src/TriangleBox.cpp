#include "tetrapage/runtime/geometry/TriangleBox.h"

#include "tetrapage/runtime/geometry/Predicates.h"

namespace tetrapage::geometry {

TriangleBoxContact classify_triangle_box(const Triangle& t, const Box& box) {
  if (box.empty() || !boxes_overlap(box_of(t), box)) return TriangleBoxContact::none;
  if (box_contains(box, t[0]) && box_contains(box, t[1]) && box_contains(box, t[2]))
    return TriangleBoxContact::contained;

  // The triangle's normal: the box corners extreme along it, chosen by the exact signs of its
  // components, must not both lie strictly on one side of the plane.
  const Sign n[3] = {normal_sign(t[0], t[1], t[2], 0), normal_sign(t[0], t[1], t[2], 1),
                     normal_sign(t[0], t[1], t[2], 2)};
  if (n[0] != Sign::zero || n[1] != Sign::zero || n[2] != Sign::zero) {
    Point highest, lowest;
    for (int k = 0; k < 3; ++k) {
      highest[k] = n[k] == Sign::positive ? box.hi[k] : box.lo[k];
      lowest[k] = n[k] == Sign::positive ? box.lo[k] : box.hi[k];
    }
    const OrientedPlane plane(t);
    if (plane.side(highest) == Sign::negative) return TriangleBoxContact::none;
    if (plane.side(lowest) == Sign::positive) return TriangleBoxContact::none;
  }

  // Edge e times axis k: seen along axis k, the line through the projected edge must not
  // separate the projected box from the projected triangle. When the projected triangle has
  // area, only the side away from its third vertex can separate (the far side is covered by
  // another edge or a box axis); when it is flat, both sides can.
  for (int k = 0; k < 3; ++k) {
    const int i = k == 2 ? 0 : k + 1;
    const int j = k == 0 ? 2 : k - 1;
    const Sign orientation = n[k];
    for (int e = 0; e < 3; ++e) {
      const Point& p = t[e];
      const Point& q = t[e == 2 ? 0 : e + 1];
      if (p[i] == q[i] && p[j] == q[j]) continue;  // the axis is zero
      // orient2d(p, q, x) grows with x along (-(q_j - p_j), q_i - p_i).
      const double max_i = q[j] < p[j] ? box.hi[i] : box.lo[i];
      const double max_j = q[i] > p[i] ? box.hi[j] : box.lo[j];
      const double min_i = q[j] < p[j] ? box.lo[i] : box.hi[i];
      const double min_j = q[i] > p[i] ? box.lo[j] : box.hi[j];
      if (orientation != Sign::negative &&
          orient2d(p[i], p[j], q[i], q[j], max_i, max_j) == Sign::negative)
        return TriangleBoxContact::none;
      if (orientation != Sign::positive &&
          orient2d(p[i], p[j], q[i], q[j], min_i, min_j) == Sign::positive)
        return TriangleBoxContact::none;
    }
  }
  return TriangleBoxContact::intersects;
}

}  // namespace tetrapage::geometry
