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
/// touch, when one body lies inside the other, component by component:
///  - a component is a maximal set of triangles of one part (TriangleSoup::part_of; an empty
///    part_of is one part) connected through shared vertices, where vertices at identical
///    coordinates are shared whatever their indices (-0.0 equals 0.0);
///  - a component is closed when its triangles form a closed surface (in the runtime's words,
///    every edge is used an even number of times); open components (terrains, sheets) have no
///    inside. A point is inside the environment when it is strictly inside ANY closed
///    component, each judged by its own ray parity: nested solids work (inside the inner one
///    is inside both), and a self-intersecting closed component holds the points of odd
///    parity (where two of its lobes overlap is outside it);
///  - (a) object inside: some object component has a placed vertex inside a closed
///    environment component; (b) obstacle inside: some environment component, closed or
///    open, has a vertex inside a closed component of the placed object. With no surface
///    contact one vertex decides for its whole (connected) component.
///
/// Independence from the runtime (which hashes vertex positions and calls a component closed
/// when every edge is used an even number of times): components come from CGAL's exact
/// merge_duplicate_points_in_polygon_soup and a union-find over the merged points;
/// closedness from orient_polygon_soup, polygon_soup_to_polygon_mesh and CGAL::is_closed on
/// a Surface_mesh that must be a triangle mesh; insideness from Side_of_triangle_mesh.
/// Where the two definitions may differ, the tests avoid the input: an edge shared by four or
/// more triangles (orient_polygon_soup cuts the soup there, so CGAL may read it open or as
/// several sheets where parity reads it closed), and a triangle with two corners at one
/// position (read here as open). A vertex shared by several cones of triangles (two solids
/// touching at a corner) is fine: CGAL duplicates it and each piece stays closed.

#include <cstddef>
#include <cstdint>
#include <memory>

#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/formats/mesh/Pose.h"

namespace tetrapage {

class ReferenceCollider {
 public:
  struct Answer {
    bool collides = false;         ///< surfaces_touch || object_inside || obstacle_inside
    bool surfaces_touch = false;   ///< some triangle pair intersects
    bool object_inside = false;    ///< no touch, but an object component is inside a closed one
    bool obstacle_inside = false;  ///< no touch, not object_inside, but an environment component
                                   ///< is inside a closed object component
    std::uint64_t candidates = 0;  ///< environment triangles meeting the object's box
  };

  /// Builds AABB trees over the environment and the object (object in its own frame), both
  /// soups' components, and a Side_of_triangle_mesh (with its tree) per closed environment
  /// component, all eagerly: queries mutate nothing.
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

  /// Whether p is strictly inside some closed component of the environment (see above; a
  /// point on a component's surface is not inside that component). Thread-safe.
  bool inside_environment(const Vec3& p) const;

  /// Bounding box of the object placed at `pose` (from all its placed vertices).
  BoundingBox object_bounds(const Pose& pose) const;
  const BoundingBox& environment_bounds() const;
  /// Radius of the object's bounding sphere around its own origin.
  double object_radius() const;

  /// Component counts (see the definition above), for tests and logs.
  std::size_t environment_components() const;
  std::size_t environment_closed_components() const;
  std::size_t object_components() const;
  std::size_t object_closed_components() const;

  class Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace tetrapage
