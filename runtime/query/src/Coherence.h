#pragma once
/// @file Coherence.h (private)
/// What a flying object keeps from its earlier steps, since poses are coherent: the previous
/// pose and world box (swept motion, the motion's direction), and the free box, a box that
/// meets no environment triangle, around the box of a free step.

#include <algorithm>
#include <array>
#include <cstdint>
#include <optional>

#include "PlacedObject.h"
#include "SearchedRegion.h"
#include "StepClock.h"
#include "tetrapage/runtime/geometry/Box.h"
#include "tetrapage/runtime/paging/CollisionIndex.h"
#include "tetrapage/runtime/query/DynamicObstacles.h"

namespace tetrapage {

class Coherence {
 public:
  /// This step's world box, before the accuracy's growth.
  void begin_step(const geometry::Box& world_box) { current_box_ = world_box; }
  /// This step's pose becomes the next one's previous pose.
  void remember(const PlacedObject& object) {
    previous_valid_ = true;
    previous_rotation_ = object.rotation();
    previous_translation_ = object.translation();
    previous_box_ = current_box_;
  }

  bool has_previous() const { return previous_valid_; }
  const std::array<double, 9>& previous_rotation() const { return previous_rotation_; }
  const Vec3& previous_translation() const { return previous_translation_; }
  const geometry::Box& previous_box() const { return previous_box_; }
  const geometry::Box& current_box() const { return current_box_; }
  /// How far the world box's centre moved since the previous step (none on a first step).
  std::optional<Vec3> motion() const {
    if (!previous_valid_) return std::nullopt;
    Vec3 d;
    for (int a = 0; a < 3; ++a) d[a] = current_box_.center()[a] - previous_box_.center()[a];
    return d;
  }

  bool has_free_box() const { return free_box_valid_; }
  /// Every point of `box` lies inside the free box: the step is free.
  bool in_free_box(const geometry::Box& box) const {
    return free_box_valid_ && box.lo[0] > free_box_.lo[0] && box.lo[1] > free_box_.lo[1] &&
           box.lo[2] > free_box_.lo[2] && box.hi[0] < free_box_.hi[0] &&
           box.hi[1] < free_box_.hi[1] && box.hi[2] < free_box_.hi[2];
  }
  /// How deep `box` lies inside the free box (its least distance to the free box's faces,
  /// rounded down): no environment triangle is nearer to any point of `box`. 0 outside it.
  double free_gap(const geometry::Box& box) const {
    if (!in_free_box(box)) return 0;
    double gap = box.lo[0] - free_box_.lo[0];
    for (int a = 0; a < 3; ++a)
      gap = std::min({gap, box.lo[a] - free_box_.lo[a], free_box_.hi[a] - box.hi[a]});
    return gap * (1 - 0x1p-50);
  }
  /// The object turned out inside an obstacle: the free box is not free space.
  void drop_free_box() { free_box_valid_ = false; }

  struct NewFreeBox {
    bool found = false;
    /// It overlaps the last free box: the containment vertex is on that box's side of every
    /// closed part.
    bool connected = false;
    Clock::time_point at;  ///< when the search ended
  };
  /// For a step whose box is outside the free box: a new free box around `box`, unless the
  /// last searches failed and it waits. It meets no dynamic obstacle of `overlay` either (the
  /// index's hidden parts still bound it: a smaller free box, never a wrong one).
  NewFreeBox look_for_free_box(const geometry::Box& box, SearchedRegion& region,
                               const CollisionIndex& index, const DynamicObstacles* overlay,
                               StepCounters& counters);
  /// The dynamic obstacles changed (their version): the free box is dropped when it may hold
  /// one now (a part's box meets it), or when `shown` (an index part shown again may hold the
  /// object, free while it was hidden). Removing or hiding only frees space; a part whose box
  /// misses the free box can neither touch nor hold an object inside it.
  void obstacles_changed(const DynamicObstacles* overlay, bool shown) {
    bool meets = shown || overlay == nullptr;
    if (free_box_valid_ && !meets && overlay != nullptr)
      overlay->for_each_in_box(free_box_, [&](const DynamicObstacles::Part&) {
        meets = true;
        return false;
      });
    if (meets) free_box_valid_ = false, free_box_wait_ = 0;
  }

 private:
  // After a free step whose box is `box`: a box around it holding no environment triangle
  // (free_box_), grown towards where the object heads; false when none was found.
  bool find_free_box(const geometry::Box& box, SearchedRegion& region, const CollisionIndex& index,
                     const DynamicObstacles* overlay);

  // The previous query's pose and world box (before the accuracy's growth), for swept motion.
  bool previous_valid_ = false;
  std::array<double, 9> previous_rotation_{};
  Vec3 previous_translation_{};
  geometry::Box previous_box_;
  geometry::Box current_box_;  ///< this query's world box, before the accuracy's growth
  // A box that meets no environment triangle, around the box of a step whose answer was free
  // (no contact, the object in no obstacle). Any later step whose box lies strictly inside it
  // is free too: it has no candidates, and the object's containment vertex lies in the same
  // connected, surface-free box, so on the same side of every closed part.
  geometry::Box free_box_;
  bool free_box_valid_ = false;
  std::uint32_t free_box_backoff_ =
      0;  ///< steps to wait after a failed search, doubled per failure
  std::uint32_t free_box_wait_ = 0;
};

}  // namespace tetrapage
