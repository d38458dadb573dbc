#pragma once
/// @file ObstacleInterior.h
/// Whether a point lies inside a closed obstacle, from the interiors stored in the index (the
/// study's footnote 3): locate the point's tet by walking, then count the crossings between
/// the tet's own triangles and the segment from the tet's reference point (whose closed components
/// the preprocess classified) to the point. The tet is convex, so the segment never leaves it
/// and every triangle it can cross is in the tet's shard: no ray through the whole model.
/// Crossings are decided exactly on the stored triangles; a segment that meets a triangle's
/// edge or vertex, or lies in its plane, is bent through another point strictly inside the tet
/// (parity along a closed surface does not depend on the path).
#include <cstdint>
#include <span>
#include <vector>

#include "tetrapage/runtime/geometry/Shapes.h"
#include "tetrapage/runtime/paging/CollisionIndex.h"

namespace tetrapage {

enum class ObstacleContainment : std::uint8_t {
  outside,     ///< in no closed component (or outside the coarse mesh, which encloses every obstacle)
  inside,      ///< inside closed component `component`
  on_surface,  ///< on a stored triangle of a closed component
  unknown,  ///< the index has no interiors, or the tet is undecided, or every path was degenerate
};

struct ObstacleQuery {
  ObstacleContainment containment = ObstacleContainment::unknown;
  std::uint32_t component = 0;       ///< when inside: one closed component holding the point
  std::uint32_t tet = 0;             ///< the tet that holds the point (unless outside the mesh)
  std::uint32_t paths_tried = 0;     ///< segments from the reference point (1 unless degenerate)
  std::uint64_t triangle_tests = 0;  ///< exact segment/triangle tests
};

/// Locates p from hint_tet (updated to p's tet, so that the next call walks from there) and
/// decides whether it is inside a closed obstacle. Pages in the tet's shard when it has one.
/// @throw InputError for a non-finite p or a hint out of range; what the shard cache throws.
ObstacleQuery locate_in_obstacles(const CollisionIndex& index, std::uint32_t& hint_tet,
                                  const geometry::Point& p);

/// The last point decided inside or outside, with its tet and the closed components holding it:
/// a point of the same tet is then decided from it (parity along the short segment between
/// them) instead of from the tet's reference point, whose segment meets far more triangles.
struct ObstacleMemo {
  bool valid = false;
  std::uint32_t tet = 0;
  geometry::Point point{};
  std::vector<std::uint32_t> components;
};

using ShardPin = ShardCache<Shard>::Pin;

/// The same answer, using and updating `memo` (one per moving point, e.g. per flying object).
/// A shard among `held` (pins the caller keeps, e.g. a flying object's region) is read from
/// there rather than acquired again from the cache.
ObstacleQuery locate_in_obstacles(const CollisionIndex& index, std::uint32_t& hint_tet,
                                  const geometry::Point& p, ObstacleMemo& memo,
                                  std::span<const ShardPin> held = {});

}  // namespace tetrapage
