#pragma once
/// @file FlyingObjectParts.h (private)
/// The parts of a FlyingObject's runtime step, shared by its queries (collision, distance,
/// time of impact).

#include "Coherence.h"
#include "ContainmentCheck.h"
#include "DistanceSearch.h"
#include "ObjectSolid.h"
#include "PhaseTwo.h"
#include "PlacedObject.h"
#include "PruningShapes.h"
#include "SearchedRegion.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/runtime/query/TriangleIdSet.h"

namespace tetrapage {

struct FlyingObject::Parts {
  Parts(const CollisionIndex& index, const ObjectModel& model)
      : object(model), region(index), containment(index, model), distance(index), obstacle(model) {}
  PlacedObject object;           ///< step 1: the pose, the placed vertices, the world box
  SearchedRegion region;         ///< steps 2 to 4: the walk, the box search, the shards' pins
  Coherence coherence;           ///< the previous pose and box, and the free box
  PruningShapes shapes;          ///< phase I's shapes, placed per step
  ObjectSolid solid;             ///< per-step scratch: the object as a solid
  ContainmentCheck containment;  ///< one body inside the other, for a step without contact
  TriangleIdSet met_triangles;   ///< the triangles phase I has met this step
  ContactTriangles contact_triangles;  ///< the step's contacts' index triangles, as tested
  std::size_t contact_cursor = 0;      ///< where contact_geometry found the last one
  DistanceSearch distance;       ///< the closest pair, and the last one (coherence)
  QueryResult touch;             ///< scratch: the collision step of a distance query
  std::shared_ptr<const DynamicObstacles> obstacles;  ///< merged into every query, or null
  std::uint64_t obstacles_version = 0;  ///< the overlay's version the free box was found with
  std::uint64_t obstacles_shows = 0;    ///< the overlay's shows() then
  PlacedObject obstacle;  ///< scratch: a dynamic obstacle placed (rebound to each in turn)

  /// The parts a step's test of its candidates uses, answering into `result`.
  StepContext step_context(const CollisionIndex& index, const ObjectModel& model,
                           QueryResult& result) {
    return {index,       model,         object,
            shapes,      solid,         coherence,
            containment, met_triangles, contact_triangles,
            result};
  }
};

}  // namespace tetrapage
