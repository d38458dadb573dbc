#include "tetrapage/preprocess/TriangleBinning.h"

#include <algorithm>
#include <cstdio>
#include <string>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/runtime/geometry/Box.h"
#include "tetrapage/runtime/geometry/PointTetrahedron.h"
#include "tetrapage/runtime/geometry/TriangleTetrahedron.h"
#include "tetrapage/runtime/query/MeshWalk.h"

namespace tetrapage {

namespace {

enum class Side : std::uint8_t { outside, boundary, inside };

// Where p lies against the tet whose planes the scratch holds (exact: the planes' side tests
// are orient3d's).
Side side_of(const BinningScratch& scratch, const geometry::Point& p) {
  Side side = Side::inside;
  for (const auto& plane : *scratch.planes) {
    const geometry::Sign s = plane.side(p) * scratch.orientation;
    if (s == geometry::Sign::negative) return Side::outside;
    if (s == geometry::Sign::zero) side = Side::boundary;
  }
  return side;
}

void prepare_planes(const TetMesh& mesh, std::uint32_t tet, BinningScratch& scratch) {
  if (scratch.planes_tet == tet) return;
  const auto t = mesh.corners(tet);
  const auto plane = [&](int k) {
    const auto& f = geometry::kTetrahedronFaces[k];
    return geometry::OrientedPlane(t[f[0]], t[f[1]], t[f[2]]);
  };
  scratch.planes.emplace(std::array{plane(0), plane(1), plane(2), plane(3)});
  scratch.orientation = geometry::orient3d(t[0], t[1], t[2], t[3]);
  scratch.planes_tet = tet;
}

}  // namespace

void bin_triangle(const TetMesh& mesh, const geometry::Triangle& triangle, BinningScratch& scratch,
                  std::vector<std::uint32_t>& tets) {
  if (scratch.hint >= mesh.tet_count()) scratch.hint = 0;
  // A tet holding the first corner: the last triangle's, as a rule (triangles come in Morton
  // order), else the walk's. The last tet's face planes are kept: a corner's test against them
  // is four dot products in the common case, a walk dozens of predicates.
  std::uint32_t start = scratch.hint;
  prepare_planes(mesh, start, scratch);
  Side corner0 =
      scratch.orientation == geometry::Sign::zero ? Side::outside : side_of(scratch, triangle[0]);
  if (corner0 == Side::outside) {
    const WalkResult located = locate_point(mesh, scratch.hint, triangle[0]);
    if (located.tet == TetMesh::no_neighbour) {
      char text[160];
      std::snprintf(text, sizeof text,
                    "triangle vertex (%.17g, %.17g, %.17g) lies outside the coarse mesh",
                    triangle[0][0], triangle[0][1], triangle[0][2]);
      throw InputError(text);
    }
    start = located.tet;
    scratch.hint = start;
    prepare_planes(mesh, start, scratch);
    corner0 = located.location.position == geometry::TetrahedronPosition::inside ? Side::inside
                                                                                 : Side::boundary;
  }
  // Most triangles lie strictly inside one tet: all three corners in its open interior put the
  // whole triangle there (the tet is convex), and the closed neighbours meet it only on their
  // common faces.
  if (corner0 == Side::inside && side_of(scratch, triangle[1]) == Side::inside &&
      side_of(scratch, triangle[2]) == Side::inside) {
    tets.push_back(start);
    return;
  }
  const geometry::Box box = geometry::box_of(triangle);
  const std::size_t first = tets.size();
  auto& queue = scratch.queue;
  queue.clear();
  queue.push_back(start);
  // queue holds every tet seen; [0, next) have been tested. Triangles meet few tets, so a
  // linear membership test beats a hash set.
  // The start tet holds the first corner (in its interior or on its boundary), so the closed
  // triangle meets it: no test (a fifth of the exact tests at 10M).
  const bool start_met = corner0 != Side::outside && scratch.orientation != geometry::Sign::zero;
  for (std::size_t next = 0; next < queue.size(); ++next) {
    const std::uint32_t tet = queue[next];
    if (next > 0 || !start_met) {
      const auto corners = mesh.corners(tet);
      const geometry::Box tet_box = geometry::box_of(corners);
      if (!geometry::boxes_overlap(box, tet_box)) continue;
      ++scratch.tet_tests;
      if (!geometry::triangle_intersects_tetrahedron(triangle, corners)) continue;
    }
    tets.push_back(tet);
    for (const std::uint32_t neighbour : mesh.neighbours[tet]) {
      if (neighbour == TetMesh::no_neighbour) continue;
      if (std::find(queue.begin(), queue.end(), neighbour) == queue.end())
        queue.push_back(neighbour);
    }
  }
  std::sort(tets.begin() + std::ptrdiff_t(first), tets.end());
}

}  // namespace tetrapage
