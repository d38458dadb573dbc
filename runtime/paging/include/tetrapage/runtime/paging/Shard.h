#pragma once
/// @file Shard.h
/// One region's triangles and their spatial index (a uniform grid or an R-tree), decoded from a
/// shard payload (docs/SHARD-FORMAT.md) and immutable afterwards: any number of threads may
/// query one shard at once.
///
/// Stored coordinates: vertex v is stored relative to the shard origin o as float or double r;
/// the stored vertex is, by definition, o + double(r) computed in double. Every answer here is
/// exact on those stored vertices.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory_resource>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "tetrapage/runtime/geometry/Box.h"
#include "tetrapage/runtime/geometry/Shapes.h"
#include "tetrapage/runtime/geometry/TriangleBox.h"
#include "tetrapage/runtime/paging/ShardKind.h"

namespace tetrapage {

/// Constants of the payload layout, shared by the builder and the decoder.
namespace shard_format {
inline constexpr std::array<std::byte, 4> kMagic{std::byte{'T'}, std::byte{'P'}, std::byte{'S'},
                                                 std::byte{'H'}};
inline constexpr std::uint16_t kVersion = 1;
inline constexpr std::size_t kHeaderBytes = 192;
/// The sections, in payload order; the header holds the byte offset of each and of the end.
enum Section : std::size_t {
  vertices,
  triangles,
  ids,
  part_palette,
  part_indices,
  structure,
  references,
  section_count
};
/// R-tree limits the decoder enforces (so that a query's stack is bounded).
inline constexpr std::uint32_t kMaxFanout = 16;
inline constexpr std::uint32_t kMaxDepth = 48;
/// Bit 31 of an R-tree node's count marks a leaf.
inline constexpr std::uint32_t kLeafFlag = 0x8000'0000u;
/// Bytes of one R-tree node record: a box (6 stored coordinates), first, count.
constexpr std::size_t node_record_bytes(StoredPrecision precision) {
  return (precision == StoredPrecision::float32 ? 4 : 8) * 6 + 8;
}
/// Boundary i (0..cells) of a grid axis: lo + i * cell_size rounded as written, the one
/// formula the builder and the queries share, monotone in i.
inline double grid_boundary(double lo, double cell_size, std::uint32_t i) {
  return lo + double(i) * cell_size;
}
/// The cells [first, last] of a grid axis (cells >= 1) whose closed extent meets [low, high];
/// false when none does. Exact with respect to grid_boundary.
bool grid_cell_range(double lo, double cell_size, std::uint32_t cells, double low, double high,
                     std::uint32_t& first, std::uint32_t& last);
}  // namespace shard_format

/// What one query did, for counters and the cost model.
struct ShardQueryCounters {
  std::uint64_t visited = 0;     ///< grid cells or R-tree nodes visited
  std::uint64_t references = 0;  ///< triangle references examined (with a grid's repeats)
  std::uint64_t candidates = 0;  ///< triangles passed to visit
};

/// What Shard::decode checks beyond the payload's structure.
enum class DecodeChecks {
  /// Also that each R-tree box encloses its triangles and its children, which the answers
  /// rely on: for `tetrapage validate`, tests and payloads of unknown origin.
  full,
  /// What memory safety and termination rely on only (every count, offset, index, the
  /// R-tree's shape, finite coordinates): for page-ins of an index whose writer guarantees
  /// the boxes and whose checksums guard them on disk. The box checks were 40 % of a decode.
  structure,
};

class Shard {
 public:
  /// Decodes and validates a payload: every count, offset and index is checked, so a
  /// corrupted payload throws instead of crashing or looping, and with DecodeChecks::full
  /// every box too.
  /// @param context names the payload in error messages (e.g. "model.tpi shard 17").
  /// @param memory holds the decoded arrays (the runtime's ShardArena); it must outlive the
  ///        shard. Null: the default resource.
  /// @throw FormatError naming the field at fault and its value.
  static Shard decode(std::span<const std::byte> payload, std::string_view context = "shard",
                      DecodeChecks checks = DecodeChecks::full,
                      std::pmr::memory_resource* memory = nullptr);

  ShardKind kind() const { return kind_; }
  StoredPrecision precision() const { return precision_; }
  std::uint32_t triangle_count() const { return triangle_count_; }
  std::uint32_t vertex_count() const { return vertex_count_; }
  /// Bytes held by this object (its arrays, as their memory resource's blocks, and itself).
  std::size_t memory_bytes() const;
  const geometry::Point& origin() const { return origin_; }

  /// The stored triangle `local` (< triangle_count(), unchecked) in double.
  geometry::Triangle triangle(std::uint32_t local) const {
    return precision_ == StoredPrecision::float32 ? stored_triangle<float>(local)
                                                  : stored_triangle<double>(local);
  }
  /// The model-wide triangle id of `local` (< triangle_count(), unchecked).
  std::uint64_t triangle_id(std::uint32_t local) const {
    return id_base_ + (id_offsets32_.empty() ? id_offsets64_[local] : id_offsets32_[local]);
  }
  /// The connected component of `local` (< triangle_count(), unchecked): an id of the index's
  /// components table (CollisionIndex::component_part names its part).
  std::uint32_t component_id(std::uint32_t local) const;
  /// The box of all stored triangles.
  const geometry::Box& bounds() const { return bounds_; }

  /// Calls visit(local) exactly once for each stored triangle that meets the closed box (the
  /// kernel's exact triangle_intersects_box), in no particular order. Every such triangle
  /// also has a stored box overlapping `box`; a triangle whose box overlaps `box` but that
  /// does not itself meet `box` is not visited. An empty box (or one with a NaN) visits
  /// nothing. No state is shared between concurrent queries.
  /// @return the grid cells or R-tree nodes visited.
  /// @throw whatever visit throws.
  template <class Visit>
  std::size_t for_each_candidate(const geometry::Box& box, Visit&& visit) const {
    ShardQueryCounters counters;
    query<QueryMode::decide>(box, always, visit, counters, false);
    return counters.visited;
  }
  /// The same, adding what the query did to `counters`.
  template <class Visit>
  std::size_t for_each_candidate(const geometry::Box& box, Visit&& visit,
                                 ShardQueryCounters& counters) const {
    const std::uint64_t before = counters.visited;
    query<QueryMode::decide>(box, always, visit, counters, false);
    return counters.visited - before;
  }

  /// Calls visit(local, triangle) once for each stored triangle whose box overlaps `box` (no
  /// exact triangle/box test: for callers that decide each triangle exactly anyway), pruning
  /// what `accept(node_box, triangles)` rejects as well (a conservative filter of the
  /// caller's, e.g. an oriented box): R-tree leaves and grid cells (whose closed box holds
  /// every point of a triangle that a query can reach through that cell) with the number they
  /// hold. The shard's bounds and inner R-tree nodes are pruned by `box` alone: an object's own
  /// box rejected about one in twenty of the inner nodes on the benchmark flights, which did
  /// not pay for the tests (a caller that pages shards in asks its filter of a shard before),
  /// unless the object's world box is much looser than its own (see the next).
  /// A triangle is visited when some leaf or cell holding it is accepted. Each visit of an
  /// R-tree leaf's triangles follows its own accept call, before any other accept call (a
  /// caller may keep what it learnt of the leaf for its triangles). No state is shared
  /// between concurrent queries.
  template <class Accept, class Visit>
  void for_each_box_candidate(const geometry::Box& box, Accept&& accept, Visit&& visit) const {
    ShardQueryCounters counters;
    query<QueryMode::boxes>(box, accept, visit, counters, false);
  }
  /// The same, with `accept` also asked of the inner R-tree nodes below the root (with 0
  /// triangles): for a filter much tighter than `box`, where the subtrees it prunes pay for
  /// the tests.
  template <class Accept, class Visit>
  void for_each_box_candidate_pruning_inner_nodes(const geometry::Box& box, Accept&& accept, Visit&& visit) const {
    ShardQueryCounters counters;
    query<QueryMode::boxes>(box, accept, visit, counters, true);
  }

  /// Counts the cells or nodes and the references a query of `box` examines, without deciding
  /// any triangle (what the cost model measures: the exact tests are the same for every layout).
  void count_query(const geometry::Box& box, ShardQueryCounters& counters) const {
    auto ignore = [](std::uint32_t) {};
    query<QueryMode::count>(box, always, ignore, counters, false);
  }
  // Read-only views of the decoded structure, for inspection, tests and the builder's checks.
  std::array<std::uint32_t, 3> grid_cells() const { return grid_cells_; }
  const geometry::Point& grid_lo() const { return grid_lo_; }
  const geometry::Point& grid_cell_size() const { return grid_cell_size_; }
  std::size_t grid_reference_count() const {
    return references16_.empty() ? references32_.size() : references16_.size();
  }
  std::size_t rtree_node_count() const { return nodes_.size(); }
  std::uint32_t part_count() const { return std::uint32_t(part_palette_.size()); }

  /// Lower boundary of grid cell i along axis (the same rounding at build and query time).
  double grid_boundary(int axis, std::uint32_t i) const {
    return shard_format::grid_boundary(grid_lo_[axis], grid_cell_size_[axis], i);
  }

 private:
  class Decoder;  // decode's steps, in Shard.cpp
  /// Empty, its arrays in `memory`.
  explicit Shard(std::pmr::memory_resource* memory);

  /// An R-tree node; its box is in node_boxes_.
  struct Node {
    std::uint32_t first = 0;  ///< first child node, or first triangle of a leaf
    std::uint32_t count = 0;  ///< children, or triangles (with kLeafFlag for a leaf)
  };
  /// Floats past the last node in each of node_boxes_' six arrays: children are tested four
  /// at a time, and the last group may run past the end.
  static constexpr std::size_t kNodeBoxPadding = 4;
  /// A box of node i's triangles in stored (absolute) coordinates: the origin plus its
  /// outward-rounded floats, where these were clamped the shard's bounds.
  geometry::Box node_box(std::uint32_t i) const {
    const float* b = node_boxes_.data() + i;
    geometry::Box box{
        {origin_[0] + double(b[0]), origin_[1] + double(b[node_stride_]),
         origin_[2] + double(b[2 * node_stride_])},
        {origin_[0] + double(b[3 * node_stride_]), origin_[1] + double(b[4 * node_stride_]),
         origin_[2] + double(b[5 * node_stride_])}};
    if (clamped_node_boxes_) {
      constexpr float kMost = std::numeric_limits<float>::max();
      for (int k = 0; k < 3; ++k) {
        if (std::fabs(b[k * node_stride_]) == kMost) box.lo[k] = bounds_.lo[k];
        if (std::fabs(b[(3 + k) * node_stride_]) == kMost) box.hi[k] = bounds_.hi[k];
      }
    }
    return box;
  }
  /// Bit c set for each child first + c (c < count <= kMaxFanout) whose float box overlaps
  /// the query's (lo, hi: relative to the origin, rounded outward).
  std::uint32_t children_overlapping(std::uint32_t first, std::uint32_t count, const float lo[3],
                                     const float hi[3]) const;

  /// Per-thread marks that report a grid triangle once per query (defined in Shard.cpp).
  class Marks {
   public:
    explicit Marks(std::uint32_t triangle_count);
    ~Marks();
    Marks(const Marks&) = delete;
    Marks& operator=(const Marks&) = delete;
    /// True the first time t is seen during this query.
    bool first_visit(std::uint32_t t) {
      if (stamps_[t] == epoch_) return false;
      stamps_[t] = epoch_;
      return true;
    }

   private:
    std::uint32_t* stamps_ = nullptr;
    std::uint32_t epoch_ = 0;
    std::vector<std::uint32_t> own_;  ///< used when a query runs inside another's visit
    bool borrowed_ = false;
  };

  template <class Real>
  geometry::Point stored_vertex(std::uint32_t v) const {
    const Real* r;
    if constexpr (sizeof(Real) == 4)
      r = vertices32_.data() + 3 * std::size_t(v);
    else
      r = vertices64_.data() + 3 * std::size_t(v);
    return {origin_[0] + double(r[0]), origin_[1] + double(r[1]), origin_[2] + double(r[2])};
  }
  std::uint32_t corner(std::uint32_t local, int k) const {
    const std::size_t i = 3 * std::size_t(local) + std::size_t(k);
    return indices16_.empty() ? indices32_[i] : indices16_[i];
  }
  template <class Real>
  geometry::Triangle stored_triangle(std::uint32_t local) const {
    return {stored_vertex<Real>(corner(local, 0)), stored_vertex<Real>(corner(local, 1)),
            stored_vertex<Real>(corner(local, 2))};
  }
  bool meets(std::uint32_t local, const geometry::Box& box) const {
    const geometry::Triangle t = triangle(local);
    return geometry::boxes_overlap(geometry::box_of(t), box) &&
           geometry::triangle_intersects_box(t, box);
  }

  // What a traversal does with each triangle reference it reaches.
  enum class QueryMode {
    decide,  ///< visit(local) for each triangle that meets the box (exact), once
    count,   ///< count cells or nodes and references only (the cost model's measure)
    boxes,   ///< visit(local, triangle) for each triangle whose box overlaps the box, once
  };
  static constexpr auto always = [](const geometry::Box&, std::uint32_t) { return true; };

  // The one traversal of both kinds; `accept` may prune R-tree nodes (and the whole shard).
  template <QueryMode kMode, class Accept, class Visit>
  void query(const geometry::Box& box, const Accept& accept, Visit& visit, ShardQueryCounters& counters,
             bool accept_inner_nodes) const {
    for (int k = 0; k < 3; ++k)
      if (!(box.lo[k] <= box.hi[k])) return;  // empty, or NaN
    if (!geometry::boxes_overlap(box, bounds_)) return;
    // A triangle meets the box iff it meets the box clipped to the shard's bounds, which is
    // finite even when the query is not.
    geometry::Box clipped;
    for (int k = 0; k < 3; ++k) {
      clipped.lo[k] = std::max(box.lo[k], bounds_.lo[k]);
      clipped.hi[k] = std::min(box.hi[k], bounds_.hi[k]);
    }
    auto reach = [&](std::uint32_t t) {
      if constexpr (kMode == QueryMode::decide) {
        if (!meets(t, clipped)) return;
        ++counters.candidates;
        visit(t);
      } else if constexpr (kMode == QueryMode::boxes) {
        const geometry::Triangle triangle = this->triangle(t);
        if (geometry::boxes_overlap(geometry::box_of(triangle), clipped)) visit(t, triangle);
      }
    };
    if (kind_ == ShardKind::grid)
      query_grid<kMode>(clipped, accept, reach, counters);
    else
      query_rtree<kMode>(clipped, accept, reach, counters, accept_inner_nodes);
  }

  template <QueryMode kMode, class Accept, class Reach>
  void query_grid(const geometry::Box& box, const Accept& accept, Reach& reach,
                  ShardQueryCounters& counters) const {
    std::array<std::uint32_t, 3> first{}, last{};
    for (int k = 0; k < 3; ++k)
      if (!shard_format::grid_cell_range(grid_lo_[k], grid_cell_size_[k], grid_cells_[k], box.lo[k],
                                         box.hi[k], first[k], last[k]))
        return;
    // Marks report a triangle referenced by several cells once (not needed to count).
    std::optional<Marks> marks;
    if constexpr (kMode != QueryMode::count) marks.emplace(triangle_count_);
    const std::uint32_t nx = grid_cells_[0], ny = grid_cells_[1];
    for (std::uint32_t z = first[2]; z <= last[2]; ++z)
      for (std::uint32_t y = first[1]; y <= last[1]; ++y)
        for (std::uint32_t x = first[0]; x <= last[0]; ++x) {
          const std::size_t cell = (std::size_t(z) * ny + y) * nx + x;
          ++counters.visited;
          const std::uint32_t begin = cell_offsets_[cell], end = cell_offsets_[cell + 1];
          counters.references += end - begin;
          if constexpr (kMode == QueryMode::count) continue;
          if constexpr (kMode == QueryMode::boxes) {
            if (begin == end) continue;
            const geometry::Box cell_box{
                {grid_boundary(0, x), grid_boundary(1, y), grid_boundary(2, z)},
                {grid_boundary(0, x + 1), grid_boundary(1, y + 1), grid_boundary(2, z + 1)}};
            if (!accept(cell_box, end - begin)) continue;
          }
          for (std::uint32_t r = begin; r < end; ++r) {
            const std::uint32_t t = references16_.empty() ? references32_[r] : references16_[r];
            if (marks->first_visit(t)) reach(t);
          }
        }
  }

  template <QueryMode kMode, class Accept, class Reach>
  void query_rtree(const geometry::Box& box, const Accept& accept, Reach& reach, ShardQueryCounters& counters,
                   bool accept_inner_nodes) const {
    // Depth is at most kMaxDepth and each level leaves at most kMaxFanout - 1 siblings
    // pending, which the decoder checked.
    float lo[3], hi[3];
    relative_query(box, lo, hi);
    std::array<std::uint32_t, shard_format::kMaxDepth * shard_format::kMaxFanout + 1> stack;
    std::size_t size = 0;
    // A node is counted as visited when its box is tested, as each child is with its siblings.
    ++counters.visited;
    if (children_overlapping(0, 1, lo, hi) == 0) return;
    stack[size++] = 0;
    while (size > 0) {
      const std::uint32_t at = stack[--size];
      const Node& node = nodes_[at];
      const bool leaf = (node.count & shard_format::kLeafFlag) != 0;
      const std::uint32_t count = leaf ? node.count & ~shard_format::kLeafFlag : 0;
      if constexpr (kMode == QueryMode::boxes) {
        if ((leaf || (accept_inner_nodes && at != 0)) && !accept(node_box(at), count)) continue;
      }
      if (leaf) {
        counters.references += count;
        if constexpr (kMode == QueryMode::count) continue;
        for (std::uint32_t t = node.first; t < node.first + count; ++t) reach(t);
      } else {
        counters.visited += node.count;
        // Pushed last to first, so that the first child is visited first.
        for (std::uint32_t mask = children_overlapping(node.first, node.count, lo, hi);
             mask != 0;) {
          const int c = 31 - __builtin_clz(mask);
          mask &= ~(1u << c);
          stack[size++] = node.first + std::uint32_t(c);
        }
      }
    }
  }
  /// The query box relative to the origin in float, grown beyond the roundings (it only
  /// prunes): the subtraction's and the node boxes' (the origin plus their stored values),
  /// relative to the coordinates (2^-40 of them), and the float's (2^-24 of the value, or
  /// FLT_MIN near zero). Not geometry::float_below / float_above: their exact rounding, six
  /// branches a shard query, cost the 1M demo's 500-triangle flight 9 % in memory.
  void relative_query(const geometry::Box& box, float lo[3], float hi[3]) const {
    for (int k = 0; k < 3; ++k) {
      const double l = box.lo[k] - origin_[k], h = box.hi[k] - origin_[k];
      const double margin = (std::fabs(origin_[k]) + std::fabs(box.lo[k]) + std::fabs(box.hi[k])) * 0x1p-40 +
                            std::numeric_limits<float>::min();
      // Clamped to the finite floats as the nodes' are (beyond float range only for
      // coordinates far beyond any model's).
      constexpr double kMost = std::numeric_limits<float>::max();
      lo[k] = float(std::clamp(l - std::fabs(l) * 0x1p-23 - margin, -kMost, kMost));
      hi[k] = float(std::clamp(h + std::fabs(h) * 0x1p-23 + margin, -kMost, kMost));
    }
  }

  ShardKind kind_ = ShardKind::grid;
  StoredPrecision precision_ = StoredPrecision::float32;
  std::uint32_t triangle_count_ = 0;
  std::uint32_t vertex_count_ = 0;
  geometry::Point origin_{};
  geometry::Box bounds_;

  std::pmr::vector<float> vertices32_;  ///< relative xyz, when stored as float
  std::pmr::vector<double> vertices64_;
  std::pmr::vector<std::uint16_t> indices16_;  ///< three corners per triangle
  std::pmr::vector<std::uint32_t> indices32_;
  std::uint64_t id_base_ = 0;
  std::pmr::vector<std::uint32_t> id_offsets32_;
  std::pmr::vector<std::uint64_t> id_offsets64_;
  std::pmr::vector<std::uint32_t> part_palette_;
  std::pmr::vector<std::uint8_t> part_indices_;  ///< part_index_bytes_ per triangle, little-endian
  std::uint8_t part_index_bytes_ = 0;

  std::array<std::uint32_t, 3> grid_cells_{};
  geometry::Point grid_lo_{};
  geometry::Point grid_cell_size_{};
  std::pmr::vector<std::uint32_t> cell_offsets_;
  std::pmr::vector<std::uint16_t> references16_;
  std::pmr::vector<std::uint32_t> references32_;

  std::pmr::vector<Node> nodes_;
  /// The nodes' boxes relative to the origin, rounded outward to float, as six arrays of
  /// node_stride_ floats (lo x, y, z, hi x, y, z): a node's children are tested together.
  std::pmr::vector<float> node_boxes_;
  std::size_t node_stride_ = 0;
  /// Some node coordinate lay beyond float range from the origin (node_box then widens).
  bool clamped_node_boxes_ = false;
};

}  // namespace tetrapage
