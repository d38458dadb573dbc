#pragma once
/// @file CollisionIndex.h
/// An opened index: the coarse mesh and the shard tables stay resident; shards are paged in
/// on demand by a byte-budgeted cache (ShardCache). Thread-safe: any number of flying objects,
/// each used from its own thread, may share one CollisionIndex.

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <vector>

#include "tetrapage/formats/base/ByteSize.h"
#include "tetrapage/formats/index/IndexParts.h"
#include "tetrapage/formats/index/IndexReader.h"
#include "tetrapage/formats/index/TetMesh.h"
#include "tetrapage/runtime/geometry/Box.h"
#include "tetrapage/runtime/geometry/FloatBox.h"
#include "tetrapage/runtime/paging/Shard.h"
#include "tetrapage/runtime/paging/ShardArena.h"
#include "tetrapage/runtime/paging/ShardCache.h"
#include "tetrapage/runtime/paging/TetBoxFilter.h"

namespace tetrapage {

/// What a flight's peak resident memory may exceed the shard budget and the process's own
/// memory before any work (its libraries and threads) by: the coarse mesh and its tables,
/// read whole at open (the automatic region size keeps the mesh near 100k tets whatever the
/// model), the object's structures, and the buffers of the query and the prefetch thread: 52
/// to 59 MiB together at 100M triangles (docs/BENCHMARKS.md, "Memory held beside the shards at
/// 100M").
inline constexpr std::uint64_t kRuntimeOverheadAllowance = std::uint64_t(64) << 20;

struct CollisionIndexOptions {
  /// The byte budget of decoded shards held in memory (never exceeded; kDefaultMemoryBudget,
  /// ByteSize.h).
  std::uint64_t memory_budget_bytes = kDefaultMemoryBudget;
  /// Load the shards the motion is heading for in the background.
  bool prefetch = true;
  /// With prefetch, also hint the shards of the next region along the motion when an object
  /// searches a new region: a walk and a box search on the querying thread, for loads that a
  /// turning object rarely uses. Off by default: on the 10M scene's flights with the index in
  /// the page cache it cost more than it saved (docs/history/benchmarks-to-2026-11-26.md); where page-ins wait for a
  /// disk it may pay.
  bool prefetch_ahead = false;
  std::size_t prefetch_threads = 1;
  /// Decode shards into a ShardArena of the budget's size (at most the index's shards, plus an
  /// eighth for its size classes) whose pages a background thread faults in ahead of use, so
  /// that page-ins do not take the page faults. Off: shards are allocated by malloc.
  bool shard_arena = true;
  /// How long the cache's waits poll before they sleep (ShardCacheOptions::spin_before_sleep),
  /// and the index reader's wait for the chunk read lock (at most 100 us of it): while hints
  /// keep coming the prefetch thread keeps a core busy; 0 makes every wait sleep.
  std::chrono::microseconds spin_before_sleep{200};
};

class CollisionIndex {
 public:
  /// Opens and checks the index (format, version, tables) and reads the coarse mesh.
  /// @throw IoError (missing, unreadable), FormatError (not an index, wrong version,
  ///        inconsistent tables: names the file and the object), InputError (a zero budget,
  ///        or one smaller than the largest shard: names the budget, the shard and its size).
  explicit CollisionIndex(const std::filesystem::path& path, CollisionIndexOptions options = {});
  ~CollisionIndex();
  CollisionIndex(const CollisionIndex&) = delete;
  CollisionIndex& operator=(const CollisionIndex&) = delete;

  const std::filesystem::path& path() const { return reader_.path(); }
  const IndexHeader& header() const { return reader_.header(); }
  /// Every shard decodes to the coordinates the preprocess read (precision "exact" or
  /// "double"), so the copies of a triangle that crosses regions are identical.
  bool stores_input_coordinates() const { return stores_input_coordinates_; }
  const TetMesh& mesh() const { return mesh_; }
  const CollisionIndexOptions& options() const { return options_; }
  /// The box of the coarse mesh: every stored triangle lies inside it.
  const BoundingBox& mesh_bounds() const { return mesh_bounds_; }
  /// Each tet's bounding box and face planes, by tet index (for the box searches).
  const TetBoxFilter& tet_filter() const { return tet_filter_; }

  /// The shard of a tet, or TetMesh::no_neighbour for an empty region.
  std::uint32_t shard_of_tet(std::uint32_t tet) const { return tet_shard_[tet]; }
  std::uint32_t shard_count() const { return std::uint32_t(shard_bytes_.size()); }
  /// The bytes the cache reserves for a shard (an upper bound of its decoded size).
  std::uint64_t shard_bytes(std::uint32_t shard) const { return shard_bytes_[shard]; }
  /// A box enclosing the shard's stored triangles (without reading the shard; the stored
  /// bounds rounded outward to floats).
  geometry::Box shard_bounds(std::uint32_t shard) const { return shard_bounds_[shard].box(); }
  /// Decoded bytes of all shards (what "everything resident" costs).
  std::uint64_t total_shard_bytes() const { return total_shard_bytes_; }
  /// Loads every shard into the cache (everything resident: the reference a paged run is
  /// compared with), calling `progress(loaded)` after each.
  /// @throw InputError (naming the file) when the shards do not fit the budget or do not all
  ///        stay resident; what the cache throws for a damaged shard.
  void preload(const std::function<void(std::uint32_t)>& progress = {}) const;

  ShardCache<Shard>& cache() const { return *cache_; }
  /// The memory the shards are decoded into; null under `shard_arena = false`.
  const ShardArena* shard_arena() const { return arena_.get(); }

  /// The connected components of the parts' surfaces (SurfaceComponents.h): the ids that
  /// Shard::component_id returns. A component's part, whether it is closed, and its box.
  std::uint32_t component_count() const { return std::uint32_t(component_part_.size()); }
  /// The part of a component (kNoPart for an id the index does not list).
  std::uint32_t component_part(std::uint32_t component) const {
    return component < component_part_.size() ? component_part_[component] : kNoPart;
  }
  static constexpr std::uint32_t kNoPart = 0xffffffffu;
  /// Whether component `component` has a closed surface (false for an unknown id).
  bool component_closed(std::uint32_t component) const {
    return component < component_closed_.size() && component_closed_[component] != 0;
  }
  const geometry::Box& component_bounds(std::uint32_t component) const { return component_bounds_[component]; }
  /// False when no component of a part fits inside `box` (along some axis `box` is shorter
  /// than every such component): a step with that box needs no triangle that meets only the
  /// object's inside. Exact: rounded extents keep their order.
  bool may_hold_a_component(const geometry::Box& box) const {
    for (int a = 0; a < 3; ++a)
      if (box.hi[a] - box.lo[a] < shortest_component_extent_[a]) return false;
    return true;
  }

  /// The model's parts: names, instance paths and triangle counts (a contact's
  /// environment_part indexes them).
  const IndexParts& parts() const { return parts_; }

  /// A stored triangle, found by its model-wide id (a contact's environment_triangle): its
  /// corners as stored, its shard and its connected component.
  struct StoredTriangle {
    geometry::Triangle corners;
    std::uint32_t shard = 0;
    std::uint32_t component = 0;
  };
  /// Pages in the shards whose id range holds `id` (every shard for an index that does not
  /// record the ranges) until one holds it; nullopt when none does (a degenerate triangle the
  /// reader dropped has no id, so ids beyond input_triangles are never found).
  /// @throw what the shard cache throws (I/O and checksum errors naming the index).
  std::optional<StoredTriangle> stored_triangle(std::uint64_t id) const;

  /// Whether the index stores the interiors of closed components (preprocess --interiors on):
  /// each tet's reference point classified against them (ObstacleInterior.h).
  bool has_interiors() const { return !interior_offsets_.empty(); }
  /// A point strictly inside the tet whose classification is stored (has_interiors()).
  const geometry::Point& reference_point(std::uint32_t tet) const { return reference_points_[tet]; }
  /// False when the preprocess could not classify the tet's reference point.
  bool interior_decided(std::uint32_t tet) const {
    return interior_offsets_[tet + 1] == interior_offsets_[tet] ||
           interior_components_[interior_offsets_[tet]] != kInteriorUndecided;
  }
  /// The closed components whose interior holds the tet's reference point (sorted; empty for
  /// an undecided tet).
  std::span<const std::uint32_t> interior_components(std::uint32_t tet) const {
    if (!interior_decided(tet)) return {};
    return std::span<const std::uint32_t>(interior_components_).subspan(
        interior_offsets_[tet], interior_offsets_[tet + 1] - interior_offsets_[tet]);
  }
  /// The marker of an undecided tet in /tables/interior_components.
  static constexpr std::uint32_t kInteriorUndecided = 0xffffffffu;

 private:
  void check_budget_fits_shards() const;
  void read_components(const std::string& where);
  void read_interiors(const std::string& where);
  // Each shard's smallest and largest triangle id (2 per shard), or empty for an index from
  // before the table. @throw FormatError for a table of the wrong length.
  const std::vector<std::uint64_t>& shard_id_ranges() const;

  IndexReader reader_;
  CollisionIndexOptions options_;
  bool stores_input_coordinates_ = false;
  TetMesh mesh_;
  BoundingBox mesh_bounds_;
  TetBoxFilter tet_filter_;
  std::vector<std::uint32_t> tet_shard_;
  std::vector<std::uint64_t> shard_bytes_;
  std::vector<geometry::FloatBox> shard_bounds_;
  std::uint64_t total_shard_bytes_ = 0;
  std::vector<std::uint32_t> component_part_;
  std::vector<std::uint8_t> component_closed_;
  std::vector<geometry::Box> component_bounds_;
  /// Per axis, the shortest extent of a part's component (infinite when none).
  Vec3 shortest_component_extent_{std::numeric_limits<double>::infinity(),
                                  std::numeric_limits<double>::infinity(),
                                  std::numeric_limits<double>::infinity()};
  IndexParts parts_;
  mutable std::once_flag shard_id_ranges_read_;
  mutable std::vector<std::uint64_t> shard_id_ranges_;  // read on first use
  std::vector<geometry::Point> reference_points_;
  std::vector<std::uint64_t> interior_offsets_;
  std::vector<std::uint32_t> interior_components_;
  std::unique_ptr<ShardArena> arena_;  // before the cache: its shards go first
  std::unique_ptr<ShardCache<Shard>> cache_;
};

}  // namespace tetrapage
