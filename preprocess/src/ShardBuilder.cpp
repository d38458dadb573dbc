#include "tetrapage/preprocess/ShardBuilder.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <numeric>
#include <optional>
#include <string>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/runtime/geometry/Box.h"
#include "tetrapage/runtime/geometry/TriangleBox.h"
#include "tetrapage/runtime/paging/Shard.h"

namespace tetrapage {
namespace {

using geometry::Box;
using geometry::Point;
using geometry::Triangle;

/// 2^ceil(log2(x)) for x > 0.
double power_of_two_above(double x) {
  int e = std::ilogb(x);
  if (std::ldexp(1.0, e) < x) ++e;
  return std::ldexp(1.0, e);
}

/// Where the stored vertices are relative to, and the fixed-point step of float coordinates.
struct Frame {
  Point origin{};
  double step = 0;  ///< float32: relative coordinates are multiples of step; float64: unused
};

// float32: relative coordinates are integers q (|q| < 2^24, exact in float) times a power of
// two `step`, and the origin is a multiple of step, so origin + q * step is an integer times
// step below 2^53 * step: exact in double. The step is the finer of the float's resolution
// over the region and the double's resolution at the region's magnitude.
Frame float_frame(const Box& box) {
  double half_extent = 0, magnitude = 0;
  for (int k = 0; k < 3; ++k) {
    half_extent = std::max(half_extent, 0.5 * (box.hi[k] - box.lo[k]));
    magnitude = std::max({magnitude, std::fabs(box.lo[k]), std::fabs(box.hi[k])});
  }
  const double grid = half_extent > 0 ? power_of_two_above(half_extent) : 0;
  double step = std::max({std::ldexp(grid, -23),
                          magnitude > 0 ? std::ldexp(power_of_two_above(magnitude), -51) : 0.0,
                          std::ldexp(1.0, -120)});
  if (step > std::ldexp(1.0, 100))
    throw InputError("shard region of half extent " + std::to_string(half_extent) +
                     " at magnitude " + std::to_string(magnitude) +
                     " is beyond float32's range; store it as float64");
  const double spacing = std::max(grid, step);  // a power of two, a multiple of step
  Frame frame;
  frame.step = step;
  const Point centre = box.center();
  for (int k = 0; k < 3; ++k) frame.origin[k] = std::nearbyint(centre[k] / spacing) * spacing;
  return frame;
}

// float64: an origin on a coarse power-of-two grid near the centre, kept only if every vertex
// survives the trip origin + (v - origin) unchanged; else the origin 0, which always does.
Frame double_frame(const Box& box, std::span<const Triangle> triangles) {
  double half_extent = 0;
  for (int k = 0; k < 3; ++k) half_extent = std::max(half_extent, 0.5 * (box.hi[k] - box.lo[k]));
  Frame frame;
  if (half_extent == 0) return frame;
  const double spacing = power_of_two_above(half_extent);
  const Point centre = box.center();
  for (int k = 0; k < 3; ++k) frame.origin[k] = std::nearbyint(centre[k] / spacing) * spacing;
  for (const Triangle& t : triangles)
    for (const Point& v : t)
      for (int k = 0; k < 3; ++k)
        if (frame.origin[k] + (v[k] - frame.origin[k]) != v[k]) return Frame{};
  return frame;
}

// exact: float32 at an origin where every vertex decodes, as o + double(float(v - o)) in
// binary64 (the format's definition of a stored vertex), to exactly v; the float frame's origin
// is tried first, then 0 (which suits input that was float already). Nothing when neither does.
std::optional<Frame> lossless_float_frame(const Box& box, std::span<const Triangle> triangles) {
  const auto decodes = [&](const Point& o) {
    for (const Triangle& t : triangles)
      for (const Point& v : t)
        for (int k = 0; k < 3; ++k) {
          const float r = float(v[k] - o[k]);
          if (!std::isfinite(r) || o[k] + double(r) != v[k]) return false;
        }
    return true;
  };
  std::optional<Frame> frame;
  try {
    frame = float_frame(box);
  } catch (const InputError&) {
    frame.reset();  // beyond float's range around any origin near the region
  }
  if (frame && decodes(frame->origin)) return frame;
  if (decodes(Point{})) return Frame{};
  return std::nullopt;
}

struct VertexKey {
  std::array<std::uint64_t, 3> bits;
  bool operator==(const VertexKey&) const = default;
};
struct VertexKeyHash {
  std::size_t operator()(const VertexKey& key) const {
    std::uint64_t h = 0x9e3779b97f4a7c15ull;
    for (const std::uint64_t b : key.bits) h = (h ^ b) * 0xbf58476d1ce4e5b9ull + (h >> 29);
    return std::size_t(h ^ (h >> 31));
  }
};

/// The triangles as stored: relative coordinates (exactly representable in the stored type),
/// deduplicated vertices, and the absolute stored triangles.
struct StoredGeometry {
  StoredPrecision precision = StoredPrecision::float64;  ///< float32 or float64
  bool rounds = false;  ///< float32 on a fixed-point step (--precision float), not lossless
  Frame frame;
  std::vector<Point> relative;                        ///< per distinct vertex, first-seen order
  std::vector<std::array<std::uint32_t, 3>> corners;  ///< per triangle
  std::vector<Triangle> triangles;                    ///< absolute stored coordinates
  double max_rounding_distance = 0;
};

StoredGeometry store(std::span<const Triangle> input, StoredPrecision precision) {
  Box box;
  for (const Triangle& t : input)
    for (const Point& v : t) box.extend(v);
  StoredGeometry g;
  g.precision = precision;
  if (precision == StoredPrecision::exact) {
    const std::optional<Frame> lossless = lossless_float_frame(box, input);
    g.precision = lossless ? StoredPrecision::float32 : StoredPrecision::float64;
    g.frame = lossless ? *lossless : double_frame(box, input);
  } else {
    g.rounds = precision == StoredPrecision::float32;
    g.frame = g.rounds ? float_frame(box) : double_frame(box, input);
  }
  const Point& o = g.frame.origin;
  // Open addressing over a power-of-two table at most a third full: no allocation per vertex
  // (a node-based map's allocations were a tenth of the shard stage).
  std::size_t slots = 16;
  while (slots < 3 * 3 * input.size()) slots *= 2;
  constexpr std::uint32_t kEmpty = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> table(slots, kEmpty);  // vertex number, or kEmpty
  g.relative.reserve(input.size());
  g.corners.resize(input.size());
  g.triangles.resize(input.size());
  double max_squared = 0;
  for (std::size_t t = 0; t < input.size(); ++t)
    for (int c = 0; c < 3; ++c) {
      const Point& v = input[t][c];
      Point r;
      for (int k = 0; k < 3; ++k) {
        r[k] = v[k] - o[k];
        if (g.rounds)
          r[k] = double(float(std::nearbyint(r[k] / g.frame.step) * g.frame.step));
        else if (g.precision == StoredPrecision::float32)
          r[k] = double(float(r[k]));  // exact: the frame was checked to be lossless
        r[k] += 0.0;                   // one key for 0 and -0
      }
      Point stored;
      double squared = 0;
      for (int k = 0; k < 3; ++k) {
        stored[k] = o[k] + r[k];
        squared += (stored[k] - v[k]) * (stored[k] - v[k]);
      }
      max_squared = std::max(max_squared, squared);
      g.triangles[t][c] = stored;
      const VertexKey key{{std::bit_cast<std::uint64_t>(r[0]), std::bit_cast<std::uint64_t>(r[1]),
                           std::bit_cast<std::uint64_t>(r[2])}};
      std::size_t slot = VertexKeyHash{}(key) & (slots - 1);
      for (;; slot = (slot + 1) & (slots - 1)) {
        const std::uint32_t number = table[slot];
        if (number == kEmpty) {
          table[slot] = std::uint32_t(g.relative.size());
          g.relative.push_back(r);
          break;
        }
        const Point& seen = g.relative[number];
        if (std::bit_cast<std::uint64_t>(seen[0]) == key.bits[0] &&
            std::bit_cast<std::uint64_t>(seen[1]) == key.bits[1] &&
            std::bit_cast<std::uint64_t>(seen[2]) == key.bits[2])
          break;
      }
      g.corners[t][c] = table[slot];
    }
  g.max_rounding_distance = std::sqrt(max_squared);  // the same as the largest root
  return g;
}

// ---------------------------------------------------------------------------------------
// Grid

std::array<std::uint32_t, 3> grid_cells_for(const Box& bounds, std::size_t triangles,
                                            double cells_per_triangle) {
  const double target = std::max(1.0, cells_per_triangle * double(triangles));
  const Point size = bounds.size();
  std::array<bool, 3> active{};
  for (int k = 0; k < 3; ++k) active[k] = size[k] > 0;
  double side = 0;
  for (bool changed = true; changed;) {  // drop the axes thinner than a cell
    changed = false;
    int dimensions = 0;
    double measure = 1;
    for (int k = 0; k < 3; ++k)
      if (active[k]) {
        ++dimensions;
        measure *= size[k];
      }
    if (dimensions == 0) return {1, 1, 1};
    side = std::pow(measure / target, 1.0 / dimensions);
    for (int k = 0; k < 3; ++k)
      if (active[k] && size[k] < side) {
        active[k] = false;
        changed = true;
      }
  }
  std::array<std::uint32_t, 3> cells{1, 1, 1};
  for (int k = 0; k < 3; ++k)
    if (active[k]) cells[k] = std::uint32_t(std::clamp(std::round(size[k] / side), 1.0, 65536.0));
  return cells;
}

struct GridShape {
  std::array<std::uint32_t, 3> cells{};
  Point lo{}, cell_size{};
};

GridShape grid_shape(const Box& bounds, std::array<std::uint32_t, 3> cells) {
  GridShape shape;
  shape.cells = cells;
  shape.lo = bounds.lo;
  for (int k = 0; k < 3; ++k) {
    const double extent = bounds.hi[k] - bounds.lo[k];
    double h =
        extent > 0 ? extent / cells[k] : std::max(std::fabs(bounds.lo[k]) * 0x1p-40, 0x1p-900);
    // Grow the cell until the last boundary, rounded as queries round it, holds every vertex.
    for (int i = 0; shard_format::grid_boundary(shape.lo[k], h, cells[k]) < bounds.hi[k]; ++i) {
      if (i > 200) throw std::logic_error("grid extent does not converge");
      h = h * (1 + 0x1p-30) + std::numeric_limits<double>::denorm_min();
    }
    shape.cell_size[k] = h;
  }
  return shape;
}

struct GridIndex {
  GridShape shape;
  std::vector<std::uint32_t> cell_offsets;
  std::vector<std::uint32_t> references;
};

GridIndex build_grid(const std::vector<Triangle>& triangles, const Box& bounds,
                     std::array<std::uint32_t, 3> cells) {
  GridIndex grid;
  grid.shape = grid_shape(bounds, cells);
  const GridShape& s = grid.shape;
  const std::uint64_t cell_count = std::uint64_t(cells[0]) * cells[1] * cells[2];
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;  // (cell, triangle)
  pairs.reserve(triangles.size() * 2);
  auto boundary = [&](int k, std::uint32_t i) {
    return shard_format::grid_boundary(s.lo[k], s.cell_size[k], i);
  };
  for (std::uint32_t t = 0; t < triangles.size(); ++t) {
    const Box box = geometry::box_of(triangles[t]);
    std::array<std::uint32_t, 3> first{}, last{};
    for (int k = 0; k < 3; ++k)
      if (!shard_format::grid_cell_range(s.lo[k], s.cell_size[k], cells[k], box.lo[k], box.hi[k],
                                         first[k], last[k]))
        throw std::logic_error("a stored triangle lies outside its grid");
    const bool single = first == last;
    for (std::uint32_t z = first[2]; z <= last[2]; ++z)
      for (std::uint32_t y = first[1]; y <= last[1]; ++y)
        for (std::uint32_t x = first[0]; x <= last[0]; ++x) {
          Box cell;
          cell.lo = {boundary(0, x), boundary(1, y), boundary(2, z)};
          cell.hi = {boundary(0, x + 1), boundary(1, y + 1), boundary(2, z + 1)};
          if (single || geometry::triangle_intersects_box(triangles[t], cell))
            pairs.emplace_back(std::uint32_t((std::uint64_t(z) * cells[1] + y) * cells[0] + x), t);
        }
  }
  if (pairs.size() >= std::numeric_limits<std::uint32_t>::max())
    throw InputError("shard grid of " + std::to_string(cell_count) + " cells would hold " +
                     std::to_string(pairs.size()) + " references, beyond 2^32");
  grid.cell_offsets.assign(cell_count + 1, 0);
  for (const auto& [cell, t] : pairs) ++grid.cell_offsets[cell + 1];
  std::partial_sum(grid.cell_offsets.begin(), grid.cell_offsets.end(), grid.cell_offsets.begin());
  grid.references.resize(pairs.size());
  std::vector<std::uint32_t> fill(grid.cell_offsets.begin(), grid.cell_offsets.end() - 1);
  for (const auto& [cell, t] : pairs) grid.references[fill[cell]++] = t;
  return grid;
}

// ---------------------------------------------------------------------------------------
// R-tree: bulk loaded top-down; a node's triangles are cut at medians along the longest side
// of their centres into groups of full subtrees, so every leaf but the last of a parent is
// full and triangles end up in tree order.

/// Rearranges distinct keys so that keys[k] is the k-th smallest, with the smaller ones before
/// it and the larger ones after: std::nth_element's contract. A quickselect whose partition
/// has no branch on the data (Lomuto's, with the comparison's result as the step): the cuts
/// are on nearly random keys, where std::nth_element's branches mispredicted half the time.
void select_nth(std::span<std::uint64_t> keys, std::size_t k) {
  std::size_t lo = 0, hi = keys.size();
  while (hi - lo > 16) {
    // Median of three as the pivot, moved to lo.
    const std::size_t mid = lo + (hi - lo) / 2;
    std::uint64_t a = keys[lo], b = keys[mid], c = keys[hi - 1];
    if (a > b) std::swap(a, b);
    if (b > c) std::swap(b, c);
    if (a > b) std::swap(a, b);
    const std::size_t p = b == keys[lo] ? lo : (b == keys[mid] ? mid : hi - 1);
    std::swap(keys[lo], keys[p]);
    const std::uint64_t pivot = keys[lo];
    std::size_t smaller = lo + 1;  // [lo + 1, smaller) < pivot <= [smaller, j)
    for (std::size_t j = lo + 1; j < hi; ++j) {
      const std::uint64_t x = keys[j];
      keys[j] = keys[smaller];
      keys[smaller] = x;
      smaller += x < pivot;
    }
    std::swap(keys[lo], keys[smaller - 1]);  // the pivot at its rank
    const std::size_t rank = smaller - 1;
    if (rank == k) return;
    if (k < rank)
      hi = rank;
    else
      lo = rank + 1;
  }
  std::sort(keys.begin() + std::ptrdiff_t(lo), keys.begin() + std::ptrdiff_t(hi));
}

struct RtreeNode {
  Box box;  ///< relative coordinates (stored values)
  std::uint32_t first = 0;
  std::uint32_t count = 0;  ///< with kLeafFlag for a leaf
};

class RtreeBuilder {
 public:
  RtreeBuilder(const std::vector<Box>& relative_boxes, std::uint32_t leaf_size,
               std::uint32_t fanout)
      : boxes_(relative_boxes), leaf_size_(leaf_size), fanout_(fanout) {
    centres_.reserve(boxes_.size());
    order_.resize(boxes_.size());
    for (std::uint32_t t = 0; t < boxes_.size(); ++t) {
      centres_.push_back(boxes_[t].center());
      order_[t] = t;
    }
  }

  void build() {
    const std::uint64_t n = order_.size();
    std::uint32_t height = 0;
    for (std::uint64_t capacity = leaf_size_; capacity < n; capacity *= fanout_) ++height;
    nodes_.resize(1);
    build_node(0, 0, std::uint32_t(n), height);
  }

  /// The triangles in tree order (each leaf's in increasing number).
  const std::vector<std::uint32_t>& order() const { return order_; }
  std::vector<RtreeNode>& nodes() { return nodes_; }

 private:
  void build_node(std::uint32_t index, std::uint32_t begin, std::uint32_t end,
                  std::uint32_t height) {
    Box box;
    if (height == 0) {
      std::sort(order_.begin() + begin, order_.begin() + end);
      for (std::uint32_t i = begin; i < end; ++i) box.extend(boxes_[order_[i]]);
      nodes_[index] = {box, begin, (end - begin) | shard_format::kLeafFlag};
      return;
    }
    std::uint64_t capacity = leaf_size_;
    for (std::uint32_t h = 1; h < height; ++h) capacity *= fanout_;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> groups;
    const auto count = std::uint32_t((end - begin + capacity - 1) / capacity);
    split(begin, end, count, capacity, groups);
    const auto first = std::uint32_t(nodes_.size());
    nodes_.resize(nodes_.size() + groups.size());
    for (std::size_t g = 0; g < groups.size(); ++g) {
      build_node(first + std::uint32_t(g), groups[g].first, groups[g].second, height - 1);
      box.extend(nodes_[first + g].box);
    }
    nodes_[index] = {box, first, std::uint32_t(groups.size())};
  }

  // A float's bits as an unsigned integer of the same order (negative values reversed).
  static std::uint32_t ordered_bits(float value) {
    const auto bits = std::bit_cast<std::uint32_t>(value);
    return bits & 0x8000'0000u ? ~bits : bits | 0x8000'0000u;
  }

  void split(std::uint32_t begin, std::uint32_t end, std::uint32_t groups, std::uint64_t capacity,
             std::vector<std::pair<std::uint32_t, std::uint32_t>>& out) {
    if (groups == 1) {
      out.emplace_back(begin, end);
      return;
    }
    const std::uint32_t left = groups / 2;
    const auto middle = std::uint32_t(begin + left * capacity);
    Box spread;
    for (std::uint32_t i = begin; i < end; ++i) spread.extend(centres_[order_[i]]);
    const Point size = spread.size();
    const int axis =
        size[0] >= size[1] ? (size[0] >= size[2] ? 0 : 2) : (size[1] >= size[2] ? 1 : 2);
    // The cut needs no more than the centres' order along the axis: the centre in float and
    // the triangle number in one integer, whose selection is a third of the time of
    // (double centre, triangle) records with a comparison function.
    keys_.resize(end - begin);
    for (std::uint32_t i = begin; i < end; ++i) {
      const std::uint32_t t = order_[i];
      keys_[i - begin] = std::uint64_t(ordered_bits(float(centres_[t][axis]))) << 32 | t;
    }
    select_nth(std::span<std::uint64_t>(keys_), middle - begin);
    for (std::uint32_t i = begin; i < end; ++i) order_[i] = std::uint32_t(keys_[i - begin]);
    split(begin, middle, left, capacity, out);
    split(middle, end, groups - left, capacity, out);
  }

  const std::vector<Box>& boxes_;
  std::uint32_t leaf_size_, fanout_;
  std::vector<Point> centres_;        ///< per triangle
  std::vector<std::uint32_t> order_;  ///< the triangles, in tree order once built
  std::vector<std::uint64_t> keys_;   ///< a cut's scratch
  std::vector<RtreeNode> nodes_;
};

// ---------------------------------------------------------------------------------------
// Serialisation

class PayloadWriter {
 public:
  explicit PayloadWriter(std::vector<std::byte>& out) : out_(out) {}
  template <class T>
  void put(std::size_t offset, T value) {
    std::memcpy(out_.data() + offset, &value, sizeof(T));
  }
  template <class T>
  void append(T value) {
    const std::size_t at = out_.size();
    out_.resize(at + sizeof(T));
    put(at, value);
  }
  void align() { out_.resize((out_.size() + 7) & ~std::size_t(7)); }
  std::size_t size() const { return out_.size(); }

 private:
  std::vector<std::byte>& out_;
};

void check_region(const ShardTriangles& region) {
  const std::size_t n = region.triangles.size();
  if (n == 0) throw InputError("shard region has no triangles");
  if (region.ids.size() != n || region.parts.size() != n)
    throw InputError("shard region has " + std::to_string(n) + " triangles but " +
                     std::to_string(region.ids.size()) + " ids and " +
                     std::to_string(region.parts.size()) + " part ids");
  if (n >= std::numeric_limits<std::uint32_t>::max())
    throw InputError("shard region has " + std::to_string(n) + " triangles, beyond 2^32 - 1");
  for (std::size_t t = 0; t < n; ++t)
    if (!geometry::is_finite(region.triangles[t]))
      throw InputError("shard region triangle " + std::to_string(t) + " (id " +
                       std::to_string(region.ids[t]) + ") has a non-finite coordinate");
}

void check_layout(const ShardLayout& layout) {
  if (layout.rtree_fanout < 2 || layout.rtree_fanout > shard_format::kMaxFanout)
    throw InputError("R-tree fanout " + std::to_string(layout.rtree_fanout) + " is not in 2.." +
                     std::to_string(shard_format::kMaxFanout));
  if (layout.rtree_leaf_size > 65536)
    throw InputError("R-tree leaf size " + std::to_string(layout.rtree_leaf_size) +
                     " is above 65536");
  const auto& c = layout.grid_cells;
  const bool chosen = c[0] == 0 && c[1] == 0 && c[2] == 0;
  if (!chosen && (c[0] == 0 || c[1] == 0 || c[2] == 0 ||
                  std::uint64_t(c[0]) * c[1] * c[2] > (std::uint64_t(1) << 26)))
    throw InputError("grid cells " + std::to_string(c[0]) + "x" + std::to_string(c[1]) + "x" +
                     std::to_string(c[2]) + " must all be positive, at most 2^26 in all");
  if (chosen && !(layout.grid_cells_per_triangle > 0 && layout.grid_cells_per_triangle <= 64))
    throw InputError("grid cells per triangle " + std::to_string(layout.grid_cells_per_triangle) +
                     " is not in (0, 64]");
}

}  // namespace

/// What every layout of one region shares: the stored geometry and the per-triangle tables.
struct StoredRegion::Tables {
  ShardTriangles region;
  StoredPrecision precision;
  StoredGeometry g;
  Box bounds;                               ///< of the stored triangles
  std::vector<Box> boxes;                   ///< per triangle, relative (stored) coordinates
  std::vector<std::uint32_t> palette;       ///< the distinct part ids, sorted
  std::vector<std::uint32_t> part_indices;  ///< per triangle, into palette
  std::uint64_t id_base = 0;
  std::uint8_t id_bytes = 4;
};

StoredRegion::StoredRegion(const ShardTriangles& region, StoredPrecision precision) {
  check_region(region);
  auto tables = std::make_unique<Tables>();
  Tables& d = *tables;
  d.region = region;
  d.g = store(region.triangles, precision);
  d.precision = d.g.precision;
  const auto n = std::uint32_t(region.triangles.size());
  for (const Triangle& t : d.g.triangles) d.bounds.extend(geometry::box_of(t));
  d.boxes.resize(n);
  for (std::uint32_t t = 0; t < n; ++t)
    for (const std::uint32_t v : d.g.corners[t]) d.boxes[t].extend(d.g.relative[v]);
  d.palette.assign(region.parts.begin(), region.parts.end());
  std::sort(d.palette.begin(), d.palette.end());
  d.palette.erase(std::unique(d.palette.begin(), d.palette.end()), d.palette.end());
  d.part_indices.resize(n);
  for (std::uint32_t t = 0; t < n; ++t)
    d.part_indices[t] = std::uint32_t(
        std::lower_bound(d.palette.begin(), d.palette.end(), region.parts[t]) - d.palette.begin());
  const auto [id_min, id_max] = std::minmax_element(region.ids.begin(), region.ids.end());
  d.id_base = *id_min;
  d.id_bytes = *id_max - d.id_base <= 0xffff'ffffu ? 4 : 8;
  tables_ = std::move(tables);
}

StoredRegion::~StoredRegion() = default;
StoredRegion::StoredRegion(StoredRegion&&) noexcept = default;
StoredRegion& StoredRegion::operator=(StoredRegion&&) noexcept = default;

double StoredRegion::max_rounding_distance() const {
  return tables_->g.max_rounding_distance;
}

std::span<const Triangle> StoredRegion::stored_triangles() const {
  return tables_->g.triangles;
}

BuiltShard build_shard(const ShardTriangles& region, ShardKind kind, StoredPrecision precision,
                       const ShardLayout& layout) {
  check_layout(layout);  // before the region's work
  return StoredRegion(region, precision).build(kind, layout);
}

BuiltShard StoredRegion::build(ShardKind kind, const ShardLayout& layout) const {
  namespace sf = shard_format;
  check_layout(layout);
  const Tables& d = *tables_;
  const ShardTriangles& region = d.region;
  const StoredPrecision precision = d.precision;
  const StoredGeometry& g = d.g;
  const Box& bounds = d.bounds;
  const auto n = std::uint32_t(region.triangles.size());

  BuiltShard built;
  built.kind = kind;
  built.precision = precision;
  built.max_rounding_distance = g.max_rounding_distance;
  built.origin = g.frame.origin;
  built.triangle_count = n;

  // Triangle order: the R-tree's, or the input's.
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::vector<RtreeNode> nodes;
  GridIndex grid;
  if (kind == ShardKind::rtree) {
    const std::uint32_t leaf = layout.rtree_leaf_size == 0 ? 8 : layout.rtree_leaf_size;
    RtreeBuilder tree(d.boxes, leaf, layout.rtree_fanout);
    tree.build();
    order = tree.order();
    nodes = std::move(tree.nodes());
    built.rtree_leaf_size = leaf;
    built.rtree_nodes = std::uint32_t(nodes.size());
  } else {
    const auto& c = layout.grid_cells;
    const std::array<std::uint32_t, 3> cells =
        c[0] == 0 && c[1] == 0 && c[2] == 0
            ? grid_cells_for(bounds, n, layout.grid_cells_per_triangle)
            : c;
    grid = build_grid(g.triangles, bounds, cells);
    built.grid_cells = cells;
    built.grid_references = grid.references.size();
  }

  // Vertices renumbered in order of first use, for locality.
  std::vector<std::uint32_t> renumber(g.relative.size(), std::numeric_limits<std::uint32_t>::max());
  std::vector<std::uint32_t> vertex_order;
  vertex_order.reserve(g.relative.size());
  for (const std::uint32_t t : order)
    for (const std::uint32_t v : g.corners[t])
      if (renumber[v] == std::numeric_limits<std::uint32_t>::max()) {
        renumber[v] = std::uint32_t(vertex_order.size());
        vertex_order.push_back(v);
      }
  const auto vertex_count = std::uint32_t(vertex_order.size());
  built.vertex_count = vertex_count;

  const std::vector<std::uint32_t>& palette = d.palette;
  const std::uint64_t id_base = d.id_base;
  const std::uint8_t id_bytes = d.id_bytes;
  const std::uint8_t index_bytes = vertex_count <= 65536 ? 2 : 4;
  const std::uint8_t part_bytes =
      palette.size() == 1 ? 0 : (palette.size() <= 256 ? 1 : (palette.size() <= 65536 ? 2 : 4));
  const std::uint8_t reference_bytes = kind == ShardKind::grid ? (n <= 65536 ? 2 : 4) : 0;

  std::vector<std::byte>& out = built.payload;
  {  // one allocation: appends then never move the payload
    const std::size_t real = precision == StoredPrecision::float32 ? 4 : 8;
    const std::size_t structure =
        kind == ShardKind::grid ? 4 * grid.cell_offsets.size() : nodes.size() * (6 * real + 8);
    out.reserve(sf::kHeaderBytes + 3 * real * vertex_count +
                std::size_t(n) * (3 * index_bytes + id_bytes + part_bytes) + 4 * palette.size() +
                structure + reference_bytes * grid.references.size() + 8 * 8);
  }
  out.assign(sf::kHeaderBytes, std::byte{0});
  PayloadWriter w(out);
  std::memcpy(out.data(), sf::kMagic.data(), 4);
  w.put<std::uint16_t>(4, sf::kVersion);
  w.put<std::uint8_t>(6, std::uint8_t(kind));
  w.put<std::uint8_t>(7, std::uint8_t(precision));
  w.put<std::uint8_t>(8, index_bytes);
  w.put<std::uint8_t>(9, id_bytes);
  w.put<std::uint8_t>(10, part_bytes);
  w.put<std::uint8_t>(11, reference_bytes);
  w.put<std::uint32_t>(12, vertex_count);
  w.put<std::uint32_t>(16, n);
  w.put<std::uint32_t>(20, std::uint32_t(palette.size()));
  w.put<std::uint32_t>(24, kind == ShardKind::grid ? std::uint32_t(grid.cell_offsets.size() - 1)
                                                   : std::uint32_t(nodes.size()));
  w.put<std::uint32_t>(28, std::uint32_t(grid.references.size()));
  w.put<std::uint64_t>(32, id_base);
  for (int k = 0; k < 3; ++k) {
    w.put<double>(40 + 8 * k, g.frame.origin[k]);
    if (kind == ShardKind::grid) {
      w.put<std::uint32_t>(64 + 4 * k, grid.shape.cells[k]);
      w.put<double>(80 + 8 * k, grid.shape.lo[k]);
      w.put<double>(104 + 8 * k, grid.shape.cell_size[k]);
    }
  }
  std::size_t section = 0;
  auto begin_section = [&] {
    w.align();
    w.put<std::uint64_t>(128 + 8 * section++, w.size());
  };
  auto put_real = [&](double value) {
    if (precision == StoredPrecision::float32)
      w.append<float>(float(value));  // exact: the value is a stored float
    else
      w.append<double>(value);
  };

  begin_section();  // vertices
  for (const std::uint32_t v : vertex_order)
    for (int k = 0; k < 3; ++k) put_real(g.relative[v][k]);
  begin_section();  // triangles
  for (const std::uint32_t t : order)
    for (const std::uint32_t v : g.corners[t]) {
      if (index_bytes == 2)
        w.append<std::uint16_t>(std::uint16_t(renumber[v]));
      else
        w.append<std::uint32_t>(renumber[v]);
    }
  begin_section();  // ids
  for (const std::uint32_t t : order) {
    if (id_bytes == 4)
      w.append<std::uint32_t>(std::uint32_t(region.ids[t] - id_base));
    else
      w.append<std::uint64_t>(region.ids[t] - id_base);
  }
  begin_section();  // part palette
  for (const std::uint32_t p : palette) w.append<std::uint32_t>(p);
  begin_section();  // part indices
  if (part_bytes > 0)
    for (const std::uint32_t t : order) {
      const std::uint32_t i = d.part_indices[t];
      if (part_bytes == 1)
        w.append<std::uint8_t>(std::uint8_t(i));
      else if (part_bytes == 2)
        w.append<std::uint16_t>(std::uint16_t(i));
      else
        w.append<std::uint32_t>(i);
    }
  begin_section();  // structure
  if (kind == ShardKind::grid) {
    for (const std::uint32_t o : grid.cell_offsets) w.append<std::uint32_t>(o);
  } else {
    for (const RtreeNode& node : nodes) {
      for (int k = 0; k < 3; ++k) put_real(node.box.lo[k]);
      for (int k = 0; k < 3; ++k) put_real(node.box.hi[k]);
      w.append<std::uint32_t>(node.first);
      w.append<std::uint32_t>(node.count);
    }
  }
  begin_section();  // references
  for (const std::uint32_t t : grid.references) {
    if (reference_bytes == 2)
      w.append<std::uint16_t>(std::uint16_t(t));
    else
      w.append<std::uint32_t>(t);
  }
  begin_section();  // end
  return built;
}

}  // namespace tetrapage
