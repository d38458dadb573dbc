#pragma once
/// @file Shapes.h
/// The value types the geometry kernel works on: points, segments, triangles and tetrahedra
/// as plain arrays of double coordinates (the formats' Vec3). Float-stored coordinates convert
/// to double exactly, so every exact decision made on doubles is exact on floats too.

#include <array>
#include <cmath>

#include "tetrapage/formats/base/TriangleSoup.h"

namespace tetrapage::geometry {

using Point = Vec3;
using Segment = std::array<Point, 2>;
using Triangle = std::array<Point, 3>;
/// Vertices v0..v3; face k is the face opposite vertex k.
using Tetrahedron = std::array<Point, 4>;

/// A float-stored point, widened exactly.
inline Point to_point(const std::array<float, 3>& p) {
  return {double(p[0]), double(p[1]), double(p[2])};
}

inline bool is_finite(const Point& p) {
  return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

template <std::size_t N>
bool is_finite(const std::array<Point, N>& points) {
  for (const auto& p : points)
    if (!is_finite(p)) return false;
  return true;
}

}  // namespace tetrapage::geometry
