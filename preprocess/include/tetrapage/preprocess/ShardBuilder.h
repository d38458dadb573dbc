#pragma once
/// @file ShardBuilder.h
/// Builds the payload of one region's shard (docs/SHARD-FORMAT.md): deduplicated vertices
/// stored relative to an origin chosen so that the stored vertices are exact doubles, and a
/// uniform grid or an R-tree whose shape fits the region's own triangles.

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "tetrapage/runtime/geometry/Shapes.h"
#include "tetrapage/runtime/paging/ShardKind.h"

namespace tetrapage {

struct ShardCostModel;

/// One region's triangles (views; the caller owns them): triangles[i] has the model-wide id
/// ids[i] and the part id parts[i].
struct ShardTriangles {
  std::span<const geometry::Triangle> triangles;
  std::span<const std::uint64_t> ids;
  std::span<const std::uint32_t> parts;
};

/// The shape of a shard's index. Zeros mean "choose from the triangles".
struct ShardLayout {
  /// Grid cells along x, y, z; all three zero: chosen from grid_cells_per_triangle.
  std::array<std::uint32_t, 3> grid_cells{0, 0, 0};
  /// Target cell count per triangle when grid_cells is zero (cells are near-cubic, and an
  /// axis along which the region is thinner than a cell gets one cell).
  double grid_cells_per_triangle = 1.0;
  /// Triangles per R-tree leaf (at most); 0: 8.
  std::uint32_t rtree_leaf_size = 0;
  /// Children per R-tree node (at most), 2..16.
  std::uint32_t rtree_fanout = 8;
};

/// A built shard and what the preprocess reports about it.
struct BuiltShard {
  std::vector<std::byte> payload;
  ShardKind kind = ShardKind::grid;
  /// The shard's own type: float32 or float64 (for StoredPrecision::exact, whichever keeps the
  /// input's coordinates in this shard).
  StoredPrecision precision = StoredPrecision::float32;
  /// The largest Euclidean distance between an input vertex and its stored vertex.
  double max_rounding_distance = 0;
  geometry::Point origin{};
  std::uint32_t vertex_count = 0;  ///< after deduplication of the stored vertices
  std::uint32_t triangle_count = 0;
  std::array<std::uint32_t, 3> grid_cells{0, 0, 0};  ///< grid: the cells used
  std::uint64_t grid_references = 0;                 ///< grid: (triangle, cell) pairs
  std::uint32_t rtree_leaf_size = 0;                 ///< R-tree: the leaf size used
  std::uint32_t rtree_nodes = 0;                     ///< R-tree: node count
};

/// A region's triangles as a shard stores them (relative, deduplicated, rounded to the
/// precision), prepared once so that several layouts of one region can be built from them
/// (the cost model tries six). Holds views of `region`: its spans must outlive this object.
class StoredRegion {
 public:
  /// @throw InputError if the region is empty, the spans differ in size, a coordinate is not
  ///   finite, there are 2^32 triangles or more, or float32 is asked for coordinates beyond
  ///   float's range.
  StoredRegion(const ShardTriangles& region, StoredPrecision precision);
  ~StoredRegion();
  StoredRegion(StoredRegion&&) noexcept;
  StoredRegion& operator=(StoredRegion&&) noexcept;

  /// The shard of this region with the given index kind and layout (as build_shard).
  /// @throw InputError if a layout value is out of range.
  BuiltShard build(ShardKind kind, const ShardLayout& layout = {}) const;

  /// The largest distance between an input vertex and its stored vertex.
  double max_rounding_distance() const;
  /// The triangles as stored (absolute coordinates), in the region's order.
  std::span<const geometry::Triangle> stored_triangles() const;

 private:
  struct Tables;
  std::unique_ptr<const Tables> tables_;
};

/// Builds the payload of a shard holding `region`'s triangles, in the order the index needs
/// (an R-tree reorders them; Shard::triangle_id maps back).
/// @throw InputError if the region is empty, the spans differ in size, a coordinate is not
///   finite, there are 2^32 triangles or more, a layout value is out of range, or float32 is
///   asked for coordinates beyond float's range.
BuiltShard build_shard(const ShardTriangles& region, ShardKind kind, StoredPrecision precision,
                       const ShardLayout& layout = {});

/// The cheaper kind for `region` under `model` when queried by boxes of side query_extent
/// (see estimate_shard_costs in ShardCostModel.h, which also gives the layout to build with).
/// @throw InputError as build_shard, or if query_extent is negative or not finite.
ShardKind choose_shard_kind(const ShardTriangles& region, double query_extent,
                            const ShardCostModel& model);

}  // namespace tetrapage
