#pragma once
/// @file ObjectModel.h
/// What a flying object is, whatever the index and the pose: its triangles, their BVH, whether
/// the surface is closed and then its interior grid, and the vertex graph of its convex hull
/// (for the world box by hill-climbing). Built once, tens of milliseconds for 15,000 triangles,
/// and immutable afterwards: any number of FlyingObjects (one per thread, on one index or
/// several) share one model, and a model can be built while an index opens.

#include <cstdint>
#include <mutex>
#include <utility>
#include <vector>

#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/runtime/geometry/ObjectBVH.h"
#include "tetrapage/runtime/query/ObjectInteriorGrid.h"

namespace tetrapage {

class ObjectModel {
 public:
  /// @throw InputError for an empty object, non-finite coordinates, an index out of range (as
  ///        ObjectBVH), a coordinate beyond kMaxCoordinateMagnitude (its placement could
  ///        overflow), or an object whose every triangle has zero area.
  explicit ObjectModel(TriangleSoup object);

  /// Read-only after construction (models are shared as std::shared_ptr<const ObjectModel>).
  const TriangleSoup mesh;
  const geometry::ObjectBVH bvh;
  double radius = 0;  ///< largest |x| over the vertices (object frame)
  BoundingBox box;    ///< of the vertices (object frame)
  /// A ball holding every vertex (object frame): centred on the box, its radius the largest
  /// distance to the centre, rounded up.
  Vec3 ball_centre{};
  double ball_radius = 0;
  /// The ball is much tighter than the box (a round object: under 0.7 of its volume), so
  /// phase I asks it of leaves and candidates before the object's BVH.
  bool ball_prunes = false;
  /// Some connected component of the object is closed (every edge used an even number of
  /// times, SurfaceComponents.h): only then can an obstacle lie inside the object.
  bool closed = false;
  /// The closed component of each triangle (an object may hold several solids, and open ones).
  ClosedComponentOf closed_components;
  /// One vertex of each connected component, closed or open: with no surface contact, each
  /// decides whether its whole component lies inside an obstacle.
  std::vector<std::uint32_t> component_vertices;
  ObjectInteriorGrid interior_grid;  ///< closed objects only: inside some closed component, by cell
  /// The convex hull as a vertex graph: object vertex ids, and per hull vertex its neighbours
  /// (CSR, indices into hull_vertices). Without a usable 3D hull, every vertex and no graph.
  std::vector<std::uint32_t> hull_vertices;
  std::vector<std::uint32_t> hull_offsets, hull_neighbours;
  /// For a hull of at most 24 facets with volume: each facet's outward unit normal n and offset
  /// (n.x <= offset holds the object, up to rounding), a cheap test that prunes what lies
  /// beyond; empty otherwise.
  std::vector<std::pair<Vec3, double>> hull_planes;

  /// The vertices whose placed positions span the hull of the placed object (for the hull and
  /// swept solids): the hull's own vertices, then the other vertices by their depth inside it,
  /// ascending. A vertex deeper than the placement's rounding stays inside the hull of the
  /// placed candidates. Computed on the first call (a hull and a plane test per vertex, tens
  /// of milliseconds for 15,000 triangles: only hull and swept queries need it), then shared.
  struct HullCandidates {
    std::vector<std::uint32_t> on_hull;
    std::vector<std::pair<double, std::uint32_t>> near_hull;  ///< (depth, vertex), ascending
  };
  const HullCandidates& hull_candidates() const;

 private:
  mutable std::once_flag hull_candidates_once_;
  mutable HullCandidates hull_candidates_;
};

}  // namespace tetrapage
