#pragma once
/// @file TriangleBinning.h
/// Exact binning: the tets of the coarse mesh that a triangle really meets.

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "tetrapage/formats/index/TetMesh.h"
#include "tetrapage/runtime/geometry/Predicates.h"
#include "tetrapage/runtime/geometry/Shapes.h"

namespace tetrapage {

/// Reusable per-thread state of the binning search.
struct BinningScratch {
  std::uint32_t hint = 0;  ///< where the next point location starts (the last tet found)
  std::vector<std::uint32_t> queue;
  std::uint64_t tet_tests = 0;  ///< exact triangle/tet tests run
  /// The face planes of tet `planes_tet` (most triangles test their corners against the same
  /// tet as the last one) and the sign of its orientation. Keyed by their own tet, not taken to
  /// be `hint`'s, so that a caller moving the hint cannot make them stale.
  std::uint32_t planes_tet = TetMesh::no_neighbour;
  std::optional<std::array<geometry::OrientedPlane, 4>> planes;
  geometry::Sign orientation = geometry::Sign::zero;
};

/// Appends to `tets` every tet whose closed region meets the closed triangle (exact
/// triangle/tetrahedron test). Breadth-first over face neighbours from the tet that holds the
/// first vertex: the tets a connected triangle meets are face-connected, because moving along
/// the triangle from one tet to the next crosses a face, an edge or a vertex, and the tets
/// around an edge or a vertex are face-connected and all meet the triangle there.
/// @throw InputError when the first vertex lies outside the mesh (naming it).
void bin_triangle(const TetMesh& mesh, const geometry::Triangle& triangle,
                  BinningScratch& scratch, std::vector<std::uint32_t>& tets);

}  // namespace tetrapage
