#include "tetrapage/runtime/geometry/SegmentTriangle.h"

#include "CoplanarTests.h"
#include "tetrapage/runtime/geometry/Predicates.h"

namespace tetrapage::geometry {

SegmentTriangleHit classify_segment_triangle(const Segment& s, const Triangle& t) {
  const Point& p = s[0];
  const Point& q = s[1];
  const OrientedPlane plane(t);
  const Sign sp = plane.side(p), sq = plane.side(q);
  if (sp != Sign::zero && sp == sq) return {};
  if (sp == Sign::zero && sq == Sign::zero) {
    const int axis = internal::injective_axis(t[0], t[1], t[2]);
    if (axis < 0)
      return internal::segment_meets_triangle_any(p, q, t)
                 ? SegmentTriangleHit{SegmentTriangleContact::degenerate_triangle, 0, false}
                 : SegmentTriangleHit{};
    const bool meets = internal::segment_meets_triangle_2d(
        internal::project(p, axis), internal::project(q, axis), internal::project(t, axis),
        normal_sign(t[0], t[1], t[2], axis));
    return meets ? SegmentTriangleHit{SegmentTriangleContact::coplanar, 0, false}
                 : SegmentTriangleHit{};
  }
  // The line pq crosses the plane at exactly one point X (an endpoint when one side is zero).
  // orient3d(p, q, v_i, v_i+1) tells on which side of edge i the point X lies; the signs agree
  // (all positive or all negative, by the direction of the crossing) when X is inside.
  Sign e[3];
  for (int i = 0; i < 3; ++i) e[i] = orient3d(p, q, t[i], t[i == 2 ? 0 : i + 1]);
  int zeros = 0, positives = 0, negatives = 0;
  for (Sign x : e) {
    zeros += x == Sign::zero;
    positives += x == Sign::positive;
    negatives += x == Sign::negative;
  }
  if (positives > 0 && negatives > 0) return {};
  const bool at_endpoint = sp == Sign::zero || sq == Sign::zero;
  if (zeros == 0) return {SegmentTriangleContact::interior, 0, at_endpoint};
  if (zeros == 1) {
    const std::uint8_t edge = e[0] == Sign::zero ? 0 : (e[1] == Sign::zero ? 1 : 2);
    return {SegmentTriangleContact::edge, edge, at_endpoint};
  }
  if (zeros == 2) {
    // On edges i and i+1: their common vertex i+1.
    const std::uint8_t nonzero = e[0] != Sign::zero ? 0 : (e[1] != Sign::zero ? 1 : 2);
    const std::uint8_t vertex = static_cast<std::uint8_t>((nonzero + 2) % 3);
    return {SegmentTriangleContact::vertex, vertex, at_endpoint};
  }
  // Three zeros: the triangle is degenerate (the line lies in all three edge planes).
  return internal::segment_meets_triangle_any(p, q, t)
             ? SegmentTriangleHit{SegmentTriangleContact::degenerate_triangle, 0, false}
             : SegmentTriangleHit{};
}

bool segment_intersects_triangle(const Segment& s, const Triangle& t) {
  return classify_segment_triangle(s, t).contact != SegmentTriangleContact::none;
}

}  // namespace tetrapage::geometry
