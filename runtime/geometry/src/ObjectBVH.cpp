#include "tetrapage/runtime/geometry/ObjectBVH.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/runtime/geometry/TriangleTriangle.h"

namespace tetrapage::geometry {

struct ObjectBVH::BuildItem {
  Box box;
  Point centroid;  // of the box
  std::uint32_t index;
};

namespace {

constexpr int kBins = 16;
constexpr std::size_t kSmallLeaf = 2;     // never split below this
constexpr std::size_t kLargestLeaf = 8;   // always split above this
constexpr std::size_t kMedianDepth = 48;  // below this depth, split at the median (bounded depth)
constexpr double kTraversalCost = 1.0;    // relative to one triangle test
double half_area(const Box& b) {
  if (b.empty()) return 0.0;
  const double dx = b.hi[0] - b.lo[0], dy = b.hi[1] - b.lo[1], dz = b.hi[2] - b.lo[2];
  return dx * dy + dy * dz + dz * dx;
}

}  // namespace

ObjectBVH::ObjectBVH(std::span<const Vec3> vertices, std::span<const TriangleIndices> triangles) {
  if (triangles.empty()) throw InputError("object BVH: the object has no triangle");
  for (std::size_t v = 0; v < vertices.size(); ++v)
    if (!is_finite(vertices[v])) {
      std::ostringstream message;
      message << "object BVH: vertex " << v << " has a non-finite coordinate (" << vertices[v][0]
              << ", " << vertices[v][1] << ", " << vertices[v][2] << ")";
      throw InputError(message.str());
    }
  if (triangles.size() > std::numeric_limits<std::uint32_t>::max() / 2)
    throw InputError("object BVH: too many triangles (" + std::to_string(triangles.size()) + ")");

  std::vector<Triangle> source(triangles.size());
  std::vector<BuildItem> items(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    for (int c = 0; c < 3; ++c) {
      const auto v = triangles[t][c];
      if (v >= vertices.size()) {
        std::ostringstream message;
        message << "object BVH: triangle " << t << " refers to vertex " << v << " but there are "
                << vertices.size() << " vertices";
        throw InputError(message.str());
      }
      source[t][c] = vertices[v];
    }
    const Box box = box_of(source[t]);
    items[t] = {box, box.center(), static_cast<std::uint32_t>(t)};
    bounds_.extend(box);
    max_triangle_extent_ = std::max(max_triangle_extent_, extent(box));
  }

  nodes_.reserve(2 * triangles.size());
  triangles_.reserve(triangles.size());
  original_.reserve(triangles.size());
  build(items, source, 0, items.size(), 1);
  wide_nodes_.reserve(nodes_.size() / 3 + 1);
  collapse(0);
  position_of_.resize(triangles.size());
  for (std::size_t p = 0; p < original_.size(); ++p) position_of_[original_[p]] = std::uint32_t(p);
}

std::uint32_t ObjectBVH::build(std::vector<BuildItem>& items, const std::vector<Triangle>& source,
                               std::size_t begin, std::size_t end, std::size_t depth) {
  depth_ = std::max(depth_, depth);
  Box box, centroids;
  for (std::size_t i = begin; i < end; ++i) {
    box.extend(items[i].box);
    centroids.extend(items[i].centroid);
  }
  const auto node_index = static_cast<std::uint32_t>(nodes_.size());
  Node node{};
  for (int k = 0; k < 3; ++k) {
    node.lo[k] = float_below(box.lo[k]);
    node.hi[k] = float_above(box.hi[k]);
  }
  nodes_.push_back(node);

  const std::size_t n = end - begin;
  auto make_leaf = [&] {
    nodes_[node_index].first = static_cast<std::uint32_t>(triangles_.size());
    nodes_[node_index].count = static_cast<std::uint32_t>(n);
    for (std::size_t i = begin; i < end; ++i) {
      triangles_.push_back(source[items[i].index]);
      original_.push_back(items[i].index);
    }
    return node_index;
  };
  if (n <= kSmallLeaf) return make_leaf();

  const Vec3 spread = centroids.size();
  const int axis =
      spread[0] >= spread[1] && spread[0] >= spread[2] ? 0 : (spread[1] >= spread[2] ? 1 : 2);
  std::size_t mid = begin + n / 2;
  bool split_at_median =
      !(spread[axis] > 0) || !std::isfinite(kBins / spread[axis]) || depth >= kMedianDepth;

  if (!split_at_median) {
    // Binned surface-area heuristic along the widest centroid axis.
    const double lo = centroids.lo[axis];
    const double scale = kBins / spread[axis];
    auto bin_of = [&](const BuildItem& item) {
      return std::min(kBins - 1, static_cast<int>((item.centroid[axis] - lo) * scale));
    };
    std::size_t count[kBins] = {};
    Box bin_box[kBins];
    for (std::size_t i = begin; i < end; ++i) {
      const int b = bin_of(items[i]);
      ++count[b];
      bin_box[b].extend(items[i].box);
    }
    double right_area[kBins];
    std::size_t right_count[kBins];
    Box accumulated;
    std::size_t accumulated_count = 0;
    for (int b = kBins - 1; b > 0; --b) {
      accumulated.extend(bin_box[b]);
      accumulated_count += count[b];
      right_area[b] = half_area(accumulated);
      right_count[b] = accumulated_count;
    }
    const double node_area = half_area(box);
    double best_cost = std::numeric_limits<double>::infinity();
    int best_split = -1;  // left: bins 0..best_split
    accumulated = Box();
    accumulated_count = 0;
    for (int b = 0; b < kBins - 1; ++b) {
      accumulated.extend(bin_box[b]);
      accumulated_count += count[b];
      if (accumulated_count == 0 || right_count[b + 1] == 0) continue;
      const double cost = half_area(accumulated) * double(accumulated_count) +
                          right_area[b + 1] * double(right_count[b + 1]);
      if (cost < best_cost) {
        best_cost = cost;
        best_split = b;
      }
    }
    const double leaf_cost = double(n);
    const double split_cost = node_area > 0 ? kTraversalCost + best_cost / node_area
                                            : std::numeric_limits<double>::infinity();
    if (best_split < 0) {
      split_at_median = true;
    } else {
      if (n <= kLargestLeaf && leaf_cost <= split_cost) return make_leaf();
      const auto middle =
          std::partition(items.begin() + std::ptrdiff_t(begin), items.begin() + std::ptrdiff_t(end),
                         [&](const BuildItem& item) { return bin_of(item) <= best_split; });
      mid = static_cast<std::size_t>(middle - items.begin());
      if (mid == begin || mid == end) split_at_median = true;
    }
  }
  if (split_at_median) {
    mid = begin + n / 2;
    std::nth_element(items.begin() + std::ptrdiff_t(begin), items.begin() + std::ptrdiff_t(mid),
                     items.begin() + std::ptrdiff_t(end),
                     [axis](const BuildItem& a, const BuildItem& b) {
                       return a.centroid[axis] < b.centroid[axis];
                     });
  }
  build(items, source, begin, mid, depth + 1);  // the left child is node_index + 1
  const std::uint32_t right = build(items, source, mid, end, depth + 1);
  nodes_[node_index].first = right;
  nodes_[node_index].count = 0;
  return node_index;
}

std::uint32_t ObjectBVH::collapse(std::uint32_t node) {
  // Open the largest inner node among the children (by its box's area) until four are found:
  // each opened node is replaced by its two children in place, so the order stays left to right.
  std::array<std::uint32_t, 4> slots{};
  std::uint32_t used = 0;
  if (nodes_[node].count > 0) {
    slots[used++] = node;
  } else {
    slots[used++] = node + 1;
    slots[used++] = nodes_[node].first;
  }
  const auto area = [this](std::uint32_t n) {
    const Node& b = nodes_[n];
    return half_area(Box{{b.lo[0], b.lo[1], b.lo[2]}, {b.hi[0], b.hi[1], b.hi[2]}});
  };
  while (used < 4) {
    std::uint32_t open = used;
    for (std::uint32_t c = 0; c < used; ++c)
      if (nodes_[slots[c]].count == 0 && (open == used || area(slots[c]) > area(slots[open])))
        open = c;
    if (open == used) break;  // all leaves
    const std::uint32_t opened = slots[open];
    for (std::uint32_t c = used; c > open + 1; --c) slots[c] = slots[c - 1];
    slots[open] = opened + 1;
    slots[open + 1] = nodes_[opened].first;
    ++used;
  }
  const auto index = std::uint32_t(wide_nodes_.size());
  wide_nodes_.emplace_back();
  WideNode wide{};
  wide.children = used;
  for (std::uint32_t c = 0; c < 4; ++c) {
    for (int k = 0; k < 3; ++k) {
      // Unused slots are masked out by `children`; their boxes are empty besides.
      wide.lo[k][c] = c < used ? nodes_[slots[c]].lo[k] : std::numeric_limits<float>::infinity();
      wide.hi[k][c] = c < used ? nodes_[slots[c]].hi[k] : -std::numeric_limits<float>::infinity();
    }
    if (c >= used) continue;
    const Node& child = nodes_[slots[c]];
    wide.first[c] = child.count > 0 ? child.first : collapse(slots[c]);
    wide.count[c] = child.count;
  }
  wide_nodes_[index] = wide;
  return index;
}

std::size_t ObjectBVH::memory_bytes() const {
  return nodes_.capacity() * sizeof(Node) + wide_nodes_.capacity() * sizeof(WideNode) +
         triangles_.capacity() * sizeof(Triangle) +
         (original_.capacity() + position_of_.capacity()) * sizeof(std::uint32_t);
}

template <class Visitor>
void ObjectBVH::traverse(const Triangle& query, const Accuracy& accuracy, QueryCounters* counters,
                         Visitor&& visit) const {
  const Box exact_box = box_of(query);
  // The grown box never drops a pair that triangles_collide accepts (collision_margin), so it
  // prunes nodes and triangles alike.
  const double margin = collision_margin(accuracy, extent(exact_box), max_triangle_extent_);
  const Box box = margin > 0 ? inflated(exact_box, margin) : exact_box;
  const bool exact = accuracy.mode == AccuracyMode::exact;
  for_each_in_box(
      box,
      [&](std::uint32_t index) {
        const Triangle& candidate = triangle(index);
        const bool collides = exact ? triangles_intersect(query, candidate)
                                    : triangles_collide(query, candidate, accuracy);
        return !collides || visit(index);
      },
      counters);
}

std::optional<std::uint32_t> ObjectBVH::first_hit(const Triangle& query, const Accuracy& accuracy,
                                                  QueryCounters* counters) const {
  std::optional<std::uint32_t> hit;
  traverse(query, accuracy, counters, [&hit](std::uint32_t index) {
    hit = index;
    return false;
  });
  return hit;
}

std::size_t ObjectBVH::all_hits(const Triangle& query, const Accuracy& accuracy,
                                std::vector<std::uint32_t>& hits, QueryCounters* counters) const {
  const std::size_t before = hits.size();
  traverse(query, accuracy, counters, [&hits](std::uint32_t index) {
    hits.push_back(index);
    return true;
  });
  return hits.size() - before;
}

std::optional<std::uint32_t> ObjectBVH::first_hit_brute_force(const Triangle& query,
                                                              const Accuracy& accuracy) const {
  for (std::uint32_t t = 0; t < position_of_.size(); ++t)
    if (triangles_collide(query, triangle(t), accuracy)) return t;
  return std::nullopt;
}

std::size_t ObjectBVH::all_hits_brute_force(const Triangle& query, const Accuracy& accuracy,
                                            std::vector<std::uint32_t>& hits) const {
  const std::size_t before = hits.size();
  for (std::uint32_t t = 0; t < position_of_.size(); ++t)
    if (triangles_collide(query, triangle(t), accuracy)) hits.push_back(t);
  return hits.size() - before;
}

}  // namespace tetrapage::geometry
