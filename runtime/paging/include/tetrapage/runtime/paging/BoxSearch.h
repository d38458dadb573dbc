#pragma once
/// @file BoxSearch.h
/// The tets of the coarse mesh that overlap a box (step 3 of the runtime): a breadth-first
/// search over face neighbours from one tet that overlaps the box, keeping every tet whose
/// closed region meets the closed box, decided exactly.
///
/// Why the search misses nothing: the box meets the (convex) mesh in a convex set; the tets
/// around any vertex, edge or face of a valid tet mesh are connected through shared faces and
/// all meet that set wherever it touches the feature, so the tets meeting it are connected
/// through shared faces too.

#include <cstdint>
#include <span>
#include <vector>

#include "tetrapage/formats/index/TetMesh.h"
#include "tetrapage/runtime/geometry/Box.h"
#include "tetrapage/runtime/paging/TetBoxFilter.h"

namespace tetrapage {

namespace geometry {

/// Exact: the closed solid tetrahedron (either orientation) meets the closed box. Separating
/// axes with exact signs: the box's axes, the tetrahedron's four face normals and the
/// eighteen products of its edges with the box's axes. A degenerate (flat) tetrahedron is
/// tested as the convex hull of its vertices; an empty box meets nothing.
bool tetrahedron_intersects_box(const Tetrahedron& t, const Box& box);

}  // namespace geometry

class BoxSearchScratch;

/// The answer of tets_overlapping_box.
struct BoxSearchResult {
  /// The tets whose closed region meets the closed box, in breadth-first order from the start
  /// tet. A view into the scratch: valid until its next use.
  std::span<const std::uint32_t> tets;
  /// Tets reached by the search (the found ones and their neighbours that were rejected).
  std::uint32_t tets_visited = 0;
  /// Tets whose bounding box overlapped the box, so that the exact test ran.
  std::uint32_t exact_tests = 0;
};

/// Reusable state of tets_overlapping_box: visit stamps per tet and the result buffer. Once
/// grown to the mesh and to the largest answer, queries allocate nothing. One scratch per
/// thread; it may serve several meshes.
class BoxSearchScratch {
 public:
  BoxSearchScratch() = default;

 private:
  friend BoxSearchResult tets_overlapping_box(const TetMesh&, std::uint32_t, const geometry::Box&,
                                              BoxSearchScratch&);
  friend BoxSearchResult tets_near_box(const TetMesh&, const TetBoxFilter&, std::uint32_t, const geometry::Box&,
                                       BoxSearchScratch&);
  std::vector<std::uint32_t> stamps_;  ///< stamps_[tet] == stamp_: reached in this query
  std::uint32_t stamp_ = 0;
  std::vector<std::uint32_t> found_;  ///< the answer, which is also the breadth-first queue
};

/// Every tet whose closed region meets the closed box, found by breadth-first search from
/// start_tet, which must meet the box (for example the tet that locate_point found for a
/// corner of the box). An empty box (lo > hi on some axis) gives an empty answer.
/// @throw InputError if start_tet is out of range, the box is not finite, or start_tet does
///        not meet a non-empty box.
BoxSearchResult tets_overlapping_box(const TetMesh& mesh, std::uint32_t start_tet,
                                     const geometry::Box& box, BoxSearchScratch& scratch);

/// The same breadth-first search with a cheap conservative test instead of the exact one (the
/// filter's bounding boxes overlap and no face plane separates): a superset of
/// tets_overlapping_box's answer (exact_tests stays 0), for callers that only need to cover the
/// box (the flying object's searched region).
/// @throw InputError as tets_overlapping_box (the start tet must pass the filter), or if the
///        filter was not made for a mesh of as many tets.
BoxSearchResult tets_near_box(const TetMesh& mesh, const TetBoxFilter& filter, std::uint32_t start_tet,
                              const geometry::Box& box, BoxSearchScratch& scratch);

}  // namespace tetrapage
