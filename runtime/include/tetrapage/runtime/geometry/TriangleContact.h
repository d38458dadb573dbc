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
/// v + t (w - v) where t = f(v) / (f(v) - f(w)) and f is that plane's or line's determinant.
/// f(v) and f(w) are computed with relative error at most 2^-46 (a floating-point filter,
/// else CGAL's exact Mpzf rounded to double), so |t - t*| <= 2^-47 + 2u, and each coordinate
/// of the point is within (2^-46 + 9u) M < 2^-44 M (about 5.7e-14 M) of the exact point's:
/// kContactPointRelativeError * M. The normals are within 2^-44 (relative) of the exact unit
/// normals, for any triangle, however thin. Coordinates are assumed finite and below about
/// 1e150 in magnitude (the squares in the normalisation and the filter must not overflow).

#include <array>
#include <cstdint>

#include "tetrapage/runtime/geometry/Shapes.h"

namespace tetrapage::geometry {

/// The error bound above, relative to the largest input coordinate magnitude.
inline constexpr double kContactPointRelativeError = 0x1p-44;

enum class ContactShape : std::uint8_t { none, point, segment, polygon };

struct ContactGeometry {
  ContactShape shape = ContactShape::none;
  /// point: points[0]; segment: points[0..1] (not coplanar: in the direction of
  /// first_normal x second_normal); polygon: points[0..count) in order counterclockwise about
  /// first_normal (3 to 6 vertices, each a corner of the exact polygon).
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
