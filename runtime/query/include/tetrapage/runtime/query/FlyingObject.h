#pragma once
/// @file FlyingObject.h
/// A rigid object moving through an index, and the runtime step of DESIGN.md:
///  1. the pose; the world box of the object by hill-climbing on its convex hull;
///  2. the box's centre located by walking from the previous tet;
///  3. the tets overlapping the box, breadth first;
///  4. their shards pinned in the cache (a prefetch hint for where the motion heads);
///  5. phase I: shard triangles whose boxes meet the object's box; phase II: those against the
///     object's BVH, decided on the object's world coordinates (apply_pose, the canonical
///     placement), so that the exact mode answers exactly what an exact oracle answers.
/// One FlyingObject is used from one thread at a time; many may share a CollisionIndex.
/// query() runs these steps over its parts, each private to runtime/query/src (PlacedObject: 1;
/// SearchedRegion: 2 to 4; Coherence: the free box and the previous pose; PruningShapes and
/// PhaseTwo: 5, with ObjectSolid; ContainmentCheck: one body inside the other).

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/runtime/geometry/Accuracy.h"
#include "tetrapage/runtime/geometry/ObjectBVH.h"
#include "tetrapage/runtime/geometry/TriangleContact.h"
#include "tetrapage/runtime/paging/BoxSearch.h"
#include "tetrapage/runtime/paging/CollisionIndex.h"
#include "tetrapage/runtime/query/DynamicObstacles.h"
#include "tetrapage/runtime/query/ObjectModel.h"
#include "tetrapage/runtime/query/ObstacleInterior.h"
#include "tetrapage/runtime/query/Query.h"
#include "tetrapage/runtime/query/TriangleIdSet.h"

namespace tetrapage {

class FlyingObject {
 public:
  /// @throw InputError for an object ObjectModel rejects (empty, non-finite or too large
  ///        coordinates, every triangle of zero area).
  FlyingObject(std::shared_ptr<const CollisionIndex> index, TriangleSoup object);
  /// A flying instance of a shared model (built beforehand, e.g. while the index opened).
  /// @throw InputError for a null index or model.
  FlyingObject(std::shared_ptr<const CollisionIndex> index,
               std::shared_ptr<const ObjectModel> model);
  ~FlyingObject();
  FlyingObject(FlyingObject&&) noexcept;
  FlyingObject& operator=(FlyingObject&&) noexcept;

  /// One step at `pose`. Reuses `result`'s buffers. A quaternion within 1e-6 of unit squared
  /// norm stands for its rotation (rotation_matrix normalises it).
  /// @throw InputError for a non-finite or non-unit pose, or a translation beyond
  ///        kMaxCoordinateMagnitude (the placement would overflow); what the shard cache throws (a
  ///        budget smaller than one shard, I/O and checksum errors naming the index).
  void query(const Pose& pose, const QueryOptions& options, QueryResult& result);
  QueryResult query(const Pose& pose, const QueryOptions& options = {}) {
    QueryResult result;
    query(pose, options, result);
    return result;
  }

  /// The distance from the object at `pose` to the environment, with its closest points and
  /// triangles (Query.h). Whether it touches is decided first, exactly, as query()
  /// decides it with the default options (contacts, and containment with the index's
  /// interiors): then the distance is 0. Otherwise the search starts from the last step's
  /// closest pair, and a free box farther than max_distance answers "farther" at once.
  /// This is a step of the object like query(): it is the next step's previous pose.
  /// @throw InputError for a negative or NaN max_distance, and what query() throws.
  void distance(const Pose& pose, const DistanceOptions& options, DistanceResult& result);
  DistanceResult distance(const Pose& pose, const DistanceOptions& options = {}) {
    DistanceResult result;
    distance(pose, options, result);
    return result;
  }

  /// The geometry of a contact of the last query (or distance query that touched), at its
  /// pose: where the two triangles meet (a point, a segment, or a polygon when coplanar) and
  /// both normals (TriangleContact.h), the environment's "first". Pages in the triangle's
  /// shard if needed. A contact of a solid (no object triangle) has shape none.
  /// @throw InputError for an environment triangle the index does not hold.
  geometry::ContactGeometry contact_geometry(const Contact& contact);
  /// A contact's two triangles in world coordinates, the environment's first (the copy phase
  /// II tested), the object's at the last query's pose: for what contact_geometry does not
  /// say, such as whether a pair reported under a clearance accuracy meets
  /// (TriangleTriangle.h) or how far apart it lies (TriangleDistance.h).
  /// @throw InputError for a contact of a solid (no object triangle), and as contact_geometry.
  std::pair<geometry::Triangle, geometry::Triangle> contact_triangles(const Contact& contact);

  /// The first time in [0, 1] at which the object moving from `from` to `to` (PoseMotion.h)
  /// touches the environment, by conservative advancement: distance queries along the motion,
  /// each certifying the time the object needs to cover its lower bound at its speed bound,
  /// and an exact collision query at the end of the bracket (Query.h). Leaves the
  /// object at the last pose it examined.
  /// @throw InputError for a tolerance not in (0, 1], and what query() throws.
  ImpactResult time_of_impact(const Pose& from, const Pose& to, const ImpactOptions& options = {});

  /// Dynamic obstacles merged into every later query (and the index's parts they hide masked
  /// from it), or none (null). The overlay must be on this object's index; it may change
  /// between steps (DynamicObstacles.h: its threading rule), never during one. The distance
  /// query decides touching with them, but measures distance to the index's parts only.
  /// @throw InputError for an overlay on another index.
  void set_obstacles(std::shared_ptr<const DynamicObstacles> obstacles);
  const std::shared_ptr<const DynamicObstacles>& obstacles() const;

  /// The world box of the object at `pose` (hill-climbing on the hull), slightly enlarged to
  /// cover the rounding of the placement.
  geometry::Box world_box(const Pose& pose);

  const TriangleSoup& object() const { return model_->mesh; }
  const std::shared_ptr<const ObjectModel>& model() const { return model_; }
  std::size_t hull_vertex_count() const { return model_->hull_vertices.size(); }
  /// Some connected component of the object is closed: only then can an obstacle lie inside it.
  bool closed() const { return model_->closed; }

 private:
  // The parts of the runtime step (runtime/query/src): the placed object, the searched region, the
  // pruning shapes, the solid, the containment check and what the steps keep (coherence).
  struct Parts;
  // The step's box lies outside the model: nothing to touch.
  void outside_model(QueryResult& result);
  // A step whose box is outside the free box: its answer when a new free box around it was
  // found (free, or inside an obstacle), else false and the step goes on to phase I.
  bool step_in_new_free_box(const geometry::Box& box, QueryResult& result);
  // Phases I and II over the region's shards that the step needs, then containment.
  void test_region(const geometry::Box& box, const QueryOptions& options, bool solid_query,
                   std::chrono::steady_clock::time_point loop_start, QueryResult& result);
  // contact_triangles of a contact with a dynamic obstacle (at the overlay's current pose).
  std::pair<geometry::Triangle, geometry::Triangle> dynamic_contact_triangles(
      const Contact& contact);
  // A step whose box met no tet of the mesh: the dynamic obstacles alone.
  void test_obstacles_alone(const geometry::Box& box, const QueryOptions& options, bool own_frame,
                            bool solid_query, double reach, QueryResult& result);
  // The box whose coordinates bound what the pruning shapes meet (their margins).
  geometry::Box shapes_box(const geometry::Box& box) const;

  std::shared_ptr<const CollisionIndex> index_;
  std::shared_ptr<const ObjectModel> model_;
  std::unique_ptr<Parts> parts_;
};

}  // namespace tetrapage
