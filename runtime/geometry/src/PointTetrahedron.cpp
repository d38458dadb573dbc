#include "tetrapage/runtime/geometry/PointTetrahedron.h"

namespace tetrapage::geometry {

TetrahedronLocation locate_in_tetrahedron(const Point& p, const Tetrahedron& t) {
  const Sign orientation = orient3d(t[0], t[1], t[2], t[3]);
  if (orientation == Sign::zero) return {TetrahedronPosition::degenerate_tetrahedron, 0};
  const auto s = face_signs(p, t);
  std::uint8_t vertices = 0b1111;
  int zeros = 0;
  for (int k = 0; k < 4; ++k) {
    const Sign side = s[k] * orientation;
    if (side == Sign::negative) return {TetrahedronPosition::outside, 0};
    if (side == Sign::zero) {
      ++zeros;
      vertices &= static_cast<std::uint8_t>(~(1u << k));  // on face k: vertex k is not needed
    }
  }
  switch (zeros) {
    case 0:
      return {TetrahedronPosition::inside, vertices};
    case 1:
      return {TetrahedronPosition::on_face, vertices};
    case 2:
      return {TetrahedronPosition::on_edge, vertices};
    default:
      return {TetrahedronPosition::on_vertex, vertices};  // three zeros (four cannot be)
  }
}

bool point_in_tetrahedron_perturbed(const Point& p, const Tetrahedron& t) {
  const Sign orientation = orient3d(t[0], t[1], t[2], t[3]);
  if (orientation == Sign::zero) return false;
  for (int k = 0; k < 4; ++k) {
    const auto& f = kTetrahedronFaces[k];
    if (orient3d_perturbed_query(t[f[0]], t[f[1]], t[f[2]], p) != orientation) return false;
  }
  return true;
}

}  // namespace tetrapage::geometry
