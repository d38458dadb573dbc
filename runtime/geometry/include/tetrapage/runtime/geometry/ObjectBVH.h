#pragma once
/// @file ObjectBVH.h
/// A bounding volume hierarchy over the flying object's triangles, built once per object in
/// its own coordinates and queried with environment triangles already transformed into that
/// frame: phase II then costs about (candidates x log object size) triangle tests instead of
/// (candidates x object size).
///
/// Node boxes are stored in float, rounded outwards, so they always contain the double boxes
/// of their triangles: pruning never drops a pair that the leaf test would accept, and every
/// query answers exactly what the brute-force reference (the same test on every triangle)
/// answers, in every accuracy mode.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

#include "tetrapage/runtime/geometry/Accuracy.h"
#include "tetrapage/runtime/geometry/Box.h"
#include "tetrapage/runtime/geometry/FloatRounding.h"

namespace tetrapage::geometry {

class ObjectBVH {
 public:
  /// What a query did, for the counters that explain the time.
  struct QueryCounters {
    std::uint64_t nodes_visited = 0;
    std::uint64_t triangle_tests = 0;
  };

  /// Builds the hierarchy (binned surface-area heuristic, O(k log k) for k triangles).
  /// @throw InputError if there is no triangle, a vertex index is out of range or a vertex
  ///        coordinate is NaN or infinite (the message names the triangle or vertex).
  ObjectBVH(std::span<const Vec3> vertices, std::span<const TriangleIndices> triangles);
  /// @throw InputError as above.
  explicit ObjectBVH(const TriangleSoup& object) : ObjectBVH(object.vertices, object.triangles) {}

  std::size_t triangle_count() const { return triangles_.size(); }
  std::size_t node_count() const { return nodes_.size(); }
  /// The longest root-to-leaf path, in nodes.
  std::size_t depth() const { return depth_; }
  /// The object's bounding box.
  const Box& bounds() const { return bounds_; }
  /// Bytes held by the hierarchy and its copy of the triangles.
  std::size_t memory_bytes() const;
  /// Triangle `index` (the index in the input) in object coordinates.
  const Triangle& triangle(std::uint32_t index) const { return triangles_[position_of_[index]]; }

  /// Some object triangle colliding with `query` (object coordinates) under `accuracy`, or
  /// nothing. Stops at the first hit found (not necessarily the lowest index).
  std::optional<std::uint32_t> first_hit(const Triangle& query, const Accuracy& accuracy = {},
                                         QueryCounters* counters = nullptr) const;

  /// Appends to `hits` every object triangle colliding with `query` (in no particular order);
  /// returns how many were appended.
  std::size_t all_hits(const Triangle& query, const Accuracy& accuracy,
                       std::vector<std::uint32_t>& hits, QueryCounters* counters = nullptr) const;

  /// Calls visit(index) (index in the input) for every triangle whose box overlaps the closed
  /// `box` (object coordinates), until visit returns false. Conservative: node boxes are
  /// rounded outwards, and the query box is rounded outwards to float.
  template <class Visit>
  void for_each_in_box(const Box& box, Visit&& visit, QueryCounters* counters = nullptr) const {
    for_each_in_box(box, [](const Box&) { return true; }, visit, counters);
  }
  /// The same, also skipping the nodes and triangles whose (outward-rounded) box `near(box)`
  /// rejects: a conservative filter of the caller's that keeps every box holding a box it keeps
  /// (e.g. the box misses a slab around a plane). The box of a large, tilted query triangle holds
  /// most of the object; its plane does not.
  template <class Near, class Visit>
  void for_each_in_box(const Box& box, Near&& near, Visit&& visit,
                       QueryCounters* counters = nullptr) const {
    FloatBox q;
    for (int k = 0; k < 3; ++k) {
      q.lo[k] = float_below(box.lo[k]);
      q.hi[k] = float_above(box.hi[k]);
    }
    const WideQuery query(q);
    std::uint64_t visited = 0, tests = 0;
    // A leaf's triangles, or a wide node (count 0).
    struct Entry {
      std::uint32_t first, count;
    };
    Entry stack[kMaxWideStack];
    int top = 0;
    // Pushed last to first, so that the children are visited in the binary hierarchy's order.
    const auto push_children = [&](const WideNode& node) {
      for (unsigned mask = query.overlapping(node); mask != 0;) {
        const int c = 31 - __builtin_clz(mask);
        mask &= ~(1u << c);
        if (near(child_box(node, c))) stack[top++] = {node.first[c], node.count[c]};
      }
    };
    push_children(wide_nodes_[0]);
    while (top > 0) {
      const Entry entry = stack[--top];
      ++visited;
      if (entry.count == 0) {
        push_children(wide_nodes_[entry.first]);
        continue;
      }
      for (std::uint32_t i = entry.first; i < entry.first + entry.count; ++i) {
        ++tests;
        const Box own = box_of(triangles_[i]);
        if (boxes_overlap(box, own) && near(own) && !visit(original_[i])) {
          top = 0;
          break;
        }
      }
    }
    if (counters) {
      counters->nodes_visited += visited;
      counters->triangle_tests += tests;
    }
  }

  /// Calls visit(index) (index in the input) for every triangle whose box lies within
  /// `reach()` of the closed `box` (object coordinates), nearer nodes first, until visit
  /// returns false. `reach()` is asked again before each node and triangle: a visitor that
  /// finds closer triangles shrinks it, and what lies beyond is pruned. Conservative: node
  /// boxes are rounded outwards, and gaps are compared 2^-40 short of `reach()`.
  template <class Reach, class Visit>
  void for_each_near(const Box& box, Reach&& reach, Visit&& visit,
                     QueryCounters* counters = nullptr) const {
    for_each_near(box, [](const Box&, double) { return false; }, reach, visit, counters);
  }
  /// The same, also pruning the nodes (with their boxes, rounded outwards, and the reach)
  /// that `beyond_node(box, reach)` says lie beyond the reach: a caller's own conservative
  /// bound, e.g. a separating direction.
  template <class BeyondNode, class Reach, class Visit>
  void for_each_near(const Box& box, BeyondNode&& beyond_node, Reach&& reach, Visit&& visit,
                     QueryCounters* counters = nullptr) const {
    auto squared_gap = [&box](const auto& lo, const auto& hi) {
      double sum = 0;
      for (int k = 0; k < 3; ++k) {
        const double gap = std::max({0.0, double(lo[k]) - box.hi[k], box.lo[k] - double(hi[k])});
        sum += gap * gap;
      }
      return sum;
    };
    auto beyond = [&reach](double squared) {
      const double r = reach();
      return squared * (1 - 0x1p-40) > r * r;
    };
    std::uint64_t visited = 0, tests = 0;
    struct Entry {
      std::uint32_t node;
      double squared_gap;
    };
    Entry stack[kMaxStack];
    int top = 0;
    stack[top++] = {0, squared_gap(nodes_[0].lo, nodes_[0].hi)};
    while (top > 0) {
      const Entry entry = stack[--top];
      if (beyond(entry.squared_gap)) continue;
      const Node& node = nodes_[entry.node];
      if (beyond_node(Box{{node.lo[0], node.lo[1], node.lo[2]}, {node.hi[0], node.hi[1], node.hi[2]}}, reach()))
        continue;
      ++visited;
      if (node.count > 0) {
        for (std::uint32_t i = node.first; i < node.first + node.count; ++i) {
          ++tests;
          const Box own = box_of(triangles_[i]);
          if (!beyond(squared_gap(own.lo, own.hi)) && !visit(original_[i])) {
            top = 0;
            break;
          }
        }
        continue;
      }
      // The nearer child on top of the stack: it is searched first, and shrinks the reach.
      const std::uint32_t left = entry.node + 1, right = node.first;
      const Entry a{left, squared_gap(nodes_[left].lo, nodes_[left].hi)};
      const Entry b{right, squared_gap(nodes_[right].lo, nodes_[right].hi)};
      const Entry& near = a.squared_gap <= b.squared_gap ? a : b;
      const Entry& far = a.squared_gap <= b.squared_gap ? b : a;
      if (!beyond(far.squared_gap)) stack[top++] = far;
      if (!beyond(near.squared_gap)) stack[top++] = near;
    }
    if (counters) {
      counters->nodes_visited += visited;
      counters->triangle_tests += tests;
    }
  }

  /// Both hierarchies descended together (two objects, each in its own frame): calls
  /// visit(mine, theirs) (indices in the inputs) for every pair of a triangle of this BVH and
  /// one of `other` whose leaves' boxes, and every ancestor's, `meet(my_box, their_box)`
  /// accepts, until visit returns false. `meet` receives node boxes in their own frames (rounded
  /// outwards) and must be conservative: it compares boxes across frames, so it is the caller's.
  template <class Meet, class Visit>
  void for_each_pair(const ObjectBVH& other, Meet&& meet, Visit&& visit) const {
    const auto box_of_node = [](const Node& n) {
      Box b;
      b.lo = {n.lo[0], n.lo[1], n.lo[2]};
      b.hi = {n.hi[0], n.hi[1], n.hi[2]};
      return b;
    };
    // Each split pops one pair and pushes two: the stack holds at most one pair per level of
    // either hierarchy, plus one.
    std::pair<std::uint32_t, std::uint32_t> stack[2 * kMaxStack + 2];
    int top = 0;
    if (meet(box_of_node(nodes_[0]), box_of_node(other.nodes_[0]))) stack[top++] = {0, 0};
    while (top > 0) {
      const auto [a, b] = stack[--top];
      const Node& na = nodes_[a];
      const Node& nb = other.nodes_[b];
      if (na.count > 0 && nb.count > 0) {
        for (std::uint32_t i = na.first; i < na.first + na.count; ++i)
          for (std::uint32_t j = nb.first; j < nb.first + nb.count; ++j)
            if (!visit(original_[i], other.original_[j])) return;
        continue;
      }
      // Split the inner node, or the larger of two (by the sum of its sides).
      const auto sides = [](const Node& n) { return (n.hi[0] - n.lo[0]) + (n.hi[1] - n.lo[1]) + (n.hi[2] - n.lo[2]); };
      const bool split_mine = nb.count > 0 || (na.count == 0 && sides(na) >= sides(nb));
      if (split_mine) {
        for (const std::uint32_t child : {na.first, a + 1})
          if (meet(box_of_node(nodes_[child]), box_of_node(nb))) stack[top++] = {child, b};
      } else {
        for (const std::uint32_t child : {nb.first, b + 1})
          if (meet(box_of_node(na), box_of_node(other.nodes_[child]))) stack[top++] = {a, child};
      }
    }
  }

  /// The reference: triangles_collide(query, t, accuracy) on every triangle, in index order.
  /// first_hit_brute_force returns the lowest colliding index.
  std::optional<std::uint32_t> first_hit_brute_force(const Triangle& query,
                                                     const Accuracy& accuracy = {}) const;
  std::size_t all_hits_brute_force(const Triangle& query, const Accuracy& accuracy,
                                   std::vector<std::uint32_t>& hits) const;

 private:
  struct Node {
    float lo[3];
    std::uint32_t first;  ///< leaf: first triangle position; inner node: right child
    float hi[3];
    std::uint32_t count;  ///< leaf: number of triangles (> 0); inner node: 0 (left child next)
  };
  struct FloatBox {
    float lo[3], hi[3];
  };
  static constexpr int kMaxStack = 128;  // the build bounds the depth well below this
  /// Up to four children of the binary hierarchy's nodes, their boxes (its float boxes) as
  /// structure of arrays, so that a box query tests the four at once. Collapsed from the binary
  /// hierarchy with the children in its left-to-right order: a query visits the triangles in
  /// the same order as a descent of the binary one.
  struct WideNode {
    float lo[3][4];
    float hi[3][4];
    std::uint32_t first[4];  ///< a leaf's first triangle position, or a wide node
    std::uint32_t count[4];  ///< a leaf's triangles (> 0), or 0 for a wide node
    std::uint32_t children;  ///< 1 to 4: the slots used, from the first
  };
  static Box child_box(const WideNode& node, int c) {
    return Box{{node.lo[0][c], node.lo[1][c], node.lo[2][c]},
               {node.hi[0][c], node.hi[1][c], node.hi[2][c]}};
  }
  /// Each level of the wide hierarchy leaves at most three siblings pending.
  static constexpr int kMaxWideStack = 3 * kMaxStack + 4;
  /// A box query's bounds, broadcast once for the tests of four children at a time.
  class WideQuery {
   public:
    explicit WideQuery(const FloatBox& q) {
#if defined(__SSE2__)
      for (int k = 0; k < 3; ++k) lo_[k] = _mm_set1_ps(q.lo[k]), hi_[k] = _mm_set1_ps(q.hi[k]);
#else
      q_ = q;
#endif
    }
    /// Bit c set for each used child c whose box overlaps the query's (NaN overlaps nothing).
    unsigned overlapping(const WideNode& node) const {
      const unsigned used = (1u << node.children) - 1;
#if defined(__SSE2__)
      __m128 in = _mm_and_ps(_mm_cmple_ps(_mm_loadu_ps(node.lo[0]), hi_[0]),
                             _mm_cmple_ps(lo_[0], _mm_loadu_ps(node.hi[0])));
      for (int k = 1; k < 3; ++k)
        in = _mm_and_ps(in, _mm_and_ps(_mm_cmple_ps(_mm_loadu_ps(node.lo[k]), hi_[k]),
                                       _mm_cmple_ps(lo_[k], _mm_loadu_ps(node.hi[k]))));
      return unsigned(_mm_movemask_ps(in)) & used;
#else
      unsigned mask = 0;
      for (int c = 0; c < 4; ++c) {
        bool in = true;
        for (int k = 0; k < 3; ++k)
          in = in && node.lo[k][c] <= q_.hi[k] && q_.lo[k] <= node.hi[k][c];
        mask |= unsigned(in) << c;
      }
      return mask & used;
#endif
    }

   private:
#if defined(__SSE2__)
    __m128 lo_[3], hi_[3];
#else
    FloatBox q_;
#endif
  };
  struct BuildItem;

  std::uint32_t build(std::vector<BuildItem>& items, const std::vector<Triangle>& source,
                      std::size_t begin, std::size_t end, std::size_t depth);
  /// The wide node over binary node `node`'s descendants (itself, when it is a leaf).
  std::uint32_t collapse(std::uint32_t node);

  template <class Visitor>
  void traverse(const Triangle& query, const Accuracy& accuracy, QueryCounters* counters,
                Visitor&& visit) const;

  std::vector<Node> nodes_;
  std::vector<WideNode> wide_nodes_;        ///< box queries; the root first
  std::vector<Triangle> triangles_;         ///< in leaf order
  std::vector<std::uint32_t> original_;     ///< input index of each position
  std::vector<std::uint32_t> position_of_;  ///< position of each input index
  Box bounds_;
  double max_triangle_extent_ = 0.0;
  std::size_t depth_ = 0;
};

}  // namespace tetrapage::geometry
