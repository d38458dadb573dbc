#include "tetrapage/preprocess/ShardCostModel.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/runtime/geometry/Box.h"
#include "tetrapage/runtime/paging/Shard.h"

namespace tetrapage {

// Measured by bench/runtime/ShardBench.cpp on the build machine (2 cores, idle), CPU time,
// three runs each, on 2026-11-22 with index format 3 (the runtime's shard queries and page-ins
// as they are then):
//  BM_CostFit (non-negative least squares over 45 workloads per kind: 3 regions x 5 query
//  extents x 3 layouts, median of 5 x 512 queries each):
//    grid:  401, 407, 436 ns per query; 17.1, 17.5, 17.8 ns per reference; per cell and per
//           candidate indistinguishable from 0 (fitted 0; a cell visit is an empty-list read)
//    rtree: 0 ns per query; 25.1, 28.0, 28.1 ns per node; 12.7, 13.0, 13.8 ns per reference
//  BM_PageIn (IndexReader::read_shard of a one-shard index in the page cache, LZ4, and
//  Shard::decode, per decoded byte): 0.42 to 0.93 ns, median of the six workloads 0.61 in
//  both runs. Format 2's deflate, and zlib level 4 before it, made this 5.7 ns.
// The cell cost is set to 1 ns (not the fitted 0) so that finer grids are never free.
ShardCostModel::ShardCostModel()
    : seconds_per_grid_query(407e-9),
      seconds_per_cell(1e-9),
      seconds_per_grid_reference(17.5e-9),
      seconds_per_rtree_query(0),
      seconds_per_node(28e-9),
      seconds_per_rtree_reference(13e-9),
      seconds_per_byte(0.6e-9) {}

namespace {

// How close the middle grid layout must come to the best R-tree for the other two grid layouts
// to be tried (on the 10M scene the R-tree won 50,278 of 50,280 regions with all six tried).
constexpr double kGridTrialMargin = 1.5;

// Regions of more triangles than this try R-tree leaves of 16 alone (see estimate_shard_costs).
constexpr std::size_t kSmallerLeafTriangles = 256;

ShardCostEstimate estimate(const StoredRegion& region, ShardKind kind, const ShardLayout& layout,
                           const std::vector<geometry::Box>& queries,
                           const ShardCostModel& model) {
  BuiltShard built = region.build(kind, layout);
  const Shard shard = Shard::decode(built.payload);
  ShardQueryCounters counters;
  for (const geometry::Box& box : queries) shard.count_query(box, counters);
  ShardCostEstimate e;
  e.kind = kind;
  e.layout = layout;
  const double q = double(std::max<std::size_t>(queries.size(), 1));
  e.visited_per_query = double(counters.visited) / q;
  e.references_per_query = double(counters.references) / q;
  e.payload_bytes = built.payload.size();
  e.query_seconds =
      kind == ShardKind::grid
          ? model.seconds_per_grid_query + model.seconds_per_cell * e.visited_per_query +
                model.seconds_per_grid_reference * e.references_per_query
          : model.seconds_per_rtree_query + model.seconds_per_node * e.visited_per_query +
                model.seconds_per_rtree_reference * e.references_per_query;
  e.paging_seconds = model.seconds_per_byte * double(e.payload_bytes) /
                     std::max(model.queries_per_page_in, 1e-9);
  e.built = std::move(built);
  return e;
}

// No grid layout can cost less than this: its fixed cost, a reference to every triangle with a
// stored corner in the query box (such a triangle lies in a cell the query visits), and paging
// a payload with the R-tree's sections but its nodes, one cell offset and a reference per
// triangle (alignment aside). Cheap: no grid is built.
double grid_cost_floor(const StoredRegion& region, const ShardCostEstimate& rtree,
                       const std::vector<geometry::Box>& queries, const ShardCostModel& model) {
  const std::span<const geometry::Triangle> triangles = region.stored_triangles();
  std::uint64_t references = 0;
  for (const geometry::Box& q : queries)
    for (const geometry::Triangle& t : triangles)
      references += geometry::box_contains(q, t[0]) || geometry::box_contains(q, t[1]) ||
                    geometry::box_contains(q, t[2]);
  const double real_bytes = rtree.built.precision == StoredPrecision::float32 ? 4 : 8;
  const double node_bytes = double(rtree.built.rtree_nodes) * (6 * real_bytes + 8);
  const double reference_bytes = triangles.size() <= 65536 ? 2 : 4;
  const double payload = std::max(
      0.0, double(rtree.payload_bytes) - node_bytes - 64 + 8 + reference_bytes * double(triangles.size()));
  const double q = double(std::max<std::size_t>(queries.size(), 1));
  return model.seconds_per_grid_query + model.seconds_per_grid_reference * double(references) / q +
         model.seconds_per_byte * payload / std::max(model.queries_per_page_in, 1e-9);
}

}  // namespace

ShardCostReport estimate_shard_costs(const ShardTriangles& region, double query_extent,
                                     StoredPrecision precision, const ShardCostModel& model,
                                     GridTrials grid_trials) {
  if (!(query_extent >= 0) || !std::isfinite(query_extent))
    throw InputError("query extent " + std::to_string(query_extent) +
                     " is not a finite non-negative length");
  // Cubes of side query_extent centred on triangles spread over the region (every
  // (n / samples)-th): queries come where the geometry is, as a flying object near contact.
  std::vector<geometry::Box> queries;
  const std::size_t n = region.triangles.size();
  const std::size_t samples = std::min<std::size_t>(n, std::max<std::uint32_t>(model.sample_queries, 1));
  for (std::size_t i = 0; i < samples; ++i) {
    const geometry::Triangle& t = region.triangles[i * n / std::max<std::size_t>(samples, 1)];
    geometry::Point centre;
    for (int k = 0; k < 3; ++k) centre[k] = (t[0][k] + t[1][k] + t[2][k]) / 3;
    geometry::Box box;
    for (int k = 0; k < 3; ++k) {
      box.lo[k] = centre[k] - 0.5 * query_extent;
      box.hi[k] = centre[k] + 0.5 * query_extent;
    }
    queries.push_back(box);
  }
  const StoredRegion stored(region, precision);
  ShardCostReport report;
  bool first = true;
  // Largest leaves first, smaller ones while they keep getting cheaper: the cost falls and
  // then rises with the leaf size, and 16 won 1,453 of the 1M demo scene's 1,470 regions, so
  // most regions build two trees instead of three. Regions of more than kSmallerLeafTriangles
  // try 16 alone. With every leaf tried, smaller leaves won in regions of fewer than 256
  // triangles on the 10M scene (96 of 24,967 shards, 79 of them under 64 triangles), and in two
  // regions of 570 and 834 triangles on the 1M scene (float): those two keep leaves of 16. At 10M
  // the shards are the same bytes as with the limit at 1,024 and the stage takes 17 % less time.
  for (const std::uint32_t leaf : {16u, 8u, 4u}) {
    if (!first && n > kSmallerLeafTriangles) break;
    ShardLayout layout;
    layout.rtree_leaf_size = leaf;
    ShardCostEstimate e = estimate(stored, ShardKind::rtree, layout, queries, model);
    if (!first && e.total_seconds() >= report.rtree.total_seconds()) break;
    report.rtree = std::move(e);
    first = false;
  }
  // Grids cost the most to build: none is when even the floor of their cost does not beat the
  // best R-tree (on the 10M scene the R-tree won 24,966 of 24,967 regions).
  report.grid_floor_seconds = grid_cost_floor(stored, report.rtree, queries, model);
  if (grid_trials == GridTrials::when_they_can_win &&
      report.grid_floor_seconds >= report.rtree.total_seconds()) {
    report.grid_measured = false;
    report.chosen = ShardKind::rtree;
    return report;
  }
  // The middle grid first; the coarser and finer ones only when it comes within
  // kGridTrialMargin of the best R-tree.
  first = true;
  for (const double cells_per_triangle : {1.0, 0.25, 4.0}) {
    if (!first && report.grid.total_seconds() > kGridTrialMargin * report.rtree.total_seconds()) break;
    ShardLayout layout;
    layout.grid_cells_per_triangle = cells_per_triangle;
    ShardCostEstimate e = estimate(stored, ShardKind::grid, layout, queries, model);
    if (first || e.total_seconds() < report.grid.total_seconds()) report.grid = std::move(e);
    first = false;
  }
  report.chosen = report.rtree.total_seconds() < report.grid.total_seconds() ? ShardKind::rtree
                                                                             : ShardKind::grid;
  return report;
}

ShardKind choose_shard_kind(const ShardTriangles& region, double query_extent,
                            const ShardCostModel& model) {
  return estimate_shard_costs(region, query_extent, StoredPrecision::float32, model).chosen;
}

}  // namespace tetrapage
