#include "ContainmentCheck.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "PairTests.h"
#include "tetrapage/runtime/query/ObjectInteriorGrid.h"

namespace tetrapage {

void ContainmentCheck::check(const geometry::Box& box, PlacedObject& object,
                             std::span<const ShardPin> pins, QueryResult& result,
                             Clock::time_point start) {
  check_object_inside_obstacle(object, pins, result);
  if (!result.collides) check_obstacle_inside_object(box, object, result);
  result.counters.interior_seconds = seconds_since(start);
}

void ContainmentCheck::check_object_inside_obstacle(PlacedObject& object,
                                                    std::span<const ShardPin> pins,
                                                    QueryResult& result) {
  // With no surface contact, one vertex of each of the object's components decides for the
  // whole component (it is connected and crosses no surface).
  if (!index_->has_interiors()) return;
  const std::size_t components = model_->component_vertices.size();
  if (interior_memos_.size() != components)
    interior_memos_.assign(components, {}), interior_tets_.assign(components, 0);
  for (std::size_t c = 0; c < components && !result.collides; ++c) {
    const ObstacleQuery inside = locate_in_obstacles(
        *index_, interior_tets_[c], object.world_vertex(model_->component_vertices[c]),
        interior_memos_[c], pins);
    // A hidden part holds nothing. (Where it encloses a visible closed part that holds the
    // object, the walk names one of the two: see DynamicObstacles' limits.)
    if (inside.containment == ObstacleContainment::inside &&
        !(overlay_ != nullptr && overlay_->hidden(index_->component_part(inside.component)))) {
      result.collides = true;
      result.containment = Containment::object_inside_obstacle;
      result.containing_component = inside.component;
      result.containing_part = index_->component_part(inside.component);
    }
  }
}

void ContainmentCheck::check_obstacle_inside_object(const geometry::Box& box, PlacedObject& object,
                                                    QueryResult& result) {
  // An environment component whose box lies in the object's box, touching no object surface,
  // lies wholly inside or wholly outside every closed component of the object: one vertex
  // decides. Most vertices are far from the object's surface, where the interior grid answers
  // at once; the rest need a parity count.
  std::sort(enclosed_.begin(), enclosed_.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  enclosed_.erase(std::unique(enclosed_.begin(), enclosed_.end(),
                              [](const auto& a, const auto& b) { return a.first == b.first; }),
                  enclosed_.end());
  const auto inside = [&](std::uint32_t component) {
    result.collides = true;
    result.containment = Containment::obstacle_inside_object;
    result.containing_component = component;
    result.containing_part = index_->component_part(component);
  };
  std::size_t undecided = 0;
  for (std::size_t i = 0; i < enclosed_.size() && !result.collides; ++i) {
    const geometry::Point& p = enclosed_[i].second;
    switch (model_->interior_grid.classify(object.to_object_frame(p), object.frame_margin(p))) {
      case ObjectInteriorGrid::Side::inside:
        inside(enclosed_[i].first);
        break;
      case ObjectInteriorGrid::Side::outside:
        break;
      case ObjectInteriorGrid::Side::unknown:
        enclosed_[undecided++] = enclosed_[i];
        break;
    }
  }
  enclosed_.resize(undecided);
  for (std::size_t i = 0; i < enclosed_.size() && !result.collides; ++i)
    if (crossing_parity_holds(*model_, object, enclosed_[i].second, box)) inside(enclosed_[i].first);
}

void ContainmentCheck::check_dynamic(const geometry::Box& box, PlacedObject& object,
                                     PlacedObject& placed, bool solid_query, QueryResult& result) {
  if (overlay_ == nullptr || result.collides) return;
  const PairSide flying{*model_, object, box};
  overlay_->for_each_in_box(box, [&](const DynamicObstacles::Part& part) {
    placed.rebind(*part.model);
    placed.place(part.pose);
    const PairSide obstacle{*part.model, placed, part.world_box};
    if (holds_a_component(obstacle, flying))
      result.containment = Containment::object_inside_obstacle;
    else if (!solid_query && holds_a_component(flying, obstacle))
      result.containment = Containment::obstacle_inside_object;
    else
      return true;
    result.collides = true;
    result.containing_part = Contact::kDynamicPart;
    result.containing_component = 0;
    result.containing_dynamic_part = part.id;
    return false;
  });
}

bool crossing_parity_holds(const ObjectModel& model, PlacedObject& object, const geometry::Point& p,
                           const geometry::Box& box) {
  // Parity of crossings with the placed object along a segment from p to beyond the object's
  // box; a direction whose segment meets an edge, a vertex or a plane is replaced by the next.
  // Directions are nearly along the object's own axes, so that the segment's box in the
  // object's frame is thin and the BVH offers few triangles; slanted, so that the segment
  // misses the vertices that generated objects put on their axes.
  static constexpr std::array<std::array<double, 3>, 6> kDirections{
      {{0.0123457, 0.0345679, 0.99932},
       {0.99932, 0.0123457, 0.0345679},
       {0.0345679, 0.99932, 0.0123457},
       {-0.0234567, 0.0156789, -0.99960},
       {-0.99960, -0.0234567, 0.0156789},
       {0.0156789, -0.99960, -0.0234567}}};
  const std::array<double, 9>& rotation = object.rotation();
  const Vec3& translation = object.translation();
  // |d| = 1, so some coordinate moves by reach / sqrt(3) > the box's largest side.
  const double reach =
      2 * std::max({box.hi[0] - box.lo[0], box.hi[1] - box.lo[1], box.hi[2] - box.lo[2]});
  for (const auto& o : kDirections) {
    const Vec3 d{rotation[0] * o[0] + rotation[1] * o[1] + rotation[2] * o[2],
                 rotation[3] * o[0] + rotation[4] * o[1] + rotation[5] * o[2],
                 rotation[6] * o[0] + rotation[7] * o[1] + rotation[8] * o[2]};
    const geometry::Point far{p[0] + d[0] * reach, p[1] + d[1] * reach, p[2] + d[2] * reach};
    const geometry::Segment segment{p, far};
    // The segment's box in the object's frame (rounded: it only prunes), as in phase II.
    geometry::Box query;
    double magnitude = model.radius;
    for (const auto& q : segment) {
      query.extend(object.to_object_frame(q));
      for (int a = 0; a < 3; ++a)
        magnitude = std::max(magnitude, std::fabs(q[a]) + std::fabs(translation[a]));
    }
    const double grow = magnitude * 0x1p-40;
    for (int a = 0; a < 3; ++a) query.lo[a] -= grow, query.hi[a] += grow;
    if (const auto odd = crossing_parity(model.bvh, model.closed_components, segment, query,
                                         [&](std::uint32_t t) { return object.world_triangle(t); }))
      return *odd;
  }
  return false;  // every direction grazed the object: taken as outside
}

}  // namespace tetrapage
