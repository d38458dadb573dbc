#pragma once
/// @file TriangleTriangle.h
/// Exact triangle/triangle intersection of closed sets (touching counts as intersecting), the
/// collision test of phase II. Orientation predicates only (the interval comparison of Guigue
/// and Devillers, 2003), so every decision is an exact sign; no point is ever constructed.

#include <cstdint>

#include "tetrapage/runtime/geometry/Shapes.h"

namespace tetrapage::geometry {

enum class TriangleContact : std::uint8_t {
  none,
  point,     ///< not coplanar; they meet in a single point (a vertex on the other triangle,
             ///< two edges crossing, a vertex on a vertex)
  edge,      ///< not coplanar; they meet in a segment lying on an edge of one of them (one
             ///< triangle rests on the other without passing through its plane)
  crossing,  ///< not coplanar; they meet in a segment and each passes through the other's plane
  coplanar,  ///< both in one plane, meeting (in a point, a segment or an area)
  degenerate_triangle,  ///< one of them has zero area (collinear vertices) and they meet
};

/// Exact classification. Any finite input; a degenerate triangle is the union of its edges.
TriangleContact classify_triangles(const Triangle& a, const Triangle& b);

/// Exact: the closed triangles meet. Same answer as classify_triangles(a, b) != none, a little
/// faster.
bool triangles_intersect(const Triangle& a, const Triangle& b);

}  // namespace tetrapage::geometry
