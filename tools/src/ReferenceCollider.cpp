#include "tetrapage/tools/ReferenceCollider.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <vector>

#include "tetrapage/formats/Error.h"

namespace tetrapage {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Ray = Kernel::Ray_3;
using TriangleIterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, TriangleIterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

Point to_point(const Vec3& v) { return Point(v[0], v[1], v[2]); }

// Directions with no rational relation to the axes or each other; a parity is the majority
// of the three, so that one ray grazing an edge cannot decide alone.
const std::array<Kernel::Vector_3, 3> kParityDirections{Kernel::Vector_3(0.01234567890123, 0.03456789012345, 1.0),
                                                        Kernel::Vector_3(0.7071067811865, -0.5772156649015, 0.2718281828459),
                                                        Kernel::Vector_3(-0.4142135623731, 0.6180339887499, -0.5)};

// Exact closedness per part (the oracle does not share EdgeParity's hashing): every edge, an
// unordered pair of vertex positions, is used an even number of times.
std::vector<bool> closed_by_edge_count(const TriangleSoup& soup) {
  std::vector<std::vector<std::array<Vec3, 2>>> edges(std::max<std::size_t>(1, soup.part_count()));
  for (std::size_t t = 0; t < soup.triangle_count(); ++t) {
    const auto c = soup.corners(t);
    auto& list = edges[soup.part_of.empty() ? 0 : soup.part_of[t]];
    for (int k = 0; k < 3; ++k) {
      std::array<Vec3, 2> edge{c[k], c[(k + 1) % 3]};
      for (auto& p : edge)
        for (auto& x : p) x = x == 0.0 ? 0.0 : x;
      if (edge[1] < edge[0]) std::swap(edge[0], edge[1]);
      list.push_back(edge);
    }
  }
  std::vector<bool> closed(edges.size(), true);
  for (std::size_t part = 0; part < edges.size(); ++part) {
    auto& list = edges[part];
    std::sort(list.begin(), list.end());
    for (std::size_t i = 0; i < list.size();) {
      std::size_t j = i;
      while (j < list.size() && list[j] == list[i]) ++j;
      if ((j - i) % 2 == 1) closed[part] = false;
      i = j;
    }
  }
  return closed;
}

}  // namespace

class ReferenceCollider::Impl {
 public:
  Impl(const TriangleSoup& environment, const TriangleSoup& object) {
    if (environment.triangles.empty())
      throw InputError("reference collider: the environment has no triangle");
    if (object.triangles.empty()) throw InputError("reference collider: the object has no triangle");
    environment_closed_ = closed_by_edge_count(environment);
    object_closed_ = closed_by_edge_count(object).front();
    environment_triangles_.reserve(environment.triangles.size());
    environment_part_.reserve(environment.triangles.size());
    for (std::size_t t = 0; t < environment.triangles.size(); ++t) {
      const auto c = environment.corners(t);
      environment_triangles_.emplace_back(to_point(c[0]), to_point(c[1]), to_point(c[2]));
      environment_part_.push_back(environment.part_of.empty() ? 0 : environment.part_of[t]);
    }
    environment_bounds_ = environment.bounds();
    environment_tree_.rebuild(environment_triangles_.begin(), environment_triangles_.end());
    environment_tree_.build();  // now, not lazily inside the first (concurrent) query
    object_vertices_ = object.vertices;
    object_triangles_ = object.triangles;
    for (const auto& v : object_vertices_) {
      object_radius_ = std::max(object_radius_, std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]));
      object_local_box_.extend(v);
    }
  }

  // The object placed at `pose`, its box, and the environment triangles that meet the box.
  void place(const Pose& pose, std::vector<Point>& placed, BoundingBox& box,
             std::vector<Tree::Primitive_id>& candidates) const {
    const auto rotation = rotation_matrix(pose.rotation);
    placed.reserve(object_vertices_.size());
    for (const auto& v : object_vertices_) {
      const Vec3 w = apply_pose(rotation, pose.translation, v);
      box.extend(w);
      placed.push_back(to_point(w));
    }
    const CGAL::Bbox_3 object_box(box.lo[0], box.lo[1], box.lo[2], box.hi[0], box.hi[1], box.hi[2]);
    environment_tree_.all_intersected_primitives(object_box, std::back_inserter(candidates));
  }

  bool surfaces_touch(const Pose& pose) const {
    std::vector<Point> placed;
    BoundingBox box;
    std::vector<Tree::Primitive_id> candidates;
    place(pose, placed, box, candidates);
    return !candidates.empty() && surfaces_touch(placed, candidates);
  }

  Answer query(const Pose& pose) const {
    Answer answer;
    std::vector<Point> placed;
    BoundingBox box;
    std::vector<Tree::Primitive_id> candidates;
    place(pose, placed, box, candidates);
    answer.candidates = candidates.size();
    if (!candidates.empty()) answer.surfaces_touch = surfaces_touch(placed, candidates);
    if (!answer.surfaces_touch) answer.object_inside = inside(placed[object_triangles_.front()[0]]);
    if (!answer.surfaces_touch && !answer.object_inside && object_closed_)
      answer.obstacle_inside = obstacle_inside(placed, box, candidates, pose);
    answer.collides = answer.surfaces_touch || answer.object_inside || answer.obstacle_inside;
    return answer;
  }

  // Inside some closed part: per part, the majority of three ray parities.
  bool inside(const Point& p) const {
    std::map<std::uint32_t, int> votes;
    for (const auto& direction : kParityDirections) {
      std::vector<Tree::Primitive_id> hits;
      environment_tree_.all_intersected_primitives(Ray(p, direction), std::back_inserter(hits));
      std::map<std::uint32_t, int> crossings;
      for (const auto& id : hits) {
        const std::uint32_t part = environment_part_[std::size_t(id - environment_triangles_.begin())];
        if (environment_closed_[part]) ++crossings[part];
      }
      for (const auto& [part, count] : crossings) votes[part] += count % 2;
    }
    for (const auto& [part, odd] : votes)
      if (odd >= 2) return true;
    return false;
  }

  // Some environment triangle inside the closed object: only candidates whose box lies in the
  // object's box can be; with no surface contact, one vertex decides for its whole triangle.
  bool obstacle_inside(const std::vector<Point>& placed, const BoundingBox& box,
                       const std::vector<Tree::Primitive_id>& candidates, const Pose& pose) const {
    // Distinct first vertices of the enclosed candidates that also lie in the object's own box
    // (taken back to its frame with a margin far beyond the rounding: it only prunes).
    const auto rotation = rotation_matrix(pose.rotation);
    std::vector<Vec3> points;
    for (const auto& id : candidates) {
      const CGAL::Bbox_3 b = id->bbox();
      if (b.xmin() < box.lo[0] || b.ymin() < box.lo[1] || b.zmin() < box.lo[2] || b.xmax() > box.hi[0] ||
          b.ymax() > box.hi[1] || b.zmax() > box.hi[2])
        continue;
      const Point& v = id->vertex(0);
      const Vec3 p{v.x(), v.y(), v.z()};
      Vec3 local{};
      double magnitude = object_radius_;
      for (int a = 0; a < 3; ++a) magnitude += std::fabs(p[a]) + std::fabs(pose.translation[a]);
      bool near = true;
      for (int a = 0; a < 3; ++a) {
        for (int r = 0; r < 3; ++r) local[a] += rotation[3 * r + a] * (p[r] - pose.translation[r]);
        near = near && local[a] >= object_local_box_.lo[a] - magnitude * 0x1p-30 &&
               local[a] <= object_local_box_.hi[a] + magnitude * 0x1p-30;
      }
      if (near) points.push_back(p);
    }
    if (points.empty()) return false;
    std::sort(points.begin(), points.end());
    points.erase(std::unique(points.begin(), points.end()), points.end());
    // The placed object's tree, built only for a pose that needs it.
    std::vector<Triangle> placed_triangles;
    placed_triangles.reserve(object_triangles_.size());
    for (const auto& tri : object_triangles_) placed_triangles.emplace_back(placed[tri[0]], placed[tri[1]], placed[tri[2]]);
    const Tree object_tree(placed_triangles.begin(), placed_triangles.end());
    for (const auto& p : points) {
      int odd = 0;
      for (const auto& direction : kParityDirections)
        odd += object_tree.number_of_intersected_primitives(Ray(to_point(p), direction)) % 2;
      if (odd >= 2) return true;
    }
    return false;
  }

  BoundingBox object_bounds(const Pose& pose) const {
    const auto rotation = rotation_matrix(pose.rotation);
    BoundingBox box;
    for (const auto& v : object_vertices_) box.extend(apply_pose(rotation, pose.translation, v));
    return box;
  }

  const BoundingBox& environment_bounds() const { return environment_bounds_; }
  double object_radius() const { return object_radius_; }

 private:
  bool surfaces_touch(const std::vector<Point>& placed,
                      const std::vector<Tree::Primitive_id>& candidates) const {
    CGAL::Bbox_3 candidates_box;
    std::vector<std::pair<CGAL::Bbox_3, const Triangle*>> near;
    near.reserve(candidates.size());
    for (const auto& id : candidates) {
      const Triangle& t = *id;
      near.emplace_back(t.bbox(), &t);
      candidates_box += t.bbox();
    }
    for (const auto& tri : object_triangles_) {
      const Triangle placed_triangle(placed[tri[0]], placed[tri[1]], placed[tri[2]]);
      const CGAL::Bbox_3 box = placed_triangle.bbox();
      if (!CGAL::do_overlap(box, candidates_box)) continue;
      for (const auto& [candidate_box, candidate] : near) {
        if (!CGAL::do_overlap(box, candidate_box)) continue;
        if (CGAL::do_intersect(placed_triangle, *candidate)) return true;
      }
    }
    return false;
  }

  std::vector<Triangle> environment_triangles_;
  std::vector<std::uint32_t> environment_part_;
  std::vector<bool> environment_closed_;
  bool object_closed_ = false;
  BoundingBox object_local_box_;  // the object's vertices in its own frame
  Tree environment_tree_;
  BoundingBox environment_bounds_;
  std::vector<Vec3> object_vertices_;
  std::vector<TriangleIndices> object_triangles_;
  double object_radius_ = 0.0;
};

ReferenceCollider::ReferenceCollider(const TriangleSoup& environment, const TriangleSoup& object)
    : impl_(std::make_unique<Impl>(environment, object)) {}
ReferenceCollider::~ReferenceCollider() = default;
ReferenceCollider::ReferenceCollider(ReferenceCollider&&) noexcept = default;
ReferenceCollider& ReferenceCollider::operator=(ReferenceCollider&&) noexcept = default;

ReferenceCollider::Answer ReferenceCollider::query(const Pose& pose) const {
  return impl_->query(pose);
}
bool ReferenceCollider::surfaces_touch(const Pose& pose) const { return impl_->surfaces_touch(pose); }
bool ReferenceCollider::inside_environment(const Vec3& p) const {
  return impl_->inside(to_point(p));
}
BoundingBox ReferenceCollider::object_bounds(const Pose& pose) const {
  return impl_->object_bounds(pose);
}
const BoundingBox& ReferenceCollider::environment_bounds() const {
  return impl_->environment_bounds();
}
double ReferenceCollider::object_radius() const { return impl_->object_radius(); }

}  // namespace tetrapage
