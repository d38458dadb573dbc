#pragma once
/// @file PlacedObject.h (private)
/// The object placed at a step's pose: its rotation and translation, its world vertices
/// (placed on demand, once per step), the frame change back into its own frame, and its world
/// box by hill-climbing on its convex hull (step 1 of the runtime step).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/runtime/geometry/Box.h"
#include "tetrapage/runtime/query/ObjectModel.h"

namespace tetrapage {

/// @throw InputError naming the axis, the value and the limit when a coordinate of
///        `translation` lies beyond kMaxCoordinateMagnitude in magnitude (NaN is not).
void check_translation_within_limit(const Vec3& translation);

class PlacedObject {
 public:
  explicit PlacedObject(const ObjectModel& model);
  /// Another model (a scratch placement reused for many, e.g. the dynamic obstacles a step
  /// meets: no allocation once the largest was seen). Call place() before anything else.
  void rebind(const ObjectModel& model);

  /// Takes `pose` as the current placement (a new step: earlier world vertices are stale).
  /// @throw InputError for a non-finite or non-unit pose, or a translation beyond
  ///        kMaxCoordinateMagnitude.
  void place(const Pose& pose);
  /// The world box at the current placement (hill-climbing on the hull), slightly enlarged to
  /// cover the rounding of the placement.
  geometry::Box world_box();

  const std::array<double, 9>& rotation() const { return rotation_; }
  const Vec3& translation() const { return translation_; }
  /// The largest coordinate of the translation in magnitude.
  double translation_magnitude() const {
    return std::max(
        {std::fabs(translation_[0]), std::fabs(translation_[1]), std::fabs(translation_[2])});
  }

  /// Vertex v placed by apply_pose (the canonical placement, the oracle's arithmetic).
  const Vec3& world_vertex(std::uint32_t v) {
    if (world_step_[v] != step_) {
      world_[v] = apply_pose(rotation_, translation_, model_->mesh.vertices[v]);
      world_step_[v] = step_;
    }
    return world_[v];
  }
  geometry::Triangle world_triangle(std::uint32_t t) {
    const auto& c = model_->mesh.triangles[t];
    return {world_vertex(c[0]), world_vertex(c[1]), world_vertex(c[2])};
  }

  // A world point taken back to the object's frame at the current pose (rounded: callers
  // only prune with it, with margins far beyond the rounding).
  Vec3 to_object_frame(const geometry::Point& p) const {
    const Vec3 e{p[0] - translation_[0], p[1] - translation_[1], p[2] - translation_[2]};
    return {rotation_[0] * e[0] + rotation_[3] * e[1] + rotation_[6] * e[2],
            rotation_[1] * e[0] + rotation_[4] * e[1] + rotation_[7] * e[2],
            rotation_[2] * e[0] + rotation_[5] * e[1] + rotation_[8] * e[2]};
  }

  // A world direction turned into the object's frame (rounded: for pruning with margins).
  Vec3 direction_to_object_frame(const Vec3& d) const {
    return {rotation_[0] * d[0] + rotation_[3] * d[1] + rotation_[6] * d[2],
            rotation_[1] * d[0] + rotation_[4] * d[1] + rotation_[7] * d[2],
            rotation_[2] * d[0] + rotation_[5] * d[1] + rotation_[8] * d[2]};
  }

  // How far from the object's box or surface a world point must be for the frame change's
  // rounding not to matter.
  double frame_margin(const geometry::Point& p) const {
    // Far beyond the rounding of to_object_frame and of the placement: a point this close to
    // the object's box or surface is left to the exact tests.
    return (model_->radius + std::max({std::fabs(p[0]), std::fabs(p[1]), std::fabs(p[2])}) +
            std::max({std::fabs(translation_[0]), std::fabs(translation_[1]),
                      std::fabs(translation_[2])})) *
           0x1p-40;
  }

  bool in_object_box(const geometry::Point& p) const {
    // p in the object's own frame (rounded back, so the box is grown far beyond the rounding):
    // outside that box means outside the object. The world box is looser for a rotated object.
    const Vec3 x = to_object_frame(p);
    const double margin = frame_margin(p);
    for (int a = 0; a < 3; ++a)
      if (x[a] < model_->box.lo[a] - margin || x[a] > model_->box.hi[a] + margin) return false;
    return true;
  }

 private:
  const ObjectModel* model_;
  std::array<double, 9> rotation_{};
  Vec3 translation_{};
  std::uint64_t step_ = 0;
  std::vector<Vec3> world_;  ///< placed vertices, valid where world_step_ is step_
  std::vector<std::uint64_t> world_step_;
  std::array<std::uint32_t, 6> extreme_{};  ///< hull positions of the last min/max per axis
};

}  // namespace tetrapage
