#pragma once
/// @file DistanceSearch.h (private)
/// The distance query's search: environment triangles near the placed object, measured
/// against the object's BVH nearest first, within a reach that shrinks as closer pairs are
/// found; it starts from the last step's closest pair (poses are coherent) and otherwise
/// grows its reach until a triangle is found.

#include <cstdint>
#include <vector>

#include "PlacedObject.h"
#include "SearchedRegion.h"
#include "tetrapage/runtime/geometry/TriangleDistance.h"
#include "tetrapage/runtime/paging/CollisionIndex.h"
#include "tetrapage/runtime/query/DynamicObstacles.h"
#include "tetrapage/runtime/query/ObjectModel.h"
#include "tetrapage/runtime/query/Query.h"
#include "tetrapage/runtime/query/TriangleIdSet.h"

namespace tetrapage {

class DistanceSearch {
 public:
  explicit DistanceSearch(const CollisionIndex& index) : index_(&index), region_(index) {}

  /// The distance from the object placed in `object` (world box `world_box`), known to touch
  /// nothing, to the environment, within `max_distance`: fills `result` (apart or farther).
  /// Dynamic obstacles (null: none) count too, and their hidden parts do not.
  void measure(const ObjectModel& model, PlacedObject& object, const geometry::Box& world_box,
               double max_distance, const DynamicObstacles* obstacles, DistanceResult& result);
  /// The closest pair is unknown (the object touched something, or the index changed hands).
  void forget_last_pair() { has_last_ = false; }

 private:
  struct Pair {
    geometry::TriangleDistance distance;
    geometry::Triangle environment;
    ContactSite site;  ///< no component
  };
  // The triangles that meet `search_box` (the world box grown by the search's radius), from
  // the searched region's shards or, for a box centred beyond the coarse mesh, from every
  // shard whose bounds meet it.
  void measure_within(const geometry::Box& search_box);
  // The answer, from the closest pair found.
  void report(double max_distance);
  // The environment triangle against the object's BVH, nearest first.
  void measure_triangle(const geometry::Triangle& environment, std::uint64_t id,
                        std::uint32_t part, std::uint32_t dynamic_part);
  void offer(const geometry::TriangleDistance& distance, const geometry::Triangle& environment,
             std::uint64_t id, std::uint32_t part, std::uint32_t object_triangle,
             std::uint32_t dynamic_part);
  // The dynamic obstacles' triangles within reach, after the index's.
  void measure_dynamic_parts(const DynamicObstacles& obstacles);
  // Collects the shard's triangles that may lie within reach into pending_.
  void collect_shard(const Shard& shard, const geometry::Box& search_box);
  // Measures pending_ nearest first, until the next lies beyond the reach.
  void measure_pending();
  // A lower bound on the distance from the object to a box (its world box's and its ball's).
  double lower_bound_to(const geometry::Box& box) const;

  const CollisionIndex* index_;
  SearchedRegion region_;
  TriangleIdSet met_;
  struct Pending {
    double lower_bound;
    geometry::Triangle environment;
    std::uint64_t id;
    std::uint32_t part;
  };
  const DynamicObstacles* obstacles_ = nullptr;
  std::uint64_t obstacles_version_ = 0;  ///< the overlay's version of the last pair
  std::vector<Pending> pending_;  ///< the candidates of a search, measured nearest first
  geometry::Point ball_centre_{};  ///< the object's bounding ball, placed
  double ball_radius_ = 0;         ///< with the placement's rounding
  // The query in progress.
  const ObjectModel* model_ = nullptr;
  PlacedObject* object_ = nullptr;
  geometry::Box world_box_;
  double reach_ = 0;          ///< pairs farther than this cannot be the closest
  double lowest_bound_ = 0;   ///< the least lower bound of the pairs measured
  double lowest_upper_ = 0;   ///< the least upper bound of the pairs measured
  bool found_ = false;
  Pair best_;
  Vec3 axis_{};  ///< from the best pair's environment point to its object point
  DistanceResult* result_ = nullptr;
  // The last step's closest pair: the environment triangle (its stored corners) and the
  // object's triangle.
  bool has_last_ = false;
  Pair last_;
};

}  // namespace tetrapage
