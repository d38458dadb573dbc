#pragma once
/// @file SearchedRegion.h (private)
/// The searched region of a flying object (steps 2 to 4 of the runtime step): a box grown
/// around the object's box, the tets near it, their shards, pinned while the object's box
/// stays inside it (most steps then touch neither the mesh nor the cache), and the prefetch
/// hints for where the motion heads.

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/runtime/geometry/Box.h"
#include "tetrapage/runtime/paging/BoxSearch.h"
#include "tetrapage/runtime/paging/CollisionIndex.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/runtime/query/ObstacleInterior.h"

namespace tetrapage {

class SearchedRegion {
 public:
  explicit SearchedRegion(const CollisionIndex& index) : index_(&index) {}

  /// The box lies inside the region searched last (no walk nor search needed).
  bool contains(const geometry::Box& box) const {
    return valid_ && geometry::box_contains(box_, box);
  }
  /// Walk, box search and pinning for a new searched region around `box`; false when the box
  /// lies outside the mesh. `motion`: how far the object's box centre moved since the last
  /// step (none on a first step), for the prefetch hints.
  bool search(const geometry::Box& box, const std::optional<Vec3>& motion, StepCounters& counters);
  /// Outside the model nothing needs the region's shards: give their budget back.
  void release();

  const geometry::Box& box() const { return box_; }
  std::size_t size() const { return shards_.size(); }
  /// The box where shard k can matter: its tet's box and its stored bounds, intersected.
  const geometry::Box& reach(std::size_t k) const { return shard_reach_[k]; }
  /// The tet that named shard k.
  std::uint32_t tet(std::size_t k) const { return shard_tet_[k]; }
  /// Shard k is pinned already (kept pinned while the object stays in the region).
  bool pinned(std::size_t k) const { return keep_pins_ && pins_[k]; }
  /// The pins held, for walks that read the region's shards.
  std::span<const ShardPin> pins() const { return pins_; }

  /// Hints the prefetcher to page in the shards that `needs` and are not resident, from the
  /// last, while this thread acquires them from the first.
  template <class Needs>
  void prefetch_needed(Needs&& needs);
  /// Shard k, pinned for the step: in the region's pins when it keeps them, else in
  /// `local_pin`. Counts the page-ins and their time.
  const Shard& acquire(std::size_t k, ShardPin& local_pin, StepCounters& counters);
  /// Shard k if it is resident (pinned for the region when it keeps pins), else null.
  const Shard* resident(std::size_t k);

 private:
  // The last region's pins of the shards this region keeps move to this region's pins (when it
  // keeps pins at all); the rest are released.
  void move_kept_pins();
  // Hints the prefetcher with the shards `box` would meet a few steps ahead along `motion`.
  void hint_ahead(const geometry::Box& box, const geometry::Box& region,
                  const std::optional<Vec3>& motion);
  // Hints the prefetcher with the shards of the next region along the motion.
  void prefetch_ahead(const geometry::Box& next_region, std::uint32_t from_tet);

  const CollisionIndex* index_;
  std::uint32_t last_tet_ = 0;  ///< where the last walk ended: the next starts there
  BoxSearchScratch search_;
  BoxSearchScratch prefetch_search_;
  geometry::Box box_;
  bool valid_ = false;
  Vec3 centre_{};  ///< the object's box centre when the region was searched
  std::vector<std::uint32_t> shards_;
  std::vector<geometry::Box>
      shard_reach_;  ///< parallel to shards_: tet box and stored bounds, intersected
  std::vector<std::uint32_t> shard_tet_;  ///< parallel to shards_: the shard's tet
  std::vector<ShardPin> pins_;            ///< parallel to shards_; empty until needed
  // The last region's shards and pins while a search builds the next (reused buffers).
  std::vector<std::uint32_t> previous_shards_;
  std::vector<ShardPin> previous_pins_;
  bool keep_pins_ = false;
  std::vector<std::uint32_t> hints_;
};

template <class Needs>
void SearchedRegion::prefetch_needed(Needs&& needs) {
  const CollisionIndex& index = *index_;
  if (!index.options().prefetch) return;
  // Several shards to page in: the prefetch thread loads them from the last while this
  // thread loads from the first (on two cores, a step entering a new region waits about half).
  hints_.clear();
  for (std::size_t k = 0; k < shards_.size(); ++k)
    if (!pinned(k) && needs(k) && !index.cache().contains(shards_[k])) hints_.push_back(shards_[k]);
  if (hints_.size() > 1) index.cache().prefetch_urgently(std::span(hints_).subspan(1));
}

}  // namespace tetrapage
