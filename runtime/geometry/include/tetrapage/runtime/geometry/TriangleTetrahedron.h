#pragma once
/// @file TriangleTetrahedron.h
/// Exact overlap of a closed triangle and a closed (solid) tetrahedron, for binning each
/// triangle into every tetrahedron it really meets (not just the ones its box overlaps).

#include <cstdint>

#include "tetrapage/runtime/geometry/Shapes.h"

namespace tetrapage::geometry {

enum class TriangleTetrahedronContact : std::uint8_t {
  none,
  intersects,              ///< they meet, and the triangle is not entirely inside the tetrahedron
  contained,               ///< the triangle lies in the closed tetrahedron
  degenerate_tetrahedron,  ///< the tetrahedron's vertices are coplanar: no answer
};

/// Exact classification (either orientation of the tetrahedron; a degenerate triangle is the
/// union of its edges). Any finite input.
TriangleTetrahedronContact classify_triangle_tetrahedron(const Triangle& t,
                                                         const Tetrahedron& tetrahedron);

/// Exact: the closed triangle meets the closed solid tetrahedron (false for a degenerate
/// tetrahedron).
inline bool triangle_intersects_tetrahedron(const Triangle& t, const Tetrahedron& tetrahedron) {
  const auto c = classify_triangle_tetrahedron(t, tetrahedron);
  return c == TriangleTetrahedronContact::intersects || c == TriangleTetrahedronContact::contained;
}

}  // namespace tetrapage::geometry
