#pragma once
/// @file ShardCostModel.h
/// Which index suits a region: the expected time of a query (cells or nodes visited, triangle
/// references examined) plus the amortised time of paging the shard in, with constants
/// measured by bench/runtime/ShardBench.cpp on the build machine.

#include <cstdint>

#include "tetrapage/preprocess/ShardBuilder.h"

namespace tetrapage {

/// Measured costs (the defaults: ShardCostModel.cpp cites the bench run they come from).
struct ShardCostModel {
  /// The measured defaults.
  ShardCostModel();

  // CPU seconds per query = per-query fixed cost + per visit * cells or nodes visited +
  // per reference * triangle references examined (each: a mark or box test, and the exact
  // triangle/box test of a triangle met for the first time).
  double seconds_per_grid_query;       ///< fixed cost of a grid query
  double seconds_per_cell;             ///< per grid cell visited
  double seconds_per_grid_reference;   ///< per reference in a visited cell (repeats included)
  double seconds_per_rtree_query;      ///< fixed cost of an R-tree query
  double seconds_per_node;             ///< per R-tree node whose box is tested
  double seconds_per_rtree_reference;  ///< per triangle in a visited leaf
  double seconds_per_byte;             ///< per payload byte paged in (read, decompress, decode)
  /// Queries a shard answers, on average, each time it is paged in: a property of the scene
  /// and the memory budget, not of the machine.
  double queries_per_page_in = 256;
  /// Query boxes sampled per region when estimating (centred on spread-out triangles). Their
  /// exact triangle/box tests dominate the preprocess's shard stage: 8 made the same choices
  /// as 48 on the 1M demo scene (3,003 R-trees either way) at half the stage's time.
  std::uint32_t sample_queries = 8;
};

/// What one kind is expected to cost for one region.
struct ShardCostEstimate {
  ShardKind kind = ShardKind::grid;
  ShardLayout layout;                 ///< the layout the estimate was made with
  double visited_per_query = 0;       ///< cells or nodes
  double references_per_query = 0;    ///< triangle references examined
  std::uint64_t payload_bytes = 0;
  double query_seconds = 0;   ///< per query
  double paging_seconds = 0;  ///< per query: paging cost / queries_per_page_in
  double total_seconds() const { return query_seconds + paging_seconds; }
  /// The shard the estimate measured (so the chosen one need not be built again).
  BuiltShard built;
};

/// The estimates of both kinds (each with its best layout among a few tried) and the choice.
struct ShardCostReport {
  ShardCostEstimate grid;   ///< measured only when grid_measured
  ShardCostEstimate rtree;
  /// A lower bound of every grid layout's total_seconds(), computed without building one.
  double grid_floor_seconds = 0;
  bool grid_measured = true;
  ShardKind chosen = ShardKind::grid;
  const ShardCostEstimate& chosen_estimate() const {
    return chosen == ShardKind::grid ? grid : rtree;
  }
};

/// Whether the grid layouts are built and measured always, or only when their cost floor is
/// below the best R-tree's cost (the choice is the same: a grid costs at least its floor).
enum class GridTrials : std::uint8_t { always, when_they_can_win };

/// Estimates, for `region` queried by cubes of side query_extent centred on sampled triangles,
/// each kind's cost: it builds the candidate layouts (grids of 1/4, 1 and 4 cells per
/// triangle; R-tree leaves of 16, 8 and 4, the smaller only while they are cheaper and only in
/// regions of at most 1,024 triangles), runs the
/// sampled queries and counts.
/// @throw InputError as build_shard, or if query_extent is negative or not finite.
ShardCostReport estimate_shard_costs(const ShardTriangles& region, double query_extent,
                                     StoredPrecision precision, const ShardCostModel& model,
                                     GridTrials grid_trials = GridTrials::when_they_can_win);

}  // namespace tetrapage
