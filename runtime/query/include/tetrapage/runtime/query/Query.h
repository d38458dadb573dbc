#pragma once
/// @file Query.h
/// What the queries of a flying object ask and answer (FlyingObject.h): the collision step's
/// options, its contacts, counters and result; a distance query's (FlyingObject::distance: the
/// minimum distance between the placed object and the environment, its two closest points and
/// the triangles they lie on, certified by bounds on the double computation); and a time of
/// impact's (FlyingObject::time_of_impact: the earliest time in [0, 1] at which the object,
/// moving from one pose to another (translation linear, rotation by slerp), touches the
/// environment, certified by a bracket).

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "tetrapage/runtime/geometry/Accuracy.h"
#include "tetrapage/runtime/geometry/Box.h"
#include "tetrapage/runtime/geometry/Shapes.h"

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

/// Where an answer touches, named the same way by every query (a step's contacts, a distance's
/// closest pair, a time of impact's first contact): an environment triangle (its part,
/// connected component and model-wide id) and an object triangle, with one "none" per field,
/// which a default site holds. The object triangle is kNoObjectTriangle also when the object
/// was checked as a solid (hull, box, or swept). A site on a dynamic obstacle
/// (DynamicObstacles.h) has dynamic_part set to the obstacle's id, environment_triangle the
/// triangle's index in that obstacle's mesh, environment_part kDynamicPart and
/// environment_component 0; a site on the index has dynamic_part 0. A distance or a time of
/// impact names no component (kNoComponent).
struct ContactSite {
  static constexpr std::uint64_t kNoTriangle = std::numeric_limits<std::uint64_t>::max();
  static constexpr std::uint32_t kNoObjectTriangle = 0xffffffffu;
  static constexpr std::uint32_t kNoComponent = 0xffffffffu;
  /// environment_part of a site on a dynamic obstacle (no part of the index).
  static constexpr std::uint32_t kDynamicPart = 0xfffffffeu;
  std::uint32_t environment_part = 0;
  std::uint64_t environment_triangle = kNoTriangle;
  std::uint32_t object_triangle = kNoObjectTriangle;
  std::uint32_t environment_component = kNoComponent;
  std::uint32_t dynamic_part = 0;  ///< the dynamic obstacle's id, or 0 (kNoDynamicPart)
  /// Whether the site names an environment triangle (a containment, or a distance farther than
  /// its limit, names none).
  bool has_triangle() const { return environment_triangle != kNoTriangle; }
  bool operator==(const ContactSite&) const = default;
};

/// One contact of a step: a site with both triangles.
using Contact = ContactSite;

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

struct DistanceOptions {
  /// Distances beyond this are not measured: the answer is then only "farther", which is
  /// cheap when the object lies in free space (the usual case for planners). Must be >= 0;
  /// infinity measures any distance.
  double max_distance = std::numeric_limits<double>::infinity();
};

enum class Separation : std::uint8_t {
  /// The object touches the environment, or one body holds the other (decided exactly, as the
  /// collision query decides it): the distance is 0.
  touching,
  /// Apart, by `distance`, within max_distance.
  apart,
  /// Farther than max_distance (certified: no pair is within max_distance; lower_bound is at
  /// least max_distance), or an empty environment; the closest points are not measured.
  farther,
};

/// "touching", "apart", "farther": the words of answer files and bindings.
constexpr const char* to_string(Separation separation) {
  constexpr const char* kNames[] = {"touching", "apart", "farther"};
  return kNames[static_cast<int>(separation)];
}

struct DistanceResult {
  Separation separation = Separation::farther;
  /// The computed distance |on_environment - on_object|; 0 when touching; when farther, the
  /// certified lower bound.
  double distance = 0;
  /// The true distance (between the stored environment and the object as apply_pose places
  /// it) lies in [lower_bound, upper_bound]. Their gap is the error bound of the double
  /// computation: about 150 u M, with u = 2^-53 and M the coordinates' magnitude near the
  /// closest pair (TriangleDistance.h). Both are 0 when touching; upper_bound is infinite
  /// when farther.
  double lower_bound = 0;
  double upper_bound = std::numeric_limits<double>::infinity();
  /// The closest points, in world coordinates (when touching: a point both surfaces share,
  /// or nothing measured for a containment).
  geometry::Point on_environment{};
  geometry::Point on_object{};
  /// The closest pair's triangles (none when farther, or for a containment; no component).
  ContactSite closest;
  /// Touching without contact: which body holds the other (its part in containing_part).
  Containment containment{};
  std::uint32_t containing_part = 0;
  std::uint32_t containing_dynamic_part = 0;  ///< as QueryResult's
  /// Environment triangles measured against the object, and triangle pairs measured.
  std::uint64_t candidates = 0;
  std::uint64_t pair_tests = 0;
  /// The step started from the last step's closest pair (coherence), or found a free box far
  /// enough to answer "farther" without measuring.
  bool from_last_pair = false;
  bool from_free_box = false;
};

struct ImpactOptions {
  /// The bracket's width at most (in the motion's time, [0, 1]).
  double tolerance = 1e-4;
  /// Conservative advancement steps at most; an object grazing the environment at a
  /// distance far below the tolerance's reach can need many.
  std::uint32_t max_iterations = 10000;
};

enum class Impact : std::uint8_t {
  none,        ///< certified: the object touches nothing during the whole motion
  hit,         ///< it touches, first at a time in (free_until, contact_at]
  unresolved,  ///< max_iterations ran out: no contact up to free_until, nothing known after
};

/// "none", "hit", "unresolved": the words of answer files and bindings.
constexpr const char* to_string(Impact impact) {
  constexpr const char* kNames[] = {"none", "hit", "unresolved"};
  return kNames[static_cast<int>(impact)];
}

struct ImpactResult {
  Impact impact = Impact::none;
  /// No contact at any time in [0, free_until) (certified by distance bounds over the
  /// motion's speed bound); 1 when impact is none.
  double free_until = 1;
  /// The pose at this time collides (decided exactly); contact_at - free_until <= tolerance.
  double contact_at = 1;
  /// The first contact found at contact_at (the collision query's first hit; none for a
  /// containment or without a hit; no component).
  ContactSite contact;
  /// A hit with no contact: which body holds the other at contact_at, and its environment
  /// part (Contact::kDynamicPart with containing_dynamic_part for a dynamic obstacle).
  Containment containment{};
  std::uint32_t containing_part = 0;
  std::uint32_t containing_dynamic_part = 0;
  std::uint32_t iterations = 0;  ///< distance queries run
};

inline bool has_closest_points(const DistanceResult& result) {
  return result.separation == Separation::apart ||
         (result.separation == Separation::touching && result.closest.has_triangle() &&
          result.closest.object_triangle != ContactSite::kNoObjectTriangle);
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

}  // namespace tetrapage
