#pragma once
/// @file PlacedObject.h
/// The flying object at one pose, as every study method sees it: its bounding box BB(F) from
/// the transformed vertices of its convex hull (the study updates the box from the hull), and
/// its triangles in world coordinates, transformed only when a method asks for them (phase II).
/// Every coordinate is computed by apply_pose, the one canonical way, so BB(F) holds every
/// transformed vertex exactly and all methods see the same numbers.

#include <span>
#include <vector>

#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/runtime/geometry/Box.h"

namespace tetrapage::study {

class PlacedObject {
 public:
  /// Keeps the object's triangles and the vertices of its convex hull (CGAL).
  /// @throw InputError for an object without triangles or with non-finite coordinates.
  explicit PlacedObject(const TriangleSoup& object);

  /// Moves the object to `pose`: computes BB(F); the world triangles are made on demand.
  void place(const Pose& pose);

  const geometry::Box& box() const { return box_; }
  /// The world triangles at the current pose (computed on the first call after place()).
  std::span<const geometry::Triangle> triangles() const;
  /// Their boxes, in the same order.
  std::span<const geometry::Box> triangle_boxes() const;

  std::size_t triangle_count() const { return local_.size(); }
  std::size_t hull_vertex_count() const { return hull_.size(); }

 private:
  void transform() const;

  std::vector<geometry::Triangle> local_;
  std::vector<Vec3> hull_;
  std::array<double, 9> rotation_{};
  Vec3 translation_{};
  geometry::Box box_;
  mutable bool transformed_ = false;
  mutable std::vector<geometry::Triangle> world_;
  mutable std::vector<geometry::Box> world_boxes_;
};

}  // namespace tetrapage::study
