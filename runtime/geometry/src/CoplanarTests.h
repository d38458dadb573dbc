#pragma once
// Internal: exact tests inside one plane (after an injective projection onto a coordinate
// plane), and the fallbacks for degenerate segments and triangles. Not installed.

#include <array>
#include <cmath>

#include "tetrapage/runtime/geometry/Predicates.h"

namespace tetrapage::geometry::internal {

struct Point2 {
  double x, y;
};

/// Drops coordinate `axis`, keeping the other two in cyclic order so that the projected
/// orientation of a triangle equals normal_sign(..., axis).
inline Point2 project(const Point& p, int axis) {
  const int i = axis == 2 ? 0 : axis + 1;
  const int j = axis == 0 ? 2 : axis - 1;
  return {p[i], p[j]};
}

inline Sign orient(const Point2& a, const Point2& b, const Point2& c) {
  return orient2d(a.x, a.y, b.x, b.y, c.x, c.y);
}

/// An axis along which the projection of the plane of (a, b, c) is injective (the normal has a
/// nonzero component there, decided exactly), preferring the dominant one; -1 when the three
/// points are collinear.
inline int injective_axis(const Point& a, const Point& b, const Point& c) {
  const double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
  const double vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
  const double n[3] = {std::fabs(uy * vz - uz * vy), std::fabs(uz * vx - ux * vz),
                       std::fabs(ux * vy - uy * vx)};
  int order[3] = {0, 1, 2};
  if (n[order[1]] > n[order[0]]) std::swap(order[0], order[1]);
  if (n[order[2]] > n[order[1]]) std::swap(order[1], order[2]);
  if (n[order[1]] > n[order[0]]) std::swap(order[0], order[1]);
  for (int axis : order)
    if (normal_sign(a, b, c, axis) != Sign::zero) return axis;
  return -1;
}

/// Lexicographic comparison (x, then y, then z): along a line, the order of the points.
inline bool lexicographically_less(const Point& a, const Point& b) {
  if (a[0] != b[0]) return a[0] < b[0];
  if (a[1] != b[1]) return a[1] < b[1];
  return a[2] < b[2];
}

/// Closed intervals [p, q] and [r, s] of four collinear points overlap.
inline bool collinear_segments_overlap(const Point& p, const Point& q, const Point& r,
                                       const Point& s) {
  const Point& lo1 = lexicographically_less(q, p) ? q : p;
  const Point& hi1 = lexicographically_less(q, p) ? p : q;
  const Point& lo2 = lexicographically_less(s, r) ? s : r;
  const Point& hi2 = lexicographically_less(s, r) ? r : s;
  return !lexicographically_less(hi1, lo2) && !lexicographically_less(hi2, lo1);
}

/// Closed 2D segments [p, q] and [r, s] meet (either may be a single point).
inline bool segments_intersect_2d(const Point2& p, const Point2& q, const Point2& r,
                                  const Point2& s, const Point& p3, const Point& q3,
                                  const Point& r3, const Point& s3) {
  const Sign o1 = orient(p, q, r), o2 = orient(p, q, s);
  if (o1 != Sign::zero && o1 == o2) return false;
  const Sign o3 = orient(r, s, p), o4 = orient(r, s, q);
  if (o3 != Sign::zero && o3 == o4) return false;
  if ((o1 == Sign::zero && o2 == Sign::zero) || (o3 == Sign::zero && o4 == Sign::zero))
    return collinear_segments_overlap(p3, q3, r3, s3);  // the projection is injective
  return true;
}

/// Closed 3D segments [p, q] and [r, s] meet, exactly; degenerate segments are points.
inline bool segments_intersect(const Point& p, const Point& q, const Point& r, const Point& s) {
  if (orient3d(p, q, r, s) != Sign::zero) return false;
  const Point* triples[4][3] = {{&p, &q, &r}, {&p, &q, &s}, {&r, &s, &p}, {&r, &s, &q}};
  for (const auto& t : triples) {
    const int axis = injective_axis(*t[0], *t[1], *t[2]);
    if (axis < 0) continue;
    return segments_intersect_2d(project(p, axis), project(q, axis), project(r, axis),
                                 project(s, axis), p, q, r, s);
  }
  return collinear_segments_overlap(p, q, r, s);  // all four on one line
}

/// Closed 2D triangle (non-degenerate, orientation `orientation`) and segment [p, q] meet.
inline bool segment_meets_triangle_2d(const Point2& p, const Point2& q,
                                      const std::array<Point2, 3>& t, Sign orientation) {
  for (int i = 0; i < 3; ++i) {
    const Point2& a = t[i];
    const Point2& b = t[i == 2 ? 0 : i + 1];
    if (orient(a, b, p) * orientation == Sign::negative &&
        orient(a, b, q) * orientation == Sign::negative)
      return false;
  }
  const Sign s0 = orient(p, q, t[0]);
  if (s0 != Sign::zero && s0 == orient(p, q, t[1]) && s0 == orient(p, q, t[2])) return false;
  return true;
}

/// Closed 2D triangles (both non-degenerate) meet: no edge line separates them strictly.
inline bool triangles_meet_2d(const std::array<Point2, 3>& t1, Sign orientation1,
                              const std::array<Point2, 3>& t2, Sign orientation2) {
  auto separated_by_an_edge_of = [](const std::array<Point2, 3>& a, Sign orientation,
                                    const std::array<Point2, 3>& b) {
    for (int i = 0; i < 3; ++i) {
      const Point2& p = a[i];
      const Point2& q = a[i == 2 ? 0 : i + 1];
      if (orient(p, q, b[0]) * orientation == Sign::negative &&
          orient(p, q, b[1]) * orientation == Sign::negative &&
          orient(p, q, b[2]) * orientation == Sign::negative)
        return true;
    }
    return false;
  };
  return !separated_by_an_edge_of(t1, orientation1, t2) &&
         !separated_by_an_edge_of(t2, orientation2, t1);
}

inline std::array<Point2, 3> project(const Triangle& t, int axis) {
  return {project(t[0], axis), project(t[1], axis), project(t[2], axis)};
}

/// Closed segment [p, q] and closed triangle t meet, exactly, for any input (degenerate
/// segments are points, degenerate triangles the union of their edges). Slow path.
inline bool segment_meets_triangle_any(const Point& p, const Point& q, const Triangle& t) {
  const int axis = injective_axis(t[0], t[1], t[2]);
  if (axis < 0) {
    for (int i = 0; i < 3; ++i)
      if (segments_intersect(p, q, t[i], t[i == 2 ? 0 : i + 1])) return true;
    return false;
  }
  const OrientedPlane plane(t);
  const Sign sp = plane.side(p), sq = plane.side(q);
  if (sp != Sign::zero && sp == sq) return false;
  if (sp == Sign::zero && sq == Sign::zero)
    return segment_meets_triangle_2d(project(p, axis), project(q, axis), project(t, axis),
                                     normal_sign(t[0], t[1], t[2], axis));
  // The line crosses the plane at one point; it is inside iff the three edge signs agree.
  const Sign e0 = orient3d(p, q, t[0], t[1]);
  const Sign e1 = orient3d(p, q, t[1], t[2]);
  const Sign e2 = orient3d(p, q, t[2], t[0]);
  const bool has_positive = e0 == Sign::positive || e1 == Sign::positive || e2 == Sign::positive;
  const bool has_negative = e0 == Sign::negative || e1 == Sign::negative || e2 == Sign::negative;
  return !(has_positive && has_negative);
}

/// Closed triangles meet, exactly, when at least one of them is degenerate. Slow path.
inline bool degenerate_triangles_meet(const Triangle& t1, const Triangle& t2) {
  const bool degenerate1 = injective_axis(t1[0], t1[1], t1[2]) < 0;
  const Triangle& segments_of = degenerate1 ? t1 : t2;
  const Triangle& other = degenerate1 ? t2 : t1;
  for (int i = 0; i < 3; ++i)
    if (segment_meets_triangle_any(segments_of[i], segments_of[i == 2 ? 0 : i + 1], other))
      return true;
  return false;
}

}  // namespace tetrapage::geometry::internal
