#pragma once
/// @file TriangleBox.h
/// Exact triangle/box overlap of closed sets: the separating axis test (the box's three axes,
/// the triangle's normal, and the nine edge-by-axis products) with every side decided by an
/// exact sign, for binning triangles into grid cells and for BVH pruning.

#include <cstdint>

#include "tetrapage/runtime/geometry/Box.h"

namespace tetrapage::geometry {

enum class TriangleBoxContact : std::uint8_t {
  none,
  intersects,  ///< they meet, and the triangle is not entirely inside the box
  contained,   ///< the triangle lies in the closed box
};

/// Exact classification of the closed triangle against the closed box. Any finite input (a
/// degenerate triangle is a segment or a point); an empty box meets nothing.
TriangleBoxContact classify_triangle_box(const Triangle& t, const Box& box);

/// Exact: the closed triangle and the closed box meet.
inline bool triangle_intersects_box(const Triangle& t, const Box& box) {
  return classify_triangle_box(t, box) != TriangleBoxContact::none;
}

}  // namespace tetrapage::geometry
