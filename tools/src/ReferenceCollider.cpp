#include "tetrapage/tools/ReferenceCollider.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <cmath>
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

// A direction with no rational relation to the axes, so that rays from generated points
// almost never graze an edge; mostly +z so that "below a terrain" reads as inside.
const Kernel::Vector_3 kParityDirection(0.01234567890123, 0.03456789012345, 1.0);

}  // namespace

class ReferenceCollider::Impl {
 public:
  Impl(const TriangleSoup& environment, const TriangleSoup& object) {
    if (environment.triangles.empty())
      throw InputError("reference collider: the environment has no triangle");
    if (object.triangles.empty()) throw InputError("reference collider: the object has no triangle");
    environment_triangles_.reserve(environment.triangles.size());
    for (std::size_t t = 0; t < environment.triangles.size(); ++t) {
      const auto c = environment.corners(t);
      environment_triangles_.emplace_back(to_point(c[0]), to_point(c[1]), to_point(c[2]));
    }
    environment_bounds_ = environment.bounds();
    environment_tree_.rebuild(environment_triangles_.begin(), environment_triangles_.end());
    environment_tree_.build();  // now, not lazily inside the first (concurrent) query
    object_vertices_ = object.vertices;
    object_triangles_ = object.triangles;
    for (const auto& v : object_vertices_)
      object_radius_ = std::max(object_radius_, std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]));
  }

  Answer query(const Pose& pose) const {
    Answer answer;
    const std::vector<Point> placed = place(pose);
    answer.surfaces_touch = placed_surfaces_touch(placed, &answer.candidates);
    if (!answer.surfaces_touch) answer.object_inside = inside(placed.front());
    answer.collides = answer.surfaces_touch || answer.object_inside;
    return answer;
  }

  bool surfaces_touch(const Pose& pose) const { return placed_surfaces_touch(place(pose), nullptr); }

  bool inside(const Point& p) const {
    return environment_tree_.number_of_intersected_primitives(Ray(p, kParityDirection)) % 2 == 1;
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
  std::vector<Point> place(const Pose& pose) const {
    const auto rotation = rotation_matrix(pose.rotation);
    std::vector<Point> placed;
    placed.reserve(object_vertices_.size());
    for (const auto& v : object_vertices_) placed.push_back(to_point(apply_pose(rotation, pose.translation, v)));
    return placed;
  }

  bool placed_surfaces_touch(const std::vector<Point>& placed, std::uint64_t* candidate_count) const {
    CGAL::Bbox_3 object_box;  // exact: the placed coordinates are doubles
    for (const auto& p : placed) object_box += p.bbox();
    std::vector<Tree::Primitive_id> candidates;
    environment_tree_.all_intersected_primitives(object_box, std::back_inserter(candidates));
    if (candidate_count != nullptr) *candidate_count = candidates.size();
    return !candidates.empty() && candidates_touch(placed, candidates);
  }

  bool candidates_touch(const std::vector<Point>& placed,
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
