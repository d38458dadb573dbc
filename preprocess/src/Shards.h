#pragma once
/// @file Shards.h (private)
/// Stage 6 of the preprocess (docs/ARCHITECTURE.md): the shards, bucket by bucket, built,
/// compressed and appended to the index. The builder of one shard, build_shard, is public:
/// tetrapage/preprocess/ShardBuilder.h.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "Buckets.h"
#include "Ingest.h"
#include "tetrapage/formats/index/IndexWriter.h"
#include "tetrapage/preprocess/PreprocessOptions.h"
#include "tetrapage/preprocess/PreprocessSummary.h"

namespace tetrapage {

/// The shard tables (docs/FORMAT.md), a row per shard in the order they were appended.
struct ShardTables {
  std::vector<std::uint32_t> tet_shard;  ///< per tet; TetMesh::no_neighbour: no shard
  std::vector<std::uint32_t> shard_tet, shard_triangles;
  std::vector<std::uint8_t> shard_kind;
  std::vector<double>
      shard_bounds;  ///< 6 per shard: lo xyz, hi xyz, enclosing the stored triangles
  std::vector<std::uint64_t> shard_id_ranges;  ///< 2 per shard: its smallest and largest id
};

/// Empties the buckets one at a time into shards (a tet's shard holds its copies; `tet_rank`:
/// the tets' Morton ranks, the order of the shards on disk), appended to `writer`; the
/// model's soups are cleared at the end.
ShardTables build_shards(std::span<CopyBucket> buckets, std::span<const std::uint32_t> tet_rank,
                         std::size_t tet_count, IngestedModel& model, IndexWriter& writer,
                         const PreprocessOptions& options, PreprocessSummary& summary);

}  // namespace tetrapage
