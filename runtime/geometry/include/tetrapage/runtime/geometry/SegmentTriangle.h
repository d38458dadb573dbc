#pragma once
/// @file SegmentTriangle.h
/// Exact segment/triangle intersection of closed sets, classified (for mesh walks and ray
/// shooting: which feature of the triangle the segment passes through).

#include <cstdint>

#include "tetrapage/runtime/geometry/Shapes.h"

namespace tetrapage::geometry {

enum class SegmentTriangleContact : std::uint8_t {
  none,
  interior,  ///< one point, in the triangle's relative interior
  edge,      ///< one point, in the relative interior of edge `feature` (v[feature], v[feature+1])
  vertex,    ///< one point: vertex `feature` of the triangle
  coplanar,  ///< the segment lies in the triangle's plane and meets the triangle
  degenerate_triangle,  ///< the triangle has zero area and meets the segment
};

struct SegmentTriangleHit {
  SegmentTriangleContact contact = SegmentTriangleContact::none;
  std::uint8_t feature = 0;  ///< edge or vertex index, see SegmentTriangleContact
  bool at_endpoint = false;  ///< for one-point contacts: the point is an endpoint of the segment

  explicit operator bool() const { return contact != SegmentTriangleContact::none; }
};

/// Exact classification of the closed segment [s[0], s[1]] against the closed triangle t.
/// Any finite input (a zero-length segment is a point).
SegmentTriangleHit classify_segment_triangle(const Segment& s, const Triangle& t);

/// Exact: the closed segment and the closed triangle meet. Any finite input.
bool segment_intersects_triangle(const Segment& s, const Triangle& t);

}  // namespace tetrapage::geometry
