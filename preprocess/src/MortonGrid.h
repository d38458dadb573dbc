#pragma once
/// @file MortonGrid.h
/// Morton codes of points in a box: the order of the tets on disk (buckets) and of the
/// triangles within a binning task.

#include <algorithm>
#include <array>
#include <cstdint>

#include "tetrapage/formats/base/TriangleSoup.h"

namespace tetrapage {

// Spreads a 21-bit integer's bits three apart (for Morton codes).
inline std::uint64_t spread_bits(std::uint64_t x) {
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffULL;
  x = (x | x << 16) & 0x1f0000ff0000ffULL;
  x = (x | x << 8) & 0x100f00f00f00f00fULL;
  x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
  x = (x | x << 2) & 0x1249249249249249ULL;
  return x;
}

// Morton codes of points in a box, 21 bits an axis. The scales are taken once: three
// divisions a point were a sixtieth of the preprocess's CPU (binning codes every triangle).
class MortonGrid {
 public:
  explicit MortonGrid(const BoundingBox& box) : lo_(box.lo) {
    for (int axis = 0; axis < 3; ++axis) {
      const double side = box.hi[axis] - box.lo[axis];
      scale_[axis] = side > 0 ? double((1 << 21) - 1) / side : 0.0;
    }
  }
  std::uint64_t code(const Vec3& p) const {
    std::uint64_t code = 0;
    for (int axis = 0; axis < 3; ++axis) {
      const double cell =
          std::clamp((p[axis] - lo_[axis]) * scale_[axis], 0.0, double((1 << 21) - 1));
      code |= spread_bits(std::uint64_t(cell)) << axis;
    }
    return code;
  }

 private:
  Vec3 lo_;
  std::array<double, 3> scale_;
};

}  // namespace tetrapage
