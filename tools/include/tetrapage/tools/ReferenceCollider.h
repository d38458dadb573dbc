#pragma once
/// @file ReferenceCollider.h
/// The in-core reference collision oracle: CGAL's AABB_tree with exact (filtered)
/// predicates. It shares no code with the runtime, so tests and benchmarks use it to check
/// the runtime's answers, and the flight generator uses it to bounce billiard paths.
///
/// Definition of "collides" (the one every tetrapage answer is checked against): the object's
/// vertices are placed in world space by apply_pose() (formats/Pose.h), in double; the pose
/// collides when some placed object triangle and some environment triangle intersect as
/// closed sets (touching counts), decided exactly on those doubles; or, when no surfaces
/// touch, when one body lies inside the other: the object's first vertex has odd crossing
/// parity with some closed part of the environment (a part whose every edge is used an even
/// number of times; open parts such as terrains have no inside), or a vertex of an
/// environment triangle has odd parity with the closed object. Each parity is the majority
/// of three rays in fixed generic directions.

#include <cstdint>
#include <memory>

#include "tetrapage/formats/Pose.h"
#include "tetrapage/formats/TriangleSoup.h"

namespace tetrapage {

class ReferenceCollider {
 public:
  struct Answer {
    bool collides = false;        ///< surfaces_touch || object_inside || obstacle_inside
    bool surfaces_touch = false;  ///< some triangle pair intersects
    bool object_inside = false;   ///< no touch, but the object is inside a closed part
    bool obstacle_inside = false; ///< no touch, but an environment triangle is inside the object
    std::uint64_t candidates = 0; ///< environment triangles meeting the object's box
  };

  /// Builds AABB trees over the environment and the object (object in its own frame).
  /// @throw InputError if either soup has no triangle.
  ReferenceCollider(const TriangleSoup& environment, const TriangleSoup& object);
  ~ReferenceCollider();
  ReferenceCollider(ReferenceCollider&&) noexcept;
  ReferenceCollider& operator=(ReferenceCollider&&) noexcept;

  /// Answers one pose. Thread-safe (const, no shared scratch).
  Answer query(const Pose& pose) const;

  /// Only the first half of the question: some placed object triangle and some environment
  /// triangle intersect (Answer::surfaces_touch, without the containment tests). What a
  /// mesh/mesh collider such as FCL answers, decided exactly. Thread-safe.
  bool surfaces_touch(const Pose& pose) const;

  /// Whether p is inside a closed part of the environment (crossing parity, see above).
  bool inside_environment(const Vec3& p) const;

  /// Bounding box of the object placed at `pose` (from all its placed vertices).
  BoundingBox object_bounds(const Pose& pose) const;
  const BoundingBox& environment_bounds() const;
  /// Radius of the object's bounding sphere around its own origin.
  double object_radius() const;

  class Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace tetrapage
