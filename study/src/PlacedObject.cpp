#include "tetrapage/study/PlacedObject.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/convex_hull_3.h>

#include <algorithm>

#include "tetrapage/formats/base/Error.h"

namespace tetrapage::study {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;

// The vertices of the convex hull; every vertex when they are coplanar (no 3D hull).
std::vector<Vec3> hull_vertices(std::vector<Vec3> points) {
  std::sort(points.begin(), points.end());
  points.erase(std::unique(points.begin(), points.end()), points.end());
  if (points.size() < 5) return points;
  std::vector<Kernel::Point_3> input;
  input.reserve(points.size());
  for (const auto& p : points) input.emplace_back(p[0], p[1], p[2]);
  std::vector<Kernel::Point_3> extreme;
  CGAL::extreme_points_3(input, std::back_inserter(extreme));
  if (extreme.size() < 4) return points;
  std::vector<Vec3> hull;
  hull.reserve(extreme.size());
  for (const auto& p : extreme) hull.push_back({p.x(), p.y(), p.z()});
  return hull;
}

}  // namespace

PlacedObject::PlacedObject(const TriangleSoup& object) {
  if (object.triangle_count() == 0) throw InputError("flying object: no triangles");
  std::vector<Vec3> vertices;
  local_.reserve(object.triangle_count());
  for (std::size_t t = 0; t < object.triangle_count(); ++t) {
    const auto c = object.corners(t);
    if (!geometry::is_finite(c))
      throw InputError("flying object: triangle " + std::to_string(t) + " has a non-finite coordinate");
    local_.push_back(c);
    vertices.insert(vertices.end(), c.begin(), c.end());
  }
  hull_ = hull_vertices(std::move(vertices));
  place(Pose{});
}

void PlacedObject::place(const Pose& pose) {
  rotation_ = rotation_matrix(pose.rotation);
  translation_ = pose.translation;
  box_ = geometry::Box{};
  for (const auto& v : hull_) box_.extend(apply_pose(rotation_, translation_, v));
  transformed_ = false;
}

void PlacedObject::transform() const {
  world_.resize(local_.size());
  world_boxes_.resize(local_.size());
  for (std::size_t t = 0; t < local_.size(); ++t) {
    for (int k = 0; k < 3; ++k) world_[t][k] = apply_pose(rotation_, translation_, local_[t][k]);
    world_boxes_[t] = geometry::box_of(world_[t]);
  }
  transformed_ = true;
}

std::span<const geometry::Triangle> PlacedObject::triangles() const {
  if (!transformed_) transform();
  return world_;
}

std::span<const geometry::Box> PlacedObject::triangle_boxes() const {
  if (!transformed_) transform();
  return world_boxes_;
}

}  // namespace tetrapage::study
