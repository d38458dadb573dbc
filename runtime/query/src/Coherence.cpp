#include "Coherence.h"

#include <algorithm>

namespace tetrapage {

Coherence::NewFreeBox Coherence::look_for_free_box(const geometry::Box& box, SearchedRegion& region,
                                                   const CollisionIndex& index,
                                                   const DynamicObstacles* overlay,
                                                   StepCounters& counters) {
  NewFreeBox result;
  if (free_box_wait_ > 0) {
    --free_box_wait_;
    return result;
  }
  const auto start = Clock::now();
  const geometry::Box last = free_box_;
  const bool had_free_box = free_box_valid_;
  result.found = find_free_box(box, region, index, overlay);
  result.at = Clock::now();
  counters.free_box_seconds = std::chrono::duration<double>(result.at - start).count();
  if (!result.found) {
    // Near an obstacle the next steps fail too: try again after 1, 2, 4, then 8 steps.
    free_box_backoff_ =
        std::min<std::uint32_t>(std::max<std::uint32_t>(2 * free_box_backoff_, 1), 8);
    free_box_wait_ = free_box_backoff_;
    return result;
  }
  free_box_backoff_ = 0;
  counters.found_free_box = true;
  // No triangle's box meets the step's box: no candidates, no contact. The containment vertex
  // is on the last free box's side of every closed part when the two boxes' insides overlap
  // (their union is connected and holds no triangle); else the walk decides.
  result.connected = had_free_box && last.lo[0] < free_box_.hi[0] && free_box_.lo[0] < last.hi[0] &&
                     last.lo[1] < free_box_.hi[1] && free_box_.lo[1] < last.hi[1] &&
                     last.lo[2] < free_box_.hi[2] && free_box_.lo[2] < last.hi[2];
  return result;
}

bool Coherence::find_free_box(const geometry::Box& box, SearchedRegion& region,
                              const CollisionIndex& index, const DynamicObstacles* overlay) {
  // The box grown a little on every side (for rotations) and a few steps' motion ahead, within
  // the searched region: its tets' shards hold every triangle that meets it.
  // (0.0625 to 0.25 of the extent, 4 to 16 steps, and regions grown by 0.5 to 1 gave the same
  // rates within 3 % on the 1M demo's flights.)
  constexpr double kSlack = 0.125;
  constexpr double kStepsAhead = 8;
  const double slack = kSlack * geometry::extent(box);
  // How fast each side of the box moves outwards (the motion, and the rotation's growth).
  std::array<double, 6> speed{};
  if (previous_valid_)
    for (int a = 0; a < 3; ++a) {
      speed[2 * a] = std::max(0.0, previous_box_.lo[a] - current_box_.lo[a]);
      speed[2 * a + 1] = std::max(0.0, current_box_.hi[a] - previous_box_.hi[a]);
    }
  geometry::Box grown;
  // Within the mesh's box too: a step whose box lies inside the free box is inside the model.
  for (int a = 0; a < 3; ++a) {
    grown.lo[a] = std::max({region.box().lo[a], index.mesh_bounds().lo[a],
                            box.lo[a] - slack - kStepsAhead * speed[2 * a]});
    grown.hi[a] = std::min({region.box().hi[a], index.mesh_bounds().hi[a],
                            box.hi[a] + slack + kStepsAhead * speed[2 * a + 1]});
  }
  // Cut away each triangle box (or unread shard's reach) that meets the grown box, on a side
  // where it is apart from the step's box: the side the box takes longest to reach.
  const double slowest = 0.01 * geometry::extent(box);
  auto cut = [&](const geometry::Box& obstacle) {
    if (!geometry::boxes_overlap(grown, obstacle)) return true;
    int best_side = -1;
    double best_steps = -1;
    for (int a = 0; a < 3; ++a) {
      if (obstacle.hi[a] < box.lo[a]) {
        const double steps = (box.lo[a] - obstacle.hi[a]) / std::max(speed[2 * a], slowest);
        if (steps > best_steps) best_steps = steps, best_side = 2 * a;
      }
      if (obstacle.lo[a] > box.hi[a]) {
        const double steps = (obstacle.lo[a] - box.hi[a]) / std::max(speed[2 * a + 1], slowest);
        if (steps > best_steps) best_steps = steps, best_side = 2 * a + 1;
      }
    }
    if (best_side < 0) return false;  // it overlaps the step's box itself
    const int a = best_side / 2;
    if (best_side % 2 == 1)
      grown.hi[a] = std::min(grown.hi[a], obstacle.lo[a]);
    else
      grown.lo[a] = std::max(grown.lo[a], obstacle.hi[a]);
    return true;
  };
  bool found = true;
  for (std::size_t k = 0; k < region.size() && found; ++k) {
    if (!geometry::boxes_overlap(grown, region.reach(k)) ||
        !index.tet_filter().planes_may_meet(region.tet(k), grown))
      continue;
    const Shard* shard = region.resident(k);
    if (shard == nullptr) {
      // Not resident: its triangles within the grown box lie in its reach, or in another tet
      // of the region whose shard holds them too. Cut the reach rather than page it in.
      found = cut(region.reach(k));
      continue;
    }
    // A leaf or cell apart from the step's box is cut whole (its box holds its triangles'
    // points that the query reaches): a few tests instead of one per triangle.
    shard->for_each_box_candidate(
        grown,
        [&](const geometry::Box& leaf, std::uint32_t) {
          if (!found || geometry::boxes_overlap(leaf, box)) return found;
          found = cut(leaf);
          return false;
        },
        [&](std::uint32_t, const geometry::Triangle& triangle) {
          if (found) found = cut(geometry::box_of(triangle));
        });
  }
  // The dynamic obstacles' boxes are cut like triangle boxes (their version is checked by
  // every step: a change drops the free box). They may stand outside the mesh's box, where
  // the step's box may reach beyond `grown`: one meeting the step's box fails the search.
  if (found && overlay != nullptr) {
    geometry::Box reach = grown;
    reach.extend(box);
    overlay->for_each_in_box(reach, [&](const DynamicObstacles::Part& part) {
      found = !geometry::boxes_overlap(part.world_box, box) && cut(part.world_box);
      return found;
    });
  }
  // A failed search keeps the last free box: it still holds no triangle.
  if (found) free_box_ = grown, free_box_valid_ = true;
  return found;
}

}  // namespace tetrapage
