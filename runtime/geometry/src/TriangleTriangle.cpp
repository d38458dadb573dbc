#include "tetrapage/runtime/geometry/TriangleTriangle.h"

#include "CoplanarTests.h"
#include "PlaneCut.h"
#include "tetrapage/runtime/geometry/Predicates.h"

namespace tetrapage::geometry {
namespace {

using internal::all_same_nonzero;
using internal::all_zero;
using internal::compare_along_line;
using internal::cut_interval;
using internal::Interval;
using internal::straddles;

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
