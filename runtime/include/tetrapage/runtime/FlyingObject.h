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
/// query() runs these steps over its parts, each private to runtime/src (PlacedObject: 1;
/// SearchedRegion: 2 to 4; Coherence: the free box and the previous pose; PruningShapes and
/// PhaseTwo: 5, with ObjectSolid; ContainmentCheck: one body inside the other).

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "tetrapage/formats/Pose.h"
#include "tetrapage/formats/TriangleSoup.h"
#include "tetrapage/runtime/BoxSearch.h"
#include "tetrapage/runtime/CollisionIndex.h"
#include "tetrapage/runtime/DistanceQuery.h"
#include "tetrapage/runtime/DynamicObstacles.h"
#include "tetrapage/runtime/ImpactQuery.h"
#include "tetrapage/runtime/ObjectModel.h"
#include "tetrapage/runtime/ObstacleInterior.h"
#include "tetrapage/runtime/TriangleIdSet.h"
#include "tetrapage/runtime/geometry/Accuracy.h"
#include "tetrapage/runtime/geometry/ObjectBVH.h"
#include "tetrapage/runtime/geometry/TriangleContact.h"

namespace tetrapage {

enum class QueryMode : std::uint8_t { first_hit, all_contacts };

/// How finely phase II represents the object (DESIGN.md: "the object is represented only as
/// finely as the chosen accuracy needs"). Coarser shapes are supersets of the object, so under
/// the exact accuracy they never miss a contact of the mesh (mesh => hull => box), and answer
/// yes more often: in the hull's concavities, in the box's corners.
enum class ObjectShape : std::uint8_t {
  /// Its triangles, and for a closed object its inside: the question ReferenceCollider answers.
  mesh,
  /// The convex hull of its placed vertices, as a solid: an environment triangle collides when
  /// it meets the hull's surface or lies inside it. A few hundred faces stand for the object's
  /// triangles, and no containment test is needed.
  hull,
  /// Its world axis-aligned box (world_box), as a solid: one exact triangle/box test per
  /// candidate, the cheapest and coarsest question.
  box,
};

/// Whether a step checks the pose alone or the motion that led to it.
enum class Motion : std::uint8_t {
  /// The pose alone: a fast object can jump through a thin obstacle between two steps.
  discrete,
  /// The convex hull of the object's placed vertices at the previous and the current pose, as a
  /// solid (the study's section 5, item 1): it holds the object at both poses and, for a
  /// translation between them, every pose in between. There is no exact swept mesh: with
  /// shape mesh or hull, swept checks this swept hull; with shape box, the box of both world
  /// boxes. The first query of a FlyingObject has no previous pose and is discrete.
  swept,
};

/// The most contacts one all_contacts step collects by default (about 32 MB of them).
inline constexpr std::size_t kDefaultMaxContacts = 1'000'000;

struct QueryOptions {
  geometry::Accuracy accuracy = geometry::Accuracy::exact();
  QueryMode mode = QueryMode::first_hit;
  ObjectShape shape = ObjectShape::mesh;
  Motion motion = Motion::discrete;
  /// all_contacts: a step that finds more contacts than this throws InputError naming the
  /// limit (a wide clearance over a dense model can find billions), instead of growing without
  /// bound.
  std::size_t max_contacts = kDefaultMaxContacts;
};

/// One contact: an environment triangle (its part, connected component and model-wide id) and
/// an object triangle (kNoObjectTriangle when the object was checked as a solid: hull, box, or
/// swept). A contact with a dynamic obstacle (DynamicObstacles.h) has dynamic_part set to the
/// part's id, environment_triangle the triangle's index in that part's mesh, environment_part
/// kDynamicPart and environment_component 0; a contact with the index has dynamic_part 0.
struct Contact {
  static constexpr std::uint32_t kNoObjectTriangle = 0xffffffffu;
  /// environment_part of a contact with a dynamic obstacle (no part of the index).
  static constexpr std::uint32_t kDynamicPart = 0xfffffffeu;
  std::uint32_t environment_part = 0;
  std::uint64_t environment_triangle = 0;
  std::uint32_t object_triangle = 0;
  std::uint32_t environment_component = 0;
  std::uint32_t dynamic_part = 0;  ///< the dynamic obstacle's id, or 0 (kNoDynamicPart)
  bool operator==(const Contact&) const = default;
};

/// What one step did (the counters that explain its time).
struct StepCounters {
  bool searched = false;           ///< the box left the last searched region: walk + search ran
  std::uint32_t tets_crossed = 0;  ///< by the walk that located the box's centre
  std::uint32_t tets_visited = 0;  ///< by the box search
  std::uint32_t tets_overlapping = 0;
  std::uint32_t shards_touched = 0;  ///< shards whose bounds met the object's box
  std::uint32_t shard_misses = 0;    ///< shards paged in synchronously by this step
  /// phase I: shard triangles whose boxes meet the object's world box and, in the object's
  /// frame, its own box (a solid's: that meet the world box exactly; a triangle stored in
  /// several of the step's shards counts once in a double-precision index), except those of
  /// leaves_inside_object
  std::uint64_t candidates = 0;
  /// phase I: R-tree leaves whose box meets no triangle's box of the closed object and lies
  /// inside it (or where the object's interior grid cannot tell): their triangles can touch no
  /// object triangle and are only noted for containment, not counted as candidates (nor read,
  /// when no component of a part fits in the step's box)
  std::uint32_t leaves_inside_object = 0;
  /// phase I: shard triangles skipped because another of the step's shards held them already
  /// (a triangle crossing regions; double-precision indexes, whose copies are identical)
  std::uint64_t repeats = 0;
  std::uint64_t triangle_tests = 0;  ///< phase II: exact (or epsilon) triangle pair tests
  /// The object's box, and the walk when it searched. While the object holds a free box, the
  /// box is not timed: a step that ends inside the free box reads no clock at all.
  double locate_seconds = 0;
  double search_seconds = 0;
  double shard_seconds = 0;     ///< acquiring shards (page-ins included)
  double test_seconds = 0;      ///< phase I and II
  double interior_seconds = 0;  ///< the containment checks of a step without contact
  /// The box lay inside the free box of an earlier step (a box that holds no environment
  /// triangle): nothing else ran, and the step is free.
  bool in_free_box = false;
  /// A new free box was found around the step's box, so phase I did not run: the step is free,
  /// or the object inside an obstacle.
  bool found_free_box = false;
  double free_box_seconds = 0;  ///< looking for a new free box (found or not)
};

/// A collision without touching surfaces: one closed body holds the other.
enum class Containment : std::uint8_t {
  none,
  object_inside_obstacle,  ///< a component of the object lies inside a closed component of the
                           ///< environment (the index's interiors)
  obstacle_inside_object,  ///< a component of the environment lies inside a closed component of
                           ///< the object
};

/// "none", "object_inside_obstacle", "obstacle_inside_object".
constexpr const char* to_string(Containment containment) {
  constexpr const char* kNames[] = {"none", "object_inside_obstacle", "obstacle_inside_object"};
  return kNames[static_cast<int>(containment)];
}

/// Whether a distance answer holds closest points: apart, or touching through a contact (a
/// containment touches with nothing measured, and "farther" measures nothing; their points are
/// then meaningless zeros).
inline bool has_closest_points(const DistanceResult& result) {
  return result.separation == Separation::apart ||
         (result.separation == Separation::touching &&
          result.environment_triangle != DistanceResult::kNoTriangle &&
          result.object_triangle != Contact::kNoObjectTriangle);
}

struct QueryResult {
  /// Surfaces touch (contacts), or one body contains the other (containment).
  bool collides = false;
  Containment containment = Containment::none;
  std::uint32_t containing_part = 0;       ///< the environment part of a containment
  std::uint32_t containing_component = 0;  ///< the environment component of a containment
  /// A dynamic obstacle's id when it holds the object or the object holds it (then
  /// containing_part is Contact::kDynamicPart and containing_component 0); else 0.
  std::uint32_t containing_dynamic_part = 0;
  /// first_hit: the first contact found; all_contacts: every pair (unordered).
  std::vector<Contact> contacts;
  /// The object's box lies entirely outside the model's coarse mesh (nothing to touch).
  bool outside_model = false;
  geometry::Box world_box;
  StepCounters counters;
};

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
  /// triangles (DistanceQuery.h). Whether it touches is decided first, exactly, as query()
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
  /// and an exact collision query at the end of the bracket (ImpactQuery.h). Leaves the
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
  // The parts of the runtime step (runtime/src): the placed object, the searched region, the
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
  std::pair<geometry::Triangle, geometry::Triangle> dynamic_contact_triangles(const Contact& contact);
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
