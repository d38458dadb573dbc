#include "Shards.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "OrderedPipeline.h"
#include "tetrapage/formats/base/Progress.h"
#include "tetrapage/preprocess/ShardBuilder.h"
#include "tetrapage/preprocess/ShardCostModel.h"

namespace tetrapage {
namespace {

// One shard built and compressed, waiting for its turn to be appended.
struct ReadyShard {
  BuiltShard built;  // its payload freed once encoded
  std::uint64_t payload_bytes = 0;
  EncodedShard encoded;
  BoundingBox bounds;
  std::uint64_t lowest_id = 0, highest_id = 0;
  std::uint32_t tet = 0;
};

// The extent of the queries the cost model prices: the option, else a twentieth of the
// model's largest side.
double query_extent_for(const PreprocessOptions& options, const BoundingBox& model_bounds) {
  if (options.query_extent > 0) return options.query_extent;
  const Vec3 size = model_bounds.size();
  return 0.05 * std::max({size[0], size[1], size[2]});
}

// The shard of copies [first, last) (one tet's) of a bucket: the kind asked, or the cost
// model's choice, built and encoded with the writer's options.
std::shared_ptr<ReadyShard> build_encoded_shard(const BucketCopies& copies, std::size_t first,
                                                std::size_t last, double query_extent,
                                                const ShardCostModel& cost_model,
                                                const PreprocessOptions& options,
                                                const IndexWriterOptions& writer_options) {
  auto ready = std::make_shared<ReadyShard>();
  std::vector<geometry::Triangle> triangles;
  std::vector<std::uint64_t> ids;
  std::vector<std::uint32_t> parts;
  triangles.reserve(last - first);
  ids.reserve(last - first);
  parts.reserve(last - first);
  copies.gather(first, last, triangles, ids, parts);
  for (const geometry::Triangle& t : triangles)
    for (const auto& p : t) ready->bounds.extend(p);
  ready->tet = copies.tet(first);
  const auto [lowest, highest] = std::minmax_element(ids.begin(), ids.end());
  ready->lowest_id = *lowest;
  ready->highest_id = *highest;
  const ShardTriangles region{triangles, ids, parts};
  if (options.shard == ShardChoice::automatic) {
    ShardCostReport costs =
        estimate_shard_costs(region, query_extent, options.precision, cost_model);
    ready->built =
        std::move(costs.chosen == ShardKind::grid ? costs.grid.built : costs.rtree.built);
  } else {
    ready->built =
        build_shard(region, options.shard == ShardChoice::grid ? ShardKind::grid : ShardKind::rtree,
                    options.precision);
  }
  ready->encoded = encode_shard(ready->built.payload, writer_options);
  ready->payload_bytes = ready->built.payload.size();
  std::vector<std::byte>().swap(ready->built.payload);
  return ready;
}

// Appends a ready shard to the index, its rows to the tables and its figures to the summary.
void append_shard(const ReadyShard& ready, IndexWriter& writer, ShardTables& tables,
                  PreprocessSummary& summary) {
  const BuiltShard& built = ready.built;
  // Stored vertices lie within the shard's rounding distance of the input
  // ones: grow the input box by it (and a few ulps) so the runtime can skip
  // shards unread.
  BoundingBox bounds = ready.bounds;
  for (int a = 0; a < 3; ++a) {
    const double grow = built.max_rounding_distance +
                        0x1p-50 * std::max(std::fabs(bounds.lo[a]), std::fabs(bounds.hi[a]));
    bounds.lo[a] -= grow;
    bounds.hi[a] += grow;
  }
  tables.shard_bounds.insert(tables.shard_bounds.end(), {bounds.lo[0], bounds.lo[1], bounds.lo[2],
                                                         bounds.hi[0], bounds.hi[1], bounds.hi[2]});
  const std::uint32_t shard = writer.append_encoded_shard(ready.encoded);
  tables.tet_shard[ready.tet] = shard;
  tables.shard_tet.push_back(ready.tet);
  tables.shard_kind.push_back(std::uint8_t(built.kind));
  tables.shard_triangles.push_back(built.triangle_count);
  tables.shard_id_ranges.insert(tables.shard_id_ranges.end(), {ready.lowest_id, ready.highest_id});
  summary.stored_triangles += built.triangle_count;
  summary.shard_payload_bytes += ready.payload_bytes;
  summary.max_rounding_distance =
      std::max(summary.max_rounding_distance, built.max_rounding_distance);
  (built.kind == ShardKind::grid ? summary.grid_shards : summary.rtree_shards) += 1;
  summary.float_shards += built.precision == StoredPrecision::float32;
}

}  // namespace

ShardTables build_shards(std::span<CopyBucket> buckets, std::span<const std::uint32_t> tet_rank,
                         std::size_t tet_count, IngestedModel& model, IndexWriter& writer,
                         const PreprocessOptions& options, PreprocessSummary& summary) {
  ShardTables tables;
  tables.tet_shard.assign(tet_count, TetMesh::no_neighbour);
  const double query_extent = query_extent_for(options, model.bounds);
  summary.query_extent = query_extent;
  const ShardCostModel cost_model;
  Progress progress("building shards", tet_count, options.progress, options.on_progress);
  for (auto& bucket : buckets) {
    BucketCopies copies = bucket.take();
    // The copies in (tet rank, id) order: each tet's then lie side by side.
    const std::vector<std::size_t> group_start = copies.order_by_tet(tet_rank);
    // Built and compressed on all threads, appended in order on one while the others build
    // on: a pipeline with a few shards in flight (the bucket's shards are never all held).
    produce_in_parallel_consume_in_order(
        group_start.size() - 1, 4 * std::size_t(tbb::this_task_arena::max_concurrency()),
        [&](std::size_t g) {
          return build_encoded_shard(copies, group_start[g], group_start[g + 1], query_extent,
                                     cost_model, options, writer.options());
        },
        [&](const std::shared_ptr<ReadyShard>& ready) {
          append_shard(*ready, writer, tables, summary);
          progress.advance();
        });
  }
  progress.finish();
  model.soups.clear();
  summary.empty_regions = tet_count - tables.shard_tet.size();
  summary.duplication_factor = double(summary.stored_triangles) / double(model.triangle_count);
  return tables;
}

}  // namespace tetrapage
