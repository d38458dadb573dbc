#pragma once
/// @file Box.h
/// Axis-aligned boxes (the formats' BoundingBox: closed, empty while lo > hi) and their exact
/// tests. Comparisons of stored coordinates involve no rounding, so these answers are exact.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "tetrapage/runtime/geometry/Shapes.h"

namespace tetrapage::geometry {

using Box = BoundingBox;

/// How two closed boxes meet.
enum class BoxContact : std::uint8_t {
  none,         ///< disjoint
  touching,     ///< they share boundary points only (the intersection has zero volume)
  overlapping,  ///< the intersection has positive volume
};

/// The smallest box holding the points (exact: min and max only).
template <std::size_t N>
Box box_of(const std::array<Point, N>& points) {
  Box box;
  box.lo = box.hi = points[0];
  for (std::size_t i = 1; i < N; ++i) box.extend(points[i]);
  return box;
}

/// Closed-set overlap; touching boxes overlap. Empty boxes overlap nothing.
inline bool boxes_overlap(const Box& a, const Box& b) {
  return a.lo[0] <= b.hi[0] && b.lo[0] <= a.hi[0] && a.lo[1] <= b.hi[1] && b.lo[1] <= a.hi[1] &&
         a.lo[2] <= b.hi[2] && b.lo[2] <= a.hi[2] && !a.empty() && !b.empty();
}

/// The classified answer of boxes_overlap.
inline BoxContact classify_boxes(const Box& a, const Box& b) {
  if (!boxes_overlap(a, b)) return BoxContact::none;
  for (int k = 0; k < 3; ++k)
    if (std::min(a.hi[k], b.hi[k]) == std::max(a.lo[k], b.lo[k])) return BoxContact::touching;
  return BoxContact::overlapping;
}

/// Whether the closed box `outer` holds all of `inner` (false for an empty inner).
inline bool box_contains(const Box& outer, const Box& inner) {
  return !inner.empty() && outer.lo[0] <= inner.lo[0] && outer.lo[1] <= inner.lo[1] && outer.lo[2] <= inner.lo[2] &&
         inner.hi[0] <= outer.hi[0] && inner.hi[1] <= outer.hi[1] && inner.hi[2] <= outer.hi[2];
}

inline bool box_contains(const Box& box, const Point& p) {
  return box.lo[0] <= p[0] && p[0] <= box.hi[0] && box.lo[1] <= p[1] && p[1] <= box.hi[1] &&
         box.lo[2] <= p[2] && p[2] <= box.hi[2];
}

/// The box grown by at least `margin` (>= 0) on every side: the bounds are rounded outwards,
/// so every point within L-infinity distance `margin` of `box` is inside the result.
inline Box inflated(const Box& box, double margin) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  Box out;
  for (int k = 0; k < 3; ++k) {
    out.lo[k] = std::nextafter(box.lo[k] - margin, -inf);
    out.hi[k] = std::nextafter(box.hi[k] + margin, inf);
  }
  return out;
}

/// A lower bound on the Euclidean distance between the closed boxes (0 when they meet): the
/// double computation's few roundings are covered by a relative 2^-50.
inline double box_distance_lower_bound(const Box& a, const Box& b) {
  double sum = 0;
  for (int k = 0; k < 3; ++k) {
    const double gap = std::max({0.0, a.lo[k] - b.hi[k], b.lo[k] - a.hi[k]});
    sum += gap * gap;
  }
  return std::sqrt(sum) * (1 - 0x1p-50);
}

}  // namespace tetrapage::geometry
