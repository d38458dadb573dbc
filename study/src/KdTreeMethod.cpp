// The study's 3d-tree (section 3.2): a BSP tree of axis-orthogonal cuts at the middle of each
// box, every node holding (implicitly) the obstacle triangles that meet its box (exact
// triangle/box test), leaves below K triangles.

#include <chrono>
#include <cmath>
#include <optional>

#include "Obstacles.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/runtime/geometry/TriangleBox.h"
#include "tetrapage/study/BoxMethods.h"

namespace tetrapage::study {
namespace {

const char* rule_name(KdAxisRule rule) {
  switch (rule) {
    case KdAxisRule::min_max_count: return "(a) min max(n1,n2)";
    case KdAxisRule::min_count_gap: return "(b) min |n1-n2|";
    case KdAxisRule::min_count_product: return "(c) min n1*n2";
    case KdAxisRule::longest_side: return "(d) longest side";
  }
  return "?";
}

class KdTreeMethod final : public StudyMethod {
 public:
  KdTreeMethod(std::span<const geometry::Triangle> input, const KdTreeOptions& options)
      : obstacles_(input, "3d-tree method"), options_(options), stamps_(input.size()) {
    if (options.leaf_triangles == 0) throw InputError("3d-tree method: K must be at least 1");
    const auto start = std::chrono::steady_clock::now();
    std::vector<std::uint32_t> all(obstacles_.size());
    for (std::uint32_t t = 0; t < all.size(); ++t) all[t] = t;
    nodes_.push_back({});
    build(0, obstacles_.bounds, std::move(all), 0, 0);
    build_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }

  std::string name() const override { return "3d-tree"; }
  std::string parameters() const override {
    return "K=" + std::to_string(options_.leaf_triangles) + ", axis " + rule_name(options_.axis_rule) +
           ", no-gain " + std::to_string(options_.no_gain_splits);
  }

  bool collides(const PlacedObject& object, StudyCounters& counters) override {
    return two_phase_check(
        object, counters,
        [&](const geometry::Box& b) { return geometry::boxes_overlap(b, obstacles_.bounds) && find_witness(0, b, counters); },
        [&](std::size_t i) {
          const geometry::Box& t_box = object.triangle_boxes()[i];
          if (!geometry::boxes_overlap(t_box, obstacles_.bounds)) return false;
          stamps_.next_round();
          return test_triangle(0, object.triangles()[i], t_box, object.box(), counters);
        });
  }

  StudyStatistics statistics() const override {
    StudyStatistics s;
    s.obstacle_triangles = obstacles_.size();
    s.stored_triangles = leaf_triangles_.size();
    s.height = height_;
    s.bytes = obstacles_.bytes() + nodes_.capacity() * sizeof(Node) +
              leaf_triangles_.capacity() * sizeof(std::uint32_t) + stamps_.bytes();
    s.build_seconds = build_seconds_;
    std::uint64_t leaves = 0;
    for (const auto& n : nodes_) leaves += n.axis < 0;
    s.details = {{"nodes", nodes_.size()}, {"leaves", leaves}};
    return s;
  }

 private:
  struct Node {
    int axis = -1;  // -1: a leaf
    double cut = 0;
    std::uint32_t children = 0;  // left; right is children + 1
    std::uint32_t first = 0, count = 0;  // a leaf's triangles in leaf_triangles_
  };

  void build(std::uint32_t node, const geometry::Box& box, std::vector<std::uint32_t> triangles, unsigned depth,
             unsigned no_gain) {
    height_ = std::max(height_, depth);
    const std::size_t n = triangles.size();
    if (n < options_.leaf_triangles || depth >= options_.max_depth) return make_leaf(node, triangles);
    struct Split {
      int axis;
      double cut;
      geometry::Box left, right;
      std::vector<std::uint32_t> in_left, in_right;
    };
    auto split_on = [&](int a) {
      Split s{a, 0.5 * (box.lo[a] + box.hi[a]), box, box, {}, {}};
      s.left.hi[a] = s.cut;
      s.right.lo[a] = s.cut;
      for (const std::uint32_t t : triangles) {
        // A triangle whose box is on one side cannot meet the other child's box.
        const geometry::Box& b = obstacles_.boxes[t];
        if (b.lo[a] > s.cut) {
          if (geometry::triangle_intersects_box(obstacles_.triangles[t], s.right)) s.in_right.push_back(t);
        } else if (b.hi[a] < s.cut) {
          if (geometry::triangle_intersects_box(obstacles_.triangles[t], s.left)) s.in_left.push_back(t);
        } else {
          if (geometry::triangle_intersects_box(obstacles_.triangles[t], s.left)) s.in_left.push_back(t);
          if (geometry::triangle_intersects_box(obstacles_.triangles[t], s.right)) s.in_right.push_back(t);
        }
      }
      return s;
    };
    auto score = [&](const Split& s) -> double {
      const double n1 = double(s.in_left.size()), n2 = double(s.in_right.size());
      switch (options_.axis_rule) {
        case KdAxisRule::min_max_count: return std::max(n1, n2);
        case KdAxisRule::min_count_gap: return std::abs(n1 - n2);
        case KdAxisRule::min_count_product: return n1 * n2;
        case KdAxisRule::longest_side: return -(box.hi[s.axis] - box.lo[s.axis]);
      }
      return 0;
    };
    std::optional<Split> best;
    for (int a = 0; a < 3; ++a) {
      if (!(box.hi[a] > box.lo[a])) continue;  // a flat box cannot be cut along this axis
      if (options_.axis_rule == KdAxisRule::longest_side && best &&
          box.hi[a] - box.lo[a] <= box.hi[best->axis] - box.lo[best->axis])
        continue;
      Split s = split_on(a);
      if (!best || score(s) < score(*best)) best = std::move(s);
    }
    if (!best) return make_leaf(node, triangles);
    // A split where a child keeps every triangle gains nothing; allowed a few times on a path.
    const bool gain = best->in_left.size() < n && best->in_right.size() < n;
    if (!gain && no_gain >= options_.no_gain_splits) return make_leaf(node, triangles);
    std::vector<std::uint32_t>().swap(triangles);
    const auto children = std::uint32_t(nodes_.size());
    nodes_[node].axis = best->axis;
    nodes_[node].cut = best->cut;
    nodes_[node].children = children;
    nodes_.push_back({});
    nodes_.push_back({});
    const unsigned next_no_gain = no_gain + (gain ? 0 : 1);
    build(children, best->left, std::move(best->in_left), depth + 1, next_no_gain);
    build(children + 1, best->right, std::move(best->in_right), depth + 1, next_no_gain);
  }

  void make_leaf(std::uint32_t node, const std::vector<std::uint32_t>& triangles) {
    nodes_[node].axis = -1;
    nodes_[node].first = std::uint32_t(leaf_triangles_.size());
    nodes_[node].count = std::uint32_t(triangles.size());
    leaf_triangles_.insert(leaf_triangles_.end(), triangles.begin(), triangles.end());
  }

  // Children a box reaches: the left one if it starts at or before the cut, the right one if it
  // ends at or after it (the cut plane belongs to both).
  bool find_witness(std::uint32_t index, const geometry::Box& box, StudyCounters& counters) const {
    ++counters.nodes_visited;
    const Node& node = nodes_[index];
    if (node.axis < 0) {
      for (std::uint32_t k = node.first; k < node.first + node.count; ++k)
        if (geometry::boxes_overlap(obstacles_.boxes[leaf_triangles_[k]], box)) return true;
      return false;
    }
    return (box.lo[node.axis] <= node.cut && find_witness(node.children, box, counters)) ||
           (box.hi[node.axis] >= node.cut && find_witness(node.children + 1, box, counters));
  }

  bool test_triangle(std::uint32_t index, const geometry::Triangle& t, const geometry::Box& t_box,
                     const geometry::Box& object_box, StudyCounters& counters) {
    ++counters.nodes_visited;
    const Node& node = nodes_[index];
    if (node.axis < 0) {
      for (std::uint32_t k = node.first; k < node.first + node.count; ++k) {
        const std::uint32_t o = leaf_triangles_[k];
        if (!stamps_.first_visit(o) || !geometry::boxes_overlap(obstacles_.boxes[o], object_box)) continue;
        if (obstacles_.meets(t, t_box, o, counters)) return true;
      }
      return false;
    }
    const int a = node.axis;
    const double cut = node.cut;
    const std::uint32_t children = node.children;  // nodes_ does not move during queries
    return (t_box.lo[a] <= cut && test_triangle(children, t, t_box, object_box, counters)) ||
           (t_box.hi[a] >= cut && test_triangle(children + 1, t, t_box, object_box, counters));
  }

  Obstacles obstacles_;
  KdTreeOptions options_;
  std::vector<Node> nodes_;
  std::vector<std::uint32_t> leaf_triangles_;
  unsigned height_ = 0;
  VisitStamps stamps_;
  double build_seconds_ = 0;
};

}  // namespace

std::unique_ptr<StudyMethod> make_kd_tree_method(std::span<const geometry::Triangle> obstacles,
                                                 const KdTreeOptions& options) {
  return std::make_unique<KdTreeMethod>(obstacles, options);
}

}  // namespace tetrapage::study
