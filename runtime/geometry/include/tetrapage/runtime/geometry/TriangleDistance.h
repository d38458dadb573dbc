#pragma once
/// @file TriangleDistance.h
/// Triangle/triangle distance for clearance queries: computed in double, with rigorous lower
/// and upper bounds on the true distance, and a within-distance test that never misses.

#include "tetrapage/runtime/geometry/Shapes.h"

namespace tetrapage::geometry {

/// The distance between two closed triangles.
///
/// Error bound: with u = 2^-53 and M the largest coordinate magnitude of the six vertices
/// taken relative to a[0], lower_bound <= true distance <= upper_bound, and
/// upper_bound - lower_bound is about 150 u M when the closest points are well defined (it
/// can be larger for near-parallel closest edges, never wrong). When the triangles intersect
/// (decided exactly), all three values are 0.
struct TriangleDistance {
  double distance = 0.0;     ///< the computed distance, |on_first - on_second|
  double lower_bound = 0.0;  ///< the true distance is at least this
  double upper_bound = 0.0;  ///< the true distance is at most this
  Point on_first{};   ///< computed closest point on the first triangle (within ~30 u M of it)
  Point on_second{};  ///< computed closest point on the second triangle
};

/// Distance between the closed triangles. Any finite input (degenerate triangles are segments
/// or points).
TriangleDistance triangle_distance(const Triangle& a, const Triangle& b);

/// True whenever the true distance is <= d: never misses a pair within d, and in particular
/// always true when the triangles touch or intersect (decided exactly), whatever the rounding.
/// May also return true for pairs slightly farther than d (by at most the error bound above).
/// Precondition: d >= 0 and finite.
bool within_distance(const Triangle& a, const Triangle& b, double d);

/// True only when the triangles are certainly farther apart than d, by cheap rigorous tests:
/// their boxes, `axis` (any direction, pointing from a towards b; zero: none) and each
/// triangle's plane separating them by more than d; false says nothing. within_distance's
/// first step, for searches that measure what it lets through.
bool farther_than_cheaply(const Triangle& a, const Triangle& b, double d, const Vec3& axis);

/// True only when every point of the closed triangle lies farther than `radius` from
/// `centre`: a pruning test, conservative whatever the rounding. The closest point is found in
/// double (the triangle's Voronoi regions) and the test is taken with a margin of 2^-20 of the
/// sizes involved; a needle or sliver (sine of its largest angle under 2^-10, where the
/// barycentric division loses its accuracy) and any non-finite input answer false.
bool triangle_outside_ball(const Triangle& triangle, const Point& centre, double radius);

}  // namespace tetrapage::geometry
