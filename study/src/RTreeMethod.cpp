// The study's binary R-tree (section 3.3): the triangles of a node split in half at the median
// centroid along the axis whose halves have the smaller boxes; each triangle in one leaf.

#include <algorithm>
#include <chrono>

#include "Obstacles.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/study/BoxMethods.h"

namespace tetrapage::study {
namespace {

double volume(const geometry::Box& b) {
  return (b.hi[0] - b.lo[0]) * (b.hi[1] - b.lo[1]) * (b.hi[2] - b.lo[2]);
}

class RTreeMethod final : public StudyMethod {
 public:
  RTreeMethod(std::span<const geometry::Triangle> input, const RTreeOptions& options)
      : obstacles_(input, "R-tree method"), options_(options) {
    if (options.leaf_triangles == 0) throw InputError("R-tree method: K must be at least 1");
    const auto start = std::chrono::steady_clock::now();
    order_.resize(obstacles_.size());
    centroids_.resize(obstacles_.size());
    for (std::uint32_t t = 0; t < order_.size(); ++t) {
      order_[t] = t;
      const auto& c = obstacles_.triangles[t];
      for (int a = 0; a < 3; ++a) centroids_[t][a] = (c[0][a] + c[1][a] + c[2][a]) / 3.0;
    }
    nodes_.reserve(2 * order_.size());
    nodes_.push_back({});
    build(0, 0, std::uint32_t(order_.size()), 0);
    std::vector<Vec3>().swap(centroids_);
    build_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }

  std::string name() const override { return "r-tree"; }
  std::string parameters() const override {
    return "K=" + std::to_string(options_.leaf_triangles) + ", split " +
           (options_.split_rule == RTreeSplitRule::min_max_volume ? "(a) min max(V1,V2)" : "(b) min V1+V2");
  }

  bool collides(const PlacedObject& object, StudyCounters& counters) override {
    return two_phase_check(
        object, counters, [&](const geometry::Box& b) { return find_witness(0, b, counters); },
        [&](std::size_t i) {
          return test_triangle(0, object.triangles()[i], object.triangle_boxes()[i], object.box(), counters);
        });
  }

  StudyStatistics statistics() const override {
    StudyStatistics s;
    s.obstacle_triangles = obstacles_.size();
    s.stored_triangles = order_.size();
    s.height = height_;
    s.bytes = obstacles_.bytes() + nodes_.capacity() * sizeof(Node) + order_.capacity() * sizeof(std::uint32_t);
    s.build_seconds = build_seconds_;
    s.details = {{"nodes", nodes_.size()}};
    return s;
  }

 private:
  struct Node {
    geometry::Box box;
    std::uint32_t children = 0;          // left; right is children + 1; 0 for a leaf
    std::uint32_t first = 0, count = 0;  // a leaf's triangles: order_[first, first + count)
  };

  geometry::Box box_of_range(std::uint32_t first, std::uint32_t last) const {
    geometry::Box b;
    for (std::uint32_t k = first; k < last; ++k) b.extend(obstacles_.boxes[order_[k]]);
    return b;
  }

  void build(std::uint32_t node, std::uint32_t first, std::uint32_t last, unsigned depth) {
    height_ = std::max(height_, depth);
    nodes_[node].box = box_of_range(first, last);
    if (last - first <= options_.leaf_triangles) {
      nodes_[node].first = first;
      nodes_[node].count = last - first;
      return;
    }
    const std::uint32_t middle = first + (last - first) / 2;
    int best_axis = -1;
    double best_score = 0;
    for (int a = 0; a < 3; ++a) {
      partition(first, middle, last, a);
      const double v1 = volume(box_of_range(first, middle)), v2 = volume(box_of_range(middle, last));
      const double score = options_.split_rule == RTreeSplitRule::min_max_volume ? std::max(v1, v2) : v1 + v2;
      if (best_axis < 0 || score < best_score) best_axis = a, best_score = score;
    }
    if (best_axis != 2) partition(first, middle, last, best_axis);
    const auto children = std::uint32_t(nodes_.size());
    nodes_[node].children = children;
    nodes_.push_back({});
    nodes_.push_back({});
    build(children, first, middle, depth + 1);
    build(children + 1, middle, last, depth + 1);
  }

  // order_[first, last) split at the median centroid along axis a (ties by triangle id, so
  // the tree does not depend on the standard library's nth_element).
  void partition(std::uint32_t first, std::uint32_t middle, std::uint32_t last, int a) {
    std::nth_element(order_.begin() + first, order_.begin() + middle, order_.begin() + last,
                     [&](std::uint32_t x, std::uint32_t y) {
                       return centroids_[x][a] < centroids_[y][a] ||
                              (centroids_[x][a] == centroids_[y][a] && x < y);
                     });
  }

  bool find_witness(std::uint32_t index, const geometry::Box& box, StudyCounters& counters) const {
    ++counters.nodes_visited;
    const Node& node = nodes_[index];
    if (!geometry::boxes_overlap(node.box, box)) return false;
    if (node.children == 0) {
      for (std::uint32_t k = node.first; k < node.first + node.count; ++k)
        if (geometry::boxes_overlap(obstacles_.boxes[order_[k]], box)) return true;
      return false;
    }
    return find_witness(node.children, box, counters) || find_witness(node.children + 1, box, counters);
  }

  bool test_triangle(std::uint32_t index, const geometry::Triangle& t, const geometry::Box& t_box,
                     const geometry::Box& object_box, StudyCounters& counters) {
    ++counters.nodes_visited;
    const Node& node = nodes_[index];
    if (!geometry::boxes_overlap(node.box, t_box)) return false;
    if (node.children == 0) {
      for (std::uint32_t k = node.first; k < node.first + node.count; ++k) {
        const std::uint32_t o = order_[k];
        // Each triangle sits in one leaf: no triangle is seen twice.
        if (!geometry::boxes_overlap(obstacles_.boxes[o], object_box)) continue;
        if (obstacles_.meets(t, t_box, o, counters)) return true;
      }
      return false;
    }
    const std::uint32_t children = node.children;
    return test_triangle(children, t, t_box, object_box, counters) ||
           test_triangle(children + 1, t, t_box, object_box, counters);
  }

  Obstacles obstacles_;
  RTreeOptions options_;
  std::vector<Node> nodes_;
  std::vector<std::uint32_t> order_;
  std::vector<Vec3> centroids_;
  unsigned height_ = 0;
  double build_seconds_ = 0;
};

}  // namespace

std::unique_ptr<StudyMethod> make_r_tree_method(std::span<const geometry::Triangle> obstacles,
                                                const RTreeOptions& options) {
  return std::make_unique<RTreeMethod>(obstacles, options);
}

}  // namespace tetrapage::study
