#pragma once
/// @file FloatRounding.h
/// Doubles rounded outward to float, for float boxes that prune (the object BVH's nodes, a
/// shard's R-tree nodes and the queries against them): when both the boxes and the queries
/// round outward, the float test never drops a pair the double test keeps.

#include <bit>
#include <cstdint>
#include <limits>

namespace tetrapage::geometry {

/// The float next to finite f towards +infinity (up) or -infinity, by its bits (std::nextafter
/// is a library call; these run per query).
inline float float_neighbour(float f, bool up) {
  if (f == 0)
    return up ? std::numeric_limits<float>::denorm_min()
              : -std::numeric_limits<float>::denorm_min();
  const auto bits = std::bit_cast<std::uint32_t>(f);
  return std::bit_cast<float>((f > 0) == up ? bits + 1 : bits - 1);
}

/// A float no larger than x, also for x beyond float's range (then the largest float, or
/// -infinity); NaN stays NaN and overlaps nothing.
inline float float_below(double x) {
  constexpr float max = std::numeric_limits<float>::max();
  if (x > double(max)) return max;
  if (x < -double(max)) return -std::numeric_limits<float>::infinity();
  const float f = static_cast<float>(x);
  return double(f) > x ? float_neighbour(f, false) : f;
}

/// A float no smaller than x (the same conventions).
inline float float_above(double x) {
  constexpr float max = std::numeric_limits<float>::max();
  if (x < -double(max)) return -max;
  if (x > double(max)) return std::numeric_limits<float>::infinity();
  const float f = static_cast<float>(x);
  return double(f) < x ? float_neighbour(f, true) : f;
}

}  // namespace tetrapage::geometry
