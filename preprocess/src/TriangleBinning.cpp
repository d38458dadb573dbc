#include "tetrapage/preprocess/TriangleBinning.h"

#include <algorithm>
#include <cstdio>
#include <string>

#include "tetrapage/formats/Error.h"
#include "tetrapage/runtime/MeshWalk.h"
#include "tetrapage/runtime/geometry/Box.h"
#include "tetrapage/runtime/geometry/PointTetrahedron.h"
#include "tetrapage/runtime/geometry/TriangleTetrahedron.h"

namespace tetrapage {

void bin_triangle(const TetMesh& mesh, const geometry::Triangle& triangle,
                  BinningScratch& scratch, std::vector<std::uint32_t>& tets) {
  if (scratch.hint >= mesh.tet_count()) scratch.hint = 0;
  // A tet holding the first corner: the last triangle's, as a rule (input order is coherent
  // and a region holds thousands of triangles), else the walk's. Testing that tet is a fifth
  // of a walk's predicates.
  std::uint32_t start = scratch.hint;
  geometry::TetrahedronPosition position =
      geometry::locate_in_tetrahedron(triangle[0], mesh.corners(start)).position;
  if (position == geometry::TetrahedronPosition::outside ||
      position == geometry::TetrahedronPosition::degenerate_tetrahedron) {
    const WalkResult located = locate_point(mesh, scratch.hint, triangle[0]);
    if (located.tet == TetMesh::no_neighbour) {
      char text[160];
      std::snprintf(text, sizeof text, "triangle vertex (%.17g, %.17g, %.17g) lies outside the coarse mesh",
                    triangle[0][0], triangle[0][1], triangle[0][2]);
      throw InputError(text);
    }
    start = located.tet;
    position = located.location.position;
    scratch.hint = start;
  }
  // Most triangles lie strictly inside one tet: all three corners in its open interior put the
  // whole triangle there (the tet is convex), and the closed neighbours meet it only on their
  // common faces.
  if (position == geometry::TetrahedronPosition::inside) {
    const auto corners = mesh.corners(start);
    if (geometry::locate_in_tetrahedron(triangle[1], corners).position ==
            geometry::TetrahedronPosition::inside &&
        geometry::locate_in_tetrahedron(triangle[2], corners).position ==
            geometry::TetrahedronPosition::inside) {
      tets.push_back(start);
      return;
    }
  }
  const geometry::Box box = geometry::box_of(triangle);
  const std::size_t first = tets.size();
  auto& queue = scratch.queue;
  queue.clear();
  queue.push_back(start);
  // queue holds every tet seen; [0, next) have been tested. Triangles meet few tets, so a
  // linear membership test beats a hash set.
  for (std::size_t next = 0; next < queue.size(); ++next) {
    const std::uint32_t tet = queue[next];
    const auto corners = mesh.corners(tet);
    const geometry::Box tet_box = geometry::box_of(corners);
    if (!geometry::boxes_overlap(box, tet_box)) continue;
    ++scratch.tet_tests;
    if (!geometry::triangle_intersects_tetrahedron(triangle, corners)) continue;
    tets.push_back(tet);
    for (const std::uint32_t neighbour : mesh.neighbours[tet]) {
      if (neighbour == TetMesh::no_neighbour) continue;
      if (std::find(queue.begin(), queue.end(), neighbour) == queue.end()) queue.push_back(neighbour);
    }
  }
  std::sort(tets.begin() + std::ptrdiff_t(first), tets.end());
}

}  // namespace tetrapage
