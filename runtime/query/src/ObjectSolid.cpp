#include "ObjectSolid.h"

#include <algorithm>
#include <cmath>

#include "tetrapage/runtime/geometry/TriangleBox.h"
#include "tetrapage/runtime/geometry/TriangleTriangle.h"

namespace tetrapage {
namespace {

using hull::hull_of;
using hull::to_point;

// How far the placement (apply_pose) may move a vertex, relative to the object's radius plus
// the translation's magnitude, taken far beyond the few ulps it really moves: a vertex deeper
// inside the object's hull than this cannot reach the hull of the placed hull vertices.
constexpr double kPlacementReach = 0x1p-36;

}  // namespace

void ObjectSolid::build(const QueryOptions& options, const ObjectModel& model, PlacedObject& object,
                        const Coherence& coherence) {
  built = true;
  faces.clear();
  face_boxes.clear();
  outside = geometry::Sign::zero;
  const bool swept = options.motion == Motion::swept && coherence.has_previous();
  if (options.shape == ObjectShape::box) {
    kind = Kind::box;
    box = coherence.current_box();
    if (swept) box.extend(coherence.previous_box());
    return;
  }
  kind = Kind::hull;
  const ObjectModel::HullCandidates& candidates = model.hull_candidates();
  // The hull candidates at each pose: the object's hull vertices and the vertices within the
  // placement's reach of its surface.
  auto magnitude = [&](const Vec3& t) {
    return model.radius + std::max({std::fabs(t[0]), std::fabs(t[1]), std::fabs(t[2])});
  };
  double reach = magnitude(object.translation());
  if (swept) reach = std::max(reach, magnitude(coherence.previous_translation()));
  reach *= kPlacementReach;
  points.clear();
  auto add_pose = [&](bool current) {
    auto add = [&](std::uint32_t v) {
      const Vec3 p = current ? object.world_vertex(v)
                             : apply_pose(coherence.previous_rotation(),
                                          coherence.previous_translation(), model.mesh.vertices[v]);
      points.emplace_back(p[0], p[1], p[2]);
    };
    for (const auto v : candidates.on_hull) add(v);
    for (const auto& [depth, v] : candidates.near_hull) {
      if (depth > reach) break;
      add(v);
    }
  };
  add_pose(true);
  if (swept) add_pose(false);
  std::sort(points.begin(), points.end());
  points.erase(std::unique(points.begin(), points.end()), points.end());
  hull_points.clear();
  hull_faces.clear();
  if (points.size() >= 4) hull_of(points, hull_points, hull_faces);
  for (const auto& f : hull_faces)
    faces.push_back(
        {to_point(hull_points[f[0]]), to_point(hull_points[f[1]]), to_point(hull_points[f[2]])});
  if (faces.empty()) {
    // Fewer than four points, or no hull: the placed triangles stand for themselves.
    for (std::uint32_t t = 0; t < model.mesh.triangle_count(); ++t)
      faces.push_back(object.world_triangle(t));
  } else {
    // CGAL orients every facet the same way: the first vertex off facet 0 names the inside.
    const auto& f = faces[0];
    for (const auto& p : hull_points) {
      const geometry::Sign s = geometry::orient3d(f[0], f[1], f[2], to_point(p));
      if (s != geometry::Sign::zero) {
        outside = -s;
        break;
      }
    }
  }
  box = {};
  for (const auto& face : faces) {
    face_boxes.push_back(geometry::box_of(face));
    box.extend(face_boxes.back());
  }
}

bool ObjectSolid::collides(const geometry::Triangle& environment,
                           const geometry::Accuracy& accuracy, double reach) const {
  if (kind == Kind::box) return geometry::triangle_collides_with_box(environment, box, accuracy);
  geometry::Box near = geometry::box_of(environment);
  if (reach > 0) near = geometry::inflated(near, reach);
  if (!geometry::boxes_overlap(near, box)) return false;
  for (std::size_t i = 0; i < faces.size(); ++i)
    if (geometry::boxes_overlap(near, face_boxes[i]) &&
        geometry::triangles_collide(environment, faces[i], accuracy))
      return true;
  // No surface contact: the triangle lies wholly inside or wholly outside; one vertex decides,
  // exactly whatever the accuracy.
  if (outside == geometry::Sign::zero || !geometry::box_contains(box, environment[0])) return false;
  for (const auto& f : faces)
    if (geometry::orient3d(f[0], f[1], f[2], environment[0]) == outside) return false;
  return true;
}

}  // namespace tetrapage
