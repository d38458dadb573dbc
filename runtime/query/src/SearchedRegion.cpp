#include "SearchedRegion.h"

#include <algorithm>

#include "StepClock.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/runtime/query/MeshWalk.h"

namespace tetrapage {
namespace {

// The box's centre, clamped into the coarse mesh's box: where a walk for the box aims.
Vec3 centre_in_mesh_box(const geometry::Box& box, const CollisionIndex& index) {
  Vec3 centre = box.center();
  for (int a = 0; a < 3; ++a)
    centre[a] = std::clamp(centre[a], index.mesh_bounds().lo[a], index.mesh_bounds().hi[a]);
  return centre;
}

}  // namespace

bool SearchedRegion::search(const geometry::Box& box, const std::optional<Vec3>& motion,
                            StepCounters& counters) {
  const CollisionIndex& index = *index_;
  const TetMesh& mesh = index.mesh();
  counters.searched = true;
  auto start = Clock::now();
  // Grow by half the box's extent each side: a billiard object then crosses the margin in
  // about ten steps of 0.005 for a 0.05 object, and re-searches that often.
  const double grow = 0.5 * geometry::extent(box);
  geometry::Box region = box;
  for (int a = 0; a < 3; ++a) region.lo[a] -= grow, region.hi[a] += grow;
  const WalkResult located = locate_point(mesh, last_tet_, centre_in_mesh_box(box, index));
  counters.tets_crossed = located.tets_crossed;
  counters.locate_seconds += seconds_since(start);  // after the box time of query()
  if (located.tet == TetMesh::no_neighbour) return false;
  last_tet_ = located.tet;

  start = Clock::now();
  // Bounding boxes are enough here: the region only has to cover the steps' boxes, and each
  // step skips the shards whose stored bounds miss its box.
  const BoxSearchResult found =
      tets_near_box(mesh, index.tet_filter(), located.tet, region, search_);
  counters.tets_visited = found.tets_visited;
  counters.tets_overlapping = std::uint32_t(found.tets.size());
  // The last region's pins, for the shards the new region keeps: releasing them and acquiring
  // them again took the cache's lock twice each.
  previous_shards_.swap(shards_);
  previous_pins_.swap(pins_);
  shards_.clear();
  shard_reach_.clear();
  shard_tet_.clear();
  for (const std::uint32_t tet : found.tets) {
    const std::uint32_t shard = index.shard_of_tet(tet);
    if (shard == TetMesh::no_neighbour) continue;
    // A shard's triangles that meet a step's box there meet it inside the shard's tet, or
    // inside another tet of the region (whose shard holds them too): a step needs the shard
    // only when its box meets both the tet's box and the stored bounds.
    const geometry::Box tet_box = index.tet_filter().bounds(tet);
    const geometry::Box& stored = index.shard_bounds(shard);
    geometry::Box reach;
    for (int a = 0; a < 3; ++a) {
      reach.lo[a] = std::max(tet_box.lo[a], stored.lo[a]);
      reach.hi[a] = std::min(tet_box.hi[a], stored.hi[a]);
    }
    if (!geometry::boxes_overlap(region, reach)) continue;
    shards_.push_back(shard);
    shard_reach_.push_back(reach);
    shard_tet_.push_back(tet);
  }
  counters.search_seconds = seconds_since(start);

  move_kept_pins();

  if (index.options().prefetch) hint_ahead(box, region, motion);
  if (index.options().prefetch && index.options().prefetch_ahead && valid_) {
    // The next region, if the motion since the last search goes on.
    geometry::Box next = region;
    const Vec3 now = box.center();
    for (int a = 0; a < 3; ++a) {
      const double d = now[a] - centre_[a];
      next.lo[a] += d, next.hi[a] += d;
    }
    prefetch_ahead(next, located.tet);
  }
  box_ = region;
  centre_ = box.center();
  valid_ = true;
  return true;
}

void SearchedRegion::move_kept_pins() {
  const CollisionIndex& index = *index_;
  // Pins of the region's shards are taken when a step first needs them, and kept while the
  // object stays in the region (unless the region outweighs an eighth of the budget, which
  // other objects share: then each step pins one shard at a time).
  pins_.clear();
  std::uint64_t region_bytes = 0;
  for (const std::uint32_t shard : shards_) region_bytes += index.shard_bytes(shard);
  keep_pins_ = region_bytes <= index.options().memory_budget_bytes / 8;
  if (keep_pins_) {
    pins_.resize(shards_.size());
    for (std::size_t k = 0; k < previous_pins_.size(); ++k) {
      if (!previous_pins_[k]) continue;
      const auto kept = std::find(shards_.begin(), shards_.end(), previous_shards_[k]);
      if (kept != shards_.end())
        pins_[std::size_t(kept - shards_.begin())] = std::move(previous_pins_[k]);
    }
  }
  previous_pins_.clear();  // the rest are released
}

void SearchedRegion::hint_ahead(const geometry::Box& box, const geometry::Box& region,
                                const std::optional<Vec3>& motion) {
  const CollisionIndex& index = *index_;
  // The region's shards that the box does not meet yet but would within four more steps of
  // its last motion: load them in the background now rather than synchronously then. (All
  // the region's shards were loaded two to three times over for those the flights then
  // used, and the useless loads evicted useful ones: docs/history/benchmarks-to-2026-11-26.md.)
  constexpr double kHintSteps = 4;
  geometry::Box ahead = region;
  if (motion) {
    ahead = box;
    for (int a = 0; a < 3; ++a) {
      const double d = kHintSteps * (*motion)[a];
      (d < 0 ? ahead.lo[a] : ahead.hi[a]) += d;
    }
  }
  hints_.clear();
  for (std::size_t k = 0; k < shards_.size(); ++k)
    if (!geometry::boxes_overlap(box, shard_reach_[k]) &&
        geometry::boxes_overlap(ahead, shard_reach_[k]) &&
        index.tet_filter().planes_may_meet(shard_tet_[k], ahead) &&
        !index.cache().contains(shards_[k]))
      hints_.push_back(shards_[k]);
  if (!hints_.empty()) index.cache().prefetch(hints_);
}

void SearchedRegion::prefetch_ahead(const geometry::Box& next_region, std::uint32_t from_tet) {
  const CollisionIndex& index = *index_;
  const TetMesh& mesh = index.mesh();
  const WalkResult ahead = locate_point(mesh, from_tet, centre_in_mesh_box(next_region, index));
  if (ahead.tet == TetMesh::no_neighbour ||
      !geometry::boxes_overlap(next_region, mesh.bounds(ahead.tet)))
    return;
  hints_.clear();
  for (const std::uint32_t tet :
       tets_near_box(mesh, index.tet_filter(), ahead.tet, next_region, prefetch_search_).tets) {
    const std::uint32_t shard = index.shard_of_tet(tet);
    if (shard != TetMesh::no_neighbour &&
        geometry::boxes_overlap(next_region, index.shard_bounds(shard)) &&
        !index.cache().contains(shard))
      hints_.push_back(shard);
  }
  if (!hints_.empty()) index.cache().prefetch(hints_);
}

void SearchedRegion::release() {
  pins_.clear();
  shards_.clear();
  shard_reach_.clear();
  shard_tet_.clear();
  valid_ = false;
}

const Shard& SearchedRegion::acquire(std::size_t k, ShardPin& local_pin, StepCounters& counters) {
  const CollisionIndex& index = *index_;
  const std::uint32_t shard_id = shards_[k];
  ShardPin& pin = keep_pins_ ? pins_[k] : local_pin;
  if (!pin) {
    const auto acquire_start = Clock::now();
    const std::uint64_t misses_before = index.cache().miss_count();
    try {
      pin = index.cache().acquire(shard_id);
    } catch (const InputError&) {
      if (!keep_pins_) throw;
      // The budget cannot hold the region's pins after all: release them and go on one
      // shard at a time.
      keep_pins_ = false;
      pins_.clear();
      local_pin = index.cache().acquire(shard_id);
    }
    counters.shard_misses += std::uint32_t(index.cache().miss_count() - misses_before);
    counters.shard_seconds += seconds_since(acquire_start);
  }
  return keep_pins_ ? *pins_[k] : *local_pin;
}

const Shard* SearchedRegion::resident(std::size_t k) {
  const CollisionIndex& index = *index_;
  if (keep_pins_ && !pins_[k] && index.cache().contains(shards_[k])) {
    try {
      pins_[k] = index.cache().acquire(shards_[k]);
    } catch (const InputError&) {
      // evicted meanwhile, and the budget holds no more pins: cut its reach instead
    }
  }
  return keep_pins_ && pins_[k] ? &*pins_[k] : nullptr;
}

}  // namespace tetrapage
