#pragma once
/// @file FloatBox.h
/// A box stored in floats, rounded outward: half the bytes of a double Box for the tables an
/// index keeps resident per tet and per shard, and still a box that holds everything the
/// double one held, so that a filter asking it never drops what the exact test would keep.

#include <array>

#include "tetrapage/runtime/geometry/Box.h"
#include "tetrapage/runtime/geometry/FloatRounding.h"

namespace tetrapage::geometry {

struct FloatBox {
  std::array<float, 3> lo{}, hi{};

  /// The smallest float box holding `box` (an empty box stays empty).
  static FloatBox enclosing(const Box& box) {
    FloatBox out;
    for (int a = 0; a < 3; ++a) {
      out.lo[a] = float_below(box.lo[a]);
      out.hi[a] = float_above(box.hi[a]);
    }
    return out;
  }
  /// The same box in doubles (exactly: every float is a double).
  Box box() const {
    Box out;
    for (int a = 0; a < 3; ++a) {
      out.lo[a] = lo[a];
      out.hi[a] = hi[a];
    }
    return out;
  }
};

/// Whether two float boxes meet (closed: touching counts), as boxes_overlap for doubles; both
/// nonempty.
inline bool boxes_overlap(const FloatBox& a, const FloatBox& b) {
  return a.lo[0] <= b.hi[0] && b.lo[0] <= a.hi[0] && a.lo[1] <= b.hi[1] && b.lo[1] <= a.hi[1] &&
         a.lo[2] <= b.hi[2] && b.lo[2] <= a.hi[2];
}

}  // namespace tetrapage::geometry
