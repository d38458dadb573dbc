#pragma once
/// @file ContainmentCheck.h (private)
/// Containment, for a step whose surfaces do not touch: is a component of the object inside a
/// closed obstacle (the index's interiors), or a component of the environment inside a closed
/// component of the object?

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "PlacedObject.h"
#include "StepClock.h"
#include "tetrapage/runtime/geometry/Box.h"
#include "tetrapage/runtime/paging/CollisionIndex.h"
#include "tetrapage/runtime/query/DynamicObstacles.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/runtime/query/ObjectModel.h"
#include "tetrapage/runtime/query/ObstacleInterior.h"

namespace tetrapage {

/// Does the closed `model`, placed as `object`, hold the world point p? By the parity of
/// crossings along segments reaching beyond `box` (a world box holding the placed object), for
/// when the interior grid cannot tell: p must not lie on the object's surface. Also used for
/// one flying object inside another (ObjectGroup).
bool crossing_parity_holds(const ObjectModel& model, PlacedObject& object, const geometry::Point& p,
                           const geometry::Box& box);

class ContainmentCheck {
 public:
  ContainmentCheck(const CollisionIndex& index, const ObjectModel& model)
      : index_(&index), model_(&model) {}

  /// The dynamic obstacles of the next steps (null: none): their hidden parts hold nothing.
  void begin_step(const DynamicObstacles* overlay) {
    enclosed_.clear();
    overlay_ = overlay;
  }
  /// An environment component whose box lies in the object's box (only those can lie inside
  /// the object), with a vertex of a candidate triangle of it.
  void note_enclosed(std::uint32_t component, const geometry::Point& vertex) {
    // One vertex decides a component; a shard lists a component's triangles together (a
    // tetrahedron's box on the 100M scene noted 100,000 a step, 3 MB).
    if (!enclosed_.empty() && enclosed_.back().first == component) return;
    enclosed_.emplace_back(component, vertex);
  }
  /// Both checks for the step whose box is `box`, the object placed as `object`; `pins`: the
  /// shards the walks may read without pinning; `start`: now, for its clock.
  void check(const geometry::Box& box, PlacedObject& object, std::span<const ShardPin> pins,
             QueryResult& result, Clock::time_point start);
  /// The same against the dynamic obstacles whose boxes meet `box`: the object inside a closed
  /// one, or (unless `solid_query`: the solid's own test found those) one inside the object.
  /// `placed`: scratch, rebound to each obstacle.
  void check_dynamic(const geometry::Box& box, PlacedObject& object, PlacedObject& placed,
                     bool solid_query, QueryResult& result);

 private:
  void check_object_inside_obstacle(PlacedObject& object, std::span<const ShardPin> pins,
                                    QueryResult& result);
  void check_obstacle_inside_object(const geometry::Box& box, PlacedObject& object,
                                    QueryResult& result);
  const CollisionIndex* index_;
  const ObjectModel* model_;
  const DynamicObstacles* overlay_ = nullptr;
  // Per step: the environment components whose boxes lie in the object's box (only those can
  // lie inside the object), each with a vertex of a candidate triangle of theirs.
  std::vector<std::pair<std::uint32_t, geometry::Point>> enclosed_;
  // Per object component: where its last containment walk ended, and its last answer.
  std::vector<std::uint32_t> interior_tets_;
  std::vector<ObstacleMemo> interior_memos_;
};

}  // namespace tetrapage
