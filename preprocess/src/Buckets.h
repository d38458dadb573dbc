#pragma once
/// @file Buckets.h
/// Stage 4 of the preprocess (docs/ARCHITECTURE.md): the tets in Morton order, cut into
/// buckets whose estimated triangle copies fit the budget; and the buckets themselves, which
/// the binning fills and the shard stage empties one at a time.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <vector>

#include "Ingest.h"
#include "MortonGrid.h"
#include "TriangleRecord.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/index/TetMesh.h"
#include "tetrapage/preprocess/PreprocessOptions.h"
#include "tetrapage/preprocess/PreprocessSummary.h"
#include "tetrapage/preprocess/RecordSpill.h"
#include "tetrapage/preprocess/SoupSpill.h"

namespace tetrapage {

/// The tets in Morton order of their centroids: neighbouring shards sit side by side on disk.
struct TetOrder {
  std::vector<std::uint32_t> order;  ///< the tet of each rank
  std::vector<std::uint32_t> rank;   ///< the rank of each tet
};

/// `mesh_grid`: the Morton grid of the box the coarse mesh covers.
TetOrder order_tets(const TetMesh& mesh, const MortonGrid& mesh_grid);

/// Buckets of consecutive tets (in Morton order) whose estimated triangle copies fit in a
/// third of the budget; the estimate locates the sampled centroids, with room for duplicates.
struct BucketPlan {
  std::vector<std::uint32_t> bucket_of;  ///< per tet
  std::size_t bucket_count = 1;
};

BucketPlan plan_buckets(const IngestedModel& model, const TetMesh& mesh,
                        const MortonGrid& mesh_grid, std::span<const std::uint32_t> tet_order,
                        const PreprocessOptions& options);

// The binned copies of one bucket: records in a spill file or, while the ingested soups are
// held in memory, only (id, tet) pairs, 12 bytes instead of 88.
#pragma pack(push, 4)
struct CopyPair {
  std::uint64_t id;
  std::uint32_t tet;
};
#pragma pack(pop)

// One bucket's copies as the shard stage reads them: records read back from a spill file, or
// (id, tet) pairs whose records the soups give when a shard gathers its triangles (a bucket's
// records, 88 bytes a copy, are then never all held: at 10M they were 1.1 GB).
class BucketCopies {
 public:
  explicit BucketCopies(std::vector<TriangleRecord> records) : records_(std::move(records)) {}
  BucketCopies(std::vector<CopyPair> pairs, const SoupSpill<TriangleRecord>& soups)
      : soups_(&soups), pairs_(std::move(pairs)) {}
  /// Orders the copies by their tet's rank, each tet's by id; returns where each tet's copies
  /// start in that order, and their count last. The pairs are moved into that order (a second
  /// array, 12 bytes a copy: the sorts and gathers then read them in order, where reading them
  /// through positions was a cache miss each); the records, 88 bytes, are read through positions.
  std::vector<std::size_t> order_by_tet(std::span<const std::uint32_t> rank);
  /// The tet of the i-th copy in order_by_tet's order.
  std::uint32_t tet(std::size_t i) const {
    return soups_ ? pairs_[i].tet : records_[order_[i]].tet;
  }
  /// Appends the triangles, ids and parts of copies [first, last) of order_by_tet's order.
  void gather(std::size_t first, std::size_t last, std::vector<geometry::Triangle>& triangles,
              std::vector<std::uint64_t>& ids, std::vector<std::uint32_t>& parts) const;

 private:
  const SoupSpill<TriangleRecord>* soups_ = nullptr;
  std::vector<TriangleRecord> records_;
  std::vector<CopyPair> pairs_;
  std::vector<std::uint32_t> order_;  ///< of the records
};

class CopyBucket {
 public:
  CopyBucket(std::filesystem::path file, const SoupSpill<TriangleRecord>& soups)
      : soups_(soups.spilled() ? nullptr : &soups) {
    if (soups_ == nullptr) records_.emplace(std::move(file));
  }
  /// Records while the soups are spilled; (id, tet) pairs while they are in memory.
  void append(std::span<const TriangleRecord> copies) {
    if (!records_) throw Error("a bucket of (id, tet) pairs was given records");
    records_->append(copies);
  }
  void append(std::span<const CopyPair> copies) {
    if (records_) throw Error("a bucket that spills records was given (id, tet) pairs");
    pairs_.insert(pairs_.end(), copies.begin(), copies.end());
  }
  /// The copies, taken out of the bucket (which is then empty, its spill file removed).
  BucketCopies take();

 private:
  const SoupSpill<TriangleRecord>* soups_;
  std::optional<RecordSpill<TriangleRecord>> records_;  ///< when the soups are spilled
  std::vector<CopyPair> pairs_;
};

/// The plan's buckets, empty: each spills to a file in `spill_folder` when the soups are
/// spilled, else keeps (id, tet) pairs in memory.
std::vector<CopyBucket> make_buckets(std::size_t bucket_count,
                                     const std::filesystem::path& spill_folder,
                                     const SoupSpill<TriangleRecord>& soups);

}  // namespace tetrapage
