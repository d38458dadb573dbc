#pragma once
/// @file PointTetrahedron.h
/// Where a point lies relative to a tetrahedron: exactly (inside, on a face, an edge, a vertex,
/// outside), and with the query point symbolically perturbed (strictly inside or outside, never
/// on the boundary), which is what a mesh walk uses so that a point on a face shared by two
/// tetrahedra is accepted by exactly one of them.

#include <array>
#include <cstdint>

#include "tetrapage/runtime/geometry/Predicates.h"

namespace tetrapage::geometry {

enum class TetrahedronPosition : std::uint8_t {
  outside,
  inside,                  ///< in the open interior
  on_face,                 ///< in the relative interior of a face
  on_edge,                 ///< in the relative interior of an edge
  on_vertex,               ///< equal to a vertex
  degenerate_tetrahedron,  ///< the four vertices are coplanar: no answer
};

/// A classified location. `vertices` has bit v set for each vertex v of the smallest closed
/// feature holding the point: all four when inside, three for a face (the face opposite the
/// missing vertex), two for an edge, one for a vertex, none when outside.
struct TetrahedronLocation {
  TetrahedronPosition position = TetrahedronPosition::outside;
  std::uint8_t vertices = 0;

  /// The face index (the vertex opposite it) when position == on_face.
  int face() const {
    for (int k = 0; k < 4; ++k)
      if (!(vertices & (1u << k))) return k;
    return -1;
  }
};

/// Vertex indices of face k (opposite vertex k), ordered so that
/// orient3d(face vertices..., v_k) == orient3d(v0, v1, v2, v3).
inline constexpr std::array<std::array<int, 3>, 4> kTetrahedronFaces = {
    {{1, 3, 2}, {0, 2, 3}, {0, 3, 1}, {0, 1, 2}}};

/// The exact signs of p against the four faces, positive on the side of the opposite vertex
/// (for a positively oriented tetrahedron; all flipped for a negatively oriented one).
inline std::array<Sign, 4> face_signs(const Point& p, const Tetrahedron& t) {
  std::array<Sign, 4> s;
  for (int k = 0; k < 4; ++k) {
    const auto& f = kTetrahedronFaces[k];
    s[k] = orient3d(t[f[0]], t[f[1]], t[f[2]], p);
  }
  return s;
}

/// Exact classification of p against the closed tetrahedron t (either orientation).
TetrahedronLocation locate_in_tetrahedron(const Point& p, const Tetrahedron& t);

/// The exact face signs of p perturbed by (e, e^2, e^4) (see orient3d_perturbed_query): never
/// zero for a non-degenerate tetrahedron. Multiply by the tetrahedron's orientation for a
/// negatively oriented one.
inline std::array<Sign, 4> face_signs_perturbed(const Point& p, const Tetrahedron& t) {
  std::array<Sign, 4> s;
  for (int k = 0; k < 4; ++k) {
    const auto& f = kTetrahedronFaces[k];
    s[k] = orient3d_perturbed_query(t[f[0]], t[f[1]], t[f[2]], p);
  }
  return s;
}

/// True when p, perturbed as above, is strictly inside t (either orientation). For the
/// tetrahedra of a triangulation, a point covered by them is accepted by exactly one.
/// A degenerate tetrahedron accepts nothing.
bool point_in_tetrahedron_perturbed(const Point& p, const Tetrahedron& t);

/// For a walk: a face of the positively oriented tetrahedron t through which the perturbed p
/// is strictly outside (the walk steps into the neighbour across it), or -1 when p is inside.
/// Faces are tried starting from `first_face` (0..3), so a walk can rotate its choice.
inline int exit_face_perturbed(const Point& p, const Tetrahedron& t, int first_face = 0) {
  for (int i = 0; i < 4; ++i) {
    const int k = (first_face + i) & 3;
    const auto& f = kTetrahedronFaces[k];
    if (orient3d_perturbed_query(t[f[0]], t[f[1]], t[f[2]], p) == Sign::negative) return k;
  }
  return -1;
}

}  // namespace tetrapage::geometry
