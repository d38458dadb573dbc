#include "tetrapage/runtime/geometry/TriangleTetrahedron.h"

#include "tetrapage/runtime/geometry/PointTetrahedron.h"
#include "tetrapage/runtime/geometry/Predicates.h"
#include "tetrapage/runtime/geometry/SegmentTriangle.h"

namespace tetrapage::geometry {

TriangleTetrahedronContact classify_triangle_tetrahedron(const Triangle& t,
                                                         const Tetrahedron& tetrahedron) {
  const Sign orientation = orient3d(tetrahedron[0], tetrahedron[1], tetrahedron[2], tetrahedron[3]);
  if (orientation == Sign::zero) return TriangleTetrahedronContact::degenerate_tetrahedron;

  // Sides of the triangle's vertices against the four face planes (positive: inner side).
  bool vertex_inside[3] = {true, true, true};
  for (int k = 0; k < 4; ++k) {
    const auto& f = kTetrahedronFaces[k];
    const OrientedPlane face(tetrahedron[f[0]], tetrahedron[f[1]], tetrahedron[f[2]]);
    int outside = 0;
    for (int v = 0; v < 3; ++v)
      if (face.side(t[v]) * orientation == Sign::negative) {
        vertex_inside[v] = false;
        ++outside;
      }
    if (outside == 3) return TriangleTetrahedronContact::none;  // the face plane separates
  }
  if (vertex_inside[0] && vertex_inside[1] && vertex_inside[2])
    return TriangleTetrahedronContact::contained;
  if (vertex_inside[0] || vertex_inside[1] || vertex_inside[2])
    return TriangleTetrahedronContact::intersects;

  // The triangle's plane separates when all four vertices lie strictly on one side.
  const OrientedPlane plane(t);
  const Sign s0 = plane.side(tetrahedron[0]);
  if (s0 != Sign::zero && s0 == plane.side(tetrahedron[1]) && s0 == plane.side(tetrahedron[2]) &&
      s0 == plane.side(tetrahedron[3]))
    return TriangleTetrahedronContact::none;

  // No triangle vertex inside: they meet iff an edge of the triangle crosses a face, or an edge
  // of the tetrahedron crosses the triangle.
  for (int e = 0; e < 3; ++e) {
    const Segment edge{t[e], t[e == 2 ? 0 : e + 1]};
    for (int k = 0; k < 4; ++k) {
      const auto& f = kTetrahedronFaces[k];
      if (segment_intersects_triangle(edge,
                                      {tetrahedron[f[0]], tetrahedron[f[1]], tetrahedron[f[2]]}))
        return TriangleTetrahedronContact::intersects;
    }
  }
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j)
      if (segment_intersects_triangle({tetrahedron[i], tetrahedron[j]}, t))
        return TriangleTetrahedronContact::intersects;
  return TriangleTetrahedronContact::none;
}

}  // namespace tetrapage::geometry
