#include "tetrapage/runtime/geometry/TriangleTriangle.h"

#include "CoplanarTests.h"
#include "tetrapage/runtime/geometry/Predicates.h"

namespace tetrapage::geometry {
namespace {

// Both triangles cut the line L where their planes meet. Orient L by d = n1 x n2 (n the normal
// (v1 - v0) x (v2 - v0) of each triangle). Each triangle's cut is an interval of L whose ends
// are points X on an edge [u, w] of the triangle, with u strictly off the other plane (X may be
// w itself when w lies on that plane).
struct IntervalEnd {
  int off;    // u: the vertex strictly off the other plane
  int other;  // w
};

struct Interval {
  IntervalEnd lo, hi;
  bool single_point = false;  // the triangle touches the other plane at one vertex only
};

bool all_same_nonzero(const Sign s[3]) {
  return s[0] != Sign::zero && s[0] == s[1] && s[0] == s[2];
}
bool all_zero(const Sign s[3]) {
  return s[0] == Sign::zero && s[1] == Sign::zero && s[2] == Sign::zero;
}
bool straddles(const Sign s[3]) {
  const bool positive = s[0] == Sign::positive || s[1] == Sign::positive || s[2] == Sign::positive;
  const bool negative = s[0] == Sign::negative || s[1] == Sign::negative || s[2] == Sign::negative;
  return positive && negative;
}

// s: the signs of the triangle's vertices against the other plane (neither all zero nor all
// the same nonzero sign). first: this is the triangle whose normal comes first in d.
Interval cut_interval(const Sign s[3], bool first) {
  for (int i = 0; i < 3; ++i) {
    if (s[i] == Sign::zero) continue;
    const int j = i == 2 ? 0 : i + 1;
    const int k = j == 2 ? 0 : j + 1;
    if (s[j] == s[i] || s[k] == s[i]) continue;
    // Vertex i is alone on its side; the cut runs from edge (i, j) to edge (i, k). With the
    // vertices counterclockwise about the normal, the end on edge (i, j) is the upper end
    // along d for the first triangle when vertex i is on the positive side, and the lower end
    // for the second (d = n1 x n2 = -(n2 x n1)).
    const bool j_is_upper = (s[i] == Sign::positive) == first;
    const IntervalEnd on_j{i, j}, on_k{i, k};
    return {j_is_upper ? on_k : on_j, j_is_upper ? on_j : on_k, false};
  }
  // No lonely vertex: one vertex on the plane, the two others strictly on one side.
  const int z = s[0] == Sign::zero ? 0 : (s[1] == Sign::zero ? 1 : 2);
  const int o = z == 2 ? 0 : z + 1;
  return {{o, z}, {o, z}, true};
}

// The sign of (Y - X) . d for X an interval end of the first triangle and Y one of the second.
// With X on [u, w], Y on [s, t] (u off plane 2, t off plane 1), orient3d(u, w, s, t) is
// proportional to (Y - X) . d with the sign -side(u, plane 2) * side(t, plane 1).
Sign compare_along_line(const Triangle& a, const Sign sa[3], IntervalEnd x, const Triangle& b,
                        const Sign sb[3], IntervalEnd y) {
  return -(orient3d(a[x.off], a[x.other], b[y.other], b[y.off]) * sa[x.off] * sb[y.off]);
}

template <bool Classify>
TriangleContact intersect(const Triangle& a, const Triangle& b) {
  const OrientedPlane plane_b(b);
  Sign sa[3];  // a's vertices against b's plane
  for (int i = 0; i < 3; ++i) sa[i] = plane_b.side(a[i]);
  if (all_same_nonzero(sa)) return TriangleContact::none;
  const OrientedPlane plane_a(a);
  Sign sb[3];
  for (int i = 0; i < 3; ++i) sb[i] = plane_a.side(b[i]);
  if (all_same_nonzero(sb)) return TriangleContact::none;

  if (all_zero(sa) || all_zero(sb)) {
    // Coplanar, or one triangle is degenerate (its plane is undefined).
    const int axis_a = internal::injective_axis(a[0], a[1], a[2]);
    const int axis_b = axis_a < 0 ? -1 : internal::injective_axis(b[0], b[1], b[2]);
    if (axis_a < 0 || axis_b < 0)
      return internal::degenerate_triangles_meet(a, b) ? TriangleContact::degenerate_triangle
                                                       : TriangleContact::none;
    // Both proper and coplanar: the projection along axis_a is injective on their plane.
    const bool meet = internal::triangles_meet_2d(
        internal::project(a, axis_a), normal_sign(a[0], a[1], a[2], axis_a),
        internal::project(b, axis_a), normal_sign(b[0], b[1], b[2], axis_a));
    return meet ? TriangleContact::coplanar : TriangleContact::none;
  }

  const Interval ia = cut_interval(sa, true);
  const Interval ib = cut_interval(sb, false);
  // Overlap iff lo(a) <= hi(b) and lo(b) <= hi(a) along d.
  const Sign gap_low = compare_along_line(a, sa, ia.lo, b, sb, ib.hi);  // hi(b) - lo(a)
  if (gap_low == Sign::negative) return TriangleContact::none;
  const Sign gap_high = compare_along_line(a, sa, ia.hi, b, sb, ib.lo);  // lo(b) - hi(a)
  if (gap_high == Sign::positive) return TriangleContact::none;
  if constexpr (!Classify) return TriangleContact::crossing;
  if (ia.single_point || ib.single_point || gap_low == Sign::zero || gap_high == Sign::zero)
    return TriangleContact::point;
  return straddles(sa) && straddles(sb) ? TriangleContact::crossing : TriangleContact::edge;
}

}  // namespace

TriangleContact classify_triangles(const Triangle& a, const Triangle& b) {
  return intersect<true>(a, b);
}

bool triangles_intersect(const Triangle& a, const Triangle& b) {
  return intersect<false>(a, b) != TriangleContact::none;
}

}  // namespace tetrapage::geometry
