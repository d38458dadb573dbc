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

}  // namespace tetrapage::geometry
