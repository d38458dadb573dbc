#pragma once
/// @file TriangleContact.h
/// The contact geometry of two closed triangles: where they meet (a point, a segment, or the
/// convex polygon they share when coplanar) and their unit normals, for contact reports.
///
/// The topology (do they meet, coplanar or not, which features cross) is decided with the
/// exact predicates of TriangleTriangle.h, so `shape != ContactShape::none` exactly when
/// triangles_intersect(first, second). Only the coordinates of the points are rounded.
///
/// Error bound. Let M be the largest magnitude of the 18 input coordinates and u = 2^-53.
/// Every point reported is an input vertex (then exact) or the crossing of an input edge
/// [v, w] with a plane (or, coplanar, with an edge line of the other triangle), computed as
/// v + t (w - v) with t = |f(v)| / (|f(v)| + |f(w)|), f that plane's or line's determinant.
/// f(v) and f(w) are computed within 2^-42 (|f(v)| + |f(w)|) of the exact values together (a
/// floating-point filter with a proven bound; else exactly, with CGAL's Mpzf, and t rounded
/// from the exact rational), so |t - t*| <= 2^-42 + 2u, and each coordinate of the point is
/// within 2 M (2^-42 + 2u) + 5 u M < 2^-40 M (about 9.1e-13 M) of the exact point's (the
/// roundings of w - v, of the product and of the sum add 2u, 2u and u times M):
/// kContactPointRelativeError * M. In practice the error is a few u M. The unit normals are
/// within 2^-40 of the exact ones, for any triangle, however thin. Coordinates are assumed
/// finite and below about 1e150 in magnitude (nothing may overflow).

#include <array>
#include <cstdint>

#include "tetrapage/runtime/geometry/Shapes.h"

namespace tetrapage::geometry {

/// The error bound above, relative to the largest input coordinate magnitude.
inline constexpr double kContactPointRelativeError = 0x1p-40;

enum class ContactShape : std::uint8_t { none, point, segment, polygon };

struct ContactGeometry {
  ContactShape shape = ContactShape::none;
  /// point: points[0]; segment: points[0..1] (not coplanar: in the direction of
  /// first_normal x second_normal); polygon: points[0..count) in order counterclockwise about
  /// first_normal (3 to 6 vertices, each a corner of the exact polygon; corners closer to
  /// each other than the error bound may come swapped).
  std::array<Point, 6> points{};
  std::uint8_t count = 0;
  /// Unit normals (v1 - v0) x (v2 - v0) / |...| of each triangle; zero for a degenerate one.
  Vec3 first_normal{}, second_normal{};
  /// Both triangles are non-degenerate and lie in one plane (set whether or not they meet).
  bool coplanar = false;
};

/// Where the closed triangles meet, and their normals. Any finite input: a degenerate triangle
/// is the segment (or point) its vertices span, so a segment against a triangle gives a point
/// or a segment, and two segments a point or a segment.
ContactGeometry contact_geometry(const Triangle& first, const Triangle& second);

}  // namespace tetrapage::geometry
