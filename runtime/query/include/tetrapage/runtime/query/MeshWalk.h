#pragma once
/// @file MeshWalk.h
/// Point location in the coarse tet mesh by a straight-line walk (ray shooting, as in section
/// 2.1 of the study): from a point strictly inside the start tet, march along the segment to
/// the target, stepping into the neighbour across the face the segment leaves through, until
/// the current tet holds the target.
///
/// Every step is decided by exact orientation signs, with all ties broken by Simulation of
/// Simplicity (orient3d_sos): the walk's source, its target and every mesh vertex carry
/// distinct symbolic ranks, so the walk behaves as if the segment passed through no vertex or
/// edge and the target lay on no face. A line crosses a convex tet at most once, so the walk
/// visits each tet at most once and always terminates, even along rays through vertices and
/// edges; every answer is checked against the closed (unperturbed) tet.
///
/// Preconditions on the mesh (a TetMesh built by build_coarse_mesh meets them): finite
/// coordinates, positively oriented non-degenerate tets, consistent neighbours, and a convex
/// union (the Delaunay tetrahedralisation of the sites), so that leaving through a hull face
/// means the target is outside the mesh.

#include <cstdint>
#include <optional>
#include <vector>

#include "tetrapage/formats/index/TetMesh.h"
#include "tetrapage/runtime/geometry/PointTetrahedron.h"

namespace tetrapage {

/// Where a walk ended.
struct WalkResult {
  /// A tet whose closed region holds the point, or TetMesh::no_neighbour when the point is
  /// outside the mesh.
  std::uint32_t tet = TetMesh::no_neighbour;
  /// Faces crossed from the start tet to `tet` (0 when the start tet holds the point). When
  /// the point is outside, the faces crossed before the walk reached the hull.
  std::uint32_t tets_crossed = 0;
  /// The exact position of the point in `tet` (inside, on a face, edge or vertex of it);
  /// position == outside when tet == no_neighbour.
  geometry::TetrahedronLocation location;
};

/// A point with double coordinates strictly inside the tet (the rounded centroid, or a point
/// near it), which walks from that tet start at; nullopt when rounding leaves no such point
/// (a sliver thinner than the coordinates' precision).
/// @throw InputError if tet is not a tet of the mesh.
std::optional<geometry::Point> walk_reference_point(const TetMesh& mesh, std::uint32_t tet);

/// Locate p by walking the straight segment from the reference point of start_tet to p (when
/// the start tet has none, from the nearest tet, in breadth-first order, that has one).
/// p on a face, edge or vertex is held by any of the tets around it; the walk returns one.
/// @throw InputError if start_tet is out of range, the mesh has no tet, or p is not finite.
/// @throw Error if no tet of the mesh has an interior reference point, or if the walk exceeds
///        tet_count() + 1 steps (an invalid mesh: inverted tets or inconsistent neighbours).
WalkResult locate_point(const TetMesh& mesh, std::uint32_t start_tet, const geometry::Point& p);

/// The tets a segment passes through, in order.
struct SegmentWalk {
  /// From a tet holding a to a tet holding b; consecutive tets share a face. Each one meets
  /// the closed segment. Where the segment touches an edge or a vertex, the walk passes
  /// through one consistent choice of the tets around it.
  std::vector<std::uint32_t> tets;
  /// The faces crossed while locating a from the start tet (not part of the segment).
  std::uint32_t tets_crossed_to_locate_a = 0;
  /// False when part of the segment lies outside the mesh: `tets` then stops where the
  /// segment leaves it (and is empty when a is outside, or lies on the hull where the tie
  /// rule puts it outside).
  bool complete = false;
};

/// Walk the segment a -> b: locate a from start_tet, then follow the segment to b. With
/// tets.size() - 1 faces crossed over |b - a|, this gives the stabbing number of the mesh
/// along the segment.
/// @throw InputError if start_tet is out of range, the mesh has no tet, or a or b is not finite.
/// @throw Error as locate_point.
SegmentWalk walk_segment(const TetMesh& mesh, std::uint32_t start_tet, const geometry::Point& a,
                         const geometry::Point& b);

}  // namespace tetrapage
