#pragma once
/// @file CollisionIndex.h
/// An opened index: the coarse mesh and the shard tables stay resident; shards are paged in
/// on demand by a byte-budgeted cache (ShardCache). Thread-safe: any number of flying objects,
/// each used from its own thread, may share one CollisionIndex.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <vector>

#include "tetrapage/formats/IndexReader.h"
#include "tetrapage/formats/TetMesh.h"
#include "tetrapage/runtime/Shard.h"
#include "tetrapage/runtime/ShardCache.h"
#include "tetrapage/runtime/geometry/Box.h"

namespace tetrapage {

struct CollisionIndexOptions {
  /// The byte budget of decoded shards held in memory (never exceeded).
  std::uint64_t memory_budget_bytes = std::uint64_t(256) << 20;
  /// Load the shards the motion is heading for in the background.
  bool prefetch = true;
  std::size_t prefetch_threads = 1;
};

class CollisionIndex {
 public:
  /// Opens and checks the index (format, version, tables) and reads the coarse mesh.
  /// @throw IoError (missing, unreadable), FormatError (not an index, wrong version,
  ///        inconsistent tables: names the file and the object), InputError (a zero budget).
  explicit CollisionIndex(const std::filesystem::path& path, CollisionIndexOptions options = {});
  ~CollisionIndex();
  CollisionIndex(const CollisionIndex&) = delete;
  CollisionIndex& operator=(const CollisionIndex&) = delete;

  const std::filesystem::path& path() const { return reader_.path(); }
  const IndexHeader& header() const { return reader_.header(); }
  const TetMesh& mesh() const { return mesh_; }
  const CollisionIndexOptions& options() const { return options_; }
  /// The box of the coarse mesh: every stored triangle lies inside it.
  const BoundingBox& mesh_bounds() const { return mesh_bounds_; }

  /// The shard of a tet, or TetMesh::no_neighbour for an empty region.
  std::uint32_t shard_of_tet(std::uint32_t tet) const { return tet_shard_[tet]; }
  std::uint32_t shard_count() const { return std::uint32_t(shard_bytes_.size()); }
  /// The bytes the cache reserves for a shard (an upper bound of its decoded size).
  std::uint64_t shard_bytes(std::uint32_t shard) const { return shard_bytes_[shard]; }
  /// A box enclosing the shard's stored triangles (without reading the shard).
  const geometry::Box& shard_bounds(std::uint32_t shard) const { return shard_bounds_[shard]; }
  /// Decoded bytes of all shards (what "everything resident" costs).
  std::uint64_t total_shard_bytes() const { return total_shard_bytes_; }

  ShardCache<Shard>& cache() const { return *cache_; }

 private:
  IndexReader reader_;
  CollisionIndexOptions options_;
  TetMesh mesh_;
  BoundingBox mesh_bounds_;
  std::vector<std::uint32_t> tet_shard_;
  std::vector<std::uint64_t> shard_bytes_;
  std::vector<geometry::Box> shard_bounds_;
  std::uint64_t total_shard_bytes_ = 0;
  std::unique_ptr<ShardCache<Shard>> cache_;
};

}  // namespace tetrapage
