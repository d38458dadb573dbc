#pragma once
/// @file PruningShapes.h (private)
/// The shapes phase I prunes with, placed for one step: the object's own box in its frame
/// (grown by the reach), its bounding ball and its hull's planes, in its frame and placed in
/// the world. Each test is conservative: it only prunes. The tests run per R-tree node and
/// per candidate, so they are inline here.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "PlacedObject.h"
#include "tetrapage/runtime/geometry/Box.h"
#include "tetrapage/runtime/query/ObjectModel.h"

namespace tetrapage {

class PruningShapes {
 public:
  using Plane = std::pair<Vec3, double>;  // n.x <= offset holds the object

  /// The shapes for a step whose phase I box is `box` (the world box grown by `reach`, the
  /// accuracy's reach). `own_frame`: the question is about the current pose's object or its
  /// hull (both inside its own box), not its world box or a swept solid; `solid_query`: the
  /// object is asked as a solid. `model_box`: the coarse mesh's box.
  void prepare(const ObjectModel& model, const PlacedObject& object, const geometry::Box& box,
               double reach, bool own_frame, bool solid_query, const geometry::Box& model_box);

  double reach() const { return reach_; }
  bool own_frame() const { return own_frame_; }
  bool ball_prunes() const { return ball_prunes_; }
  /// Inner R-tree nodes are asked of the object's own box too (meets_own_box).
  bool prune_inner() const { return prune_inner_; }

  // A box in the object's frame wholly beyond one of the hull's planes misses the object and
  // its hull (the margin covers the planes' rounding, far beyond it).
  bool beyond_hull(const geometry::Box& b) const {
    return box_beyond_planes(model_->hull_planes, plane_margin_, b);
  }
  // For a round object, a box in its frame wholly outside the ball that holds it misses it
  // and its hull (the box is grown by the reach and margins already; the ball by far more
  // than the roundings of this test).
  bool outside_ball(const geometry::Box& b) const {
    return ball_prunes_ && box_outside_ball(b, model_->ball_centre, ball_reach_);
  }
  // Either shape placed in the world: a world box it rules out misses the object.
  bool world_shapes_miss(const geometry::Box& b) const {
    return (ball_prunes_ && box_outside_ball(b, world_ball_centre_, world_ball_reach_)) ||
           box_beyond_planes(world_planes_, 0.0, b);
  }
  // Does a world box (an R-tree node's or a shard's, holding `triangles`, 0 when unknown) meet
  // the object's own box?
  bool meets_own_box(const geometry::Box& b, std::uint32_t triangles) const {
    return reach_of(b, triangles) != NodeReach::apart;
  }
  /// What of the object a node's box can reach.
  enum class NodeReach : std::uint8_t {
    apart,    ///< nothing: the node's triangles miss the object
    surface,  ///< maybe the object's surface
    /// Only the object's inside: the box (grown by the reach) meets no object triangle's box,
    /// and lies in the closed object (or the object's interior grid cannot tell). Its triangles
    /// touch no object triangle; they matter only as part of an environment component that may lie
    /// wholly inside the object.
    inside,
  };
  NodeReach reach_of(const geometry::Box& b, std::uint32_t triangles) const;

 private:
  static bool box_beyond_planes(std::span<const Plane> planes, double margin,
                                const geometry::Box& b) {
    for (const auto& [n, offset] : planes) {
      double lowest = 0;
      for (int a = 0; a < 3; ++a) lowest += n[a] * (n[a] > 0 ? b.lo[a] : b.hi[a]);
      if (lowest > offset + margin) return true;
    }
    return false;
  }
  static bool box_outside_ball(const geometry::Box& b, const Vec3& centre, double radius) {
    double squared = 0;
    for (int a = 0; a < 3; ++a) {
      const double gap = std::max({b.lo[a] - centre[a], centre[a] - b.hi[a], 0.0});
      squared += gap * gap;
    }
    return squared > radius * radius;
  }

  // The surface test pays off on leaves and cells that hold a few triangles and are small
  // beside the object (measured on the 1M and 10M scenes with 500 to 15,000 triangles): a
  // larger box nearly always meets the surface anyway.
  static constexpr std::uint32_t kSurfaceTestTriangles = 4;

  const ObjectModel* model_ = nullptr;
  const PlacedObject* object_ = nullptr;
  double reach_ = 0;
  bool own_frame_ = false;
  bool near_surface_only_ = false;
  bool ball_prunes_ = false;
  bool prune_inner_ = false;
  // The object's own box (grown by the reach), to prune R-tree nodes and triangles in its
  // frame: for a rotated object it is much tighter than the world box.
  geometry::Point own_centre_{}, own_half_{};
  double translation_magnitude_ = 0;
  double surface_test_extent_ = 0;
  double plane_margin_ = 0;
  double ball_reach_ = 0;
  Vec3 world_ball_centre_{};
  double world_ball_reach_ = 0;
  /// The hull's pruning planes placed in the world (n.x <= offset holds the object).
  std::vector<Plane> world_planes_;
};

inline PruningShapes::NodeReach PruningShapes::reach_of(const geometry::Box& b,
                                                        std::uint32_t triangles) const {
  // Does a world box meet the object's own box? Its centre taken to the object's frame and
  // its half extents through |R| (separating axes of the object's frame); the roundings are
  // covered by a margin far beyond them. Conservative: it only prunes.
  if (!own_frame_) return NodeReach::surface;
  if (world_shapes_miss(b)) return NodeReach::apart;
  const std::array<double, 9>& rotation = object_->rotation();
  const Vec3& translation = object_->translation();
  Vec3 c, h;
  for (int a = 0; a < 3; ++a)
    c[a] = 0.5 * (b.lo[a] + b.hi[a]) - translation[a], h[a] = 0.5 * (b.hi[a] - b.lo[a]);
  const double margin = (std::max({std::fabs(b.lo[0]), std::fabs(b.lo[1]), std::fabs(b.lo[2]),
                                   std::fabs(b.hi[0]), std::fabs(b.hi[1]), std::fabs(b.hi[2])}) +
                         translation_magnitude_ + model_->radius) *
                        0x1p-40;
  geometry::Box in_frame;  // the node's box in the object's frame, grown by reach and margin
  for (int a = 0; a < 3; ++a) {
    const double x = rotation[a] * c[0] + rotation[3 + a] * c[1] + rotation[6 + a] * c[2];
    const double e = std::fabs(rotation[a]) * h[0] + std::fabs(rotation[3 + a]) * h[1] +
                     std::fabs(rotation[6 + a]) * h[2];
    if (std::fabs(x - own_centre_[a]) > e + own_half_[a] + margin) return NodeReach::apart;
    in_frame.lo[a] = x - e - reach_ - margin;
    in_frame.hi[a] = x + e + reach_ + margin;
  }
  if (beyond_hull(in_frame) || outside_ball(in_frame)) return NodeReach::apart;
  // For the mesh, a node must also come near the object's surface (its BVH) or lie inside it:
  // a node whose box meets no object triangle's box lies wholly inside or wholly outside the
  // object, and one point of it tells which.
  if (!near_surface_only_ || triangles < kSurfaceTestTriangles ||
      std::max({h[0], h[1], h[2]}) > surface_test_extent_)
    return NodeReach::surface;
  bool near_surface = false;
  model_->bvh.for_each_in_box(in_frame, [&](std::uint32_t) { return !(near_surface = true); });
  if (near_surface) return NodeReach::surface;
  if (!model_->closed || model_->interior_grid.classify(in_frame.center(), margin) ==
                             ObjectInteriorGrid::Side::outside)
    return NodeReach::apart;
  return NodeReach::inside;
}

}  // namespace tetrapage
