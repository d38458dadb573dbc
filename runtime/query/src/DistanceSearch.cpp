#include "DistanceSearch.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "tetrapage/runtime/paging/Shard.h"
#include "tetrapage/runtime/query/FlyingObject.h"

namespace tetrapage {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// Far beyond the rounding of a gap computed in double: what the pruning tests leave out.
bool beyond(double lower_bound, double reach) { return lower_bound * (1 - 0x1p-40) > reach; }

}  // namespace

void DistanceSearch::measure(const ObjectModel& model, PlacedObject& object,
                             const geometry::Box& world_box, double max_distance,
                             const DynamicObstacles* obstacles, DistanceResult& result) {
  // A changed overlay may have moved or hidden the last pair's triangle.
  const std::uint64_t version = obstacles ? obstacles->version() : 0;
  if (obstacles != obstacles_ || version != obstacles_version_) has_last_ = false;
  obstacles_ = obstacles;
  obstacles_version_ = version;
  model_ = &model;
  object_ = &object;
  world_box_ = world_box;
  result_ = &result;
  reach_ = max_distance;
  lowest_bound_ = kInfinity;
  lowest_upper_ = kInfinity;
  found_ = false;
  axis_ = {0, 0, 0};
  // The bounding ball prunes far better than the world box when the object is far away.
  ball_centre_ = apply_pose(object.rotation(), object.translation(), model.ball_centre);
  ball_radius_ = model.ball_radius * (1 + 0x1p-30) +
                 (model.radius + model.ball_radius + object.translation_magnitude()) * 0x1p-40;
  if (has_last_) {
    // The last closest pair, at this pose: an upper bound that usually confines the search to
    // a thin shell around the object.
    result.from_last_pair = true;
    ++result.pair_tests;
    const Pair last = last_;
    offer(geometry::triangle_distance(last.environment,
                                      object.world_triangle(last.site.object_triangle)),
          last.environment, last.site.environment_triangle, last.site.environment_part,
          last.site.object_triangle, last.site.dynamic_part);
  }
  // Without a bound yet, a radius grown until it holds some triangle; then the triangles
  // within the best distance found.
  double radius = std::isfinite(reach_)
                      ? reach_
                      : std::max(0.25 * geometry::extent(world_box), std::numeric_limits<double>::min());
  for (;;) {
    const geometry::Box search_box = geometry::inflated(world_box, radius);
    measure_within(search_box);
    if (reach_ <= radius || geometry::box_contains(search_box, index_->mesh_bounds())) break;
    radius = found_ ? reach_ : 2 * radius;
  }
  if (obstacles) measure_dynamic_parts(*obstacles);
  report(max_distance);
}

void DistanceSearch::report(double max_distance) {
  DistanceResult& result = *result_;
  if (!found_ || lowest_bound_ > max_distance) {
    // Every pair within max_distance was measured: none is.
    result.separation = Separation::farther;
    result.distance = result.lower_bound = max_distance;
    result.upper_bound = kInfinity;
    has_last_ = found_;
    if (found_) last_ = best_;
    return;
  }
  result.separation = Separation::apart;
  result.distance = best_.distance.distance;
  result.lower_bound = std::min(lowest_bound_, result.distance);
  result.upper_bound = std::max(lowest_upper_, result.distance);
  result.on_environment = best_.distance.on_first;
  result.on_object = best_.distance.on_second;
  result.closest = best_.site;
  has_last_ = true;
  last_ = best_;
}

void DistanceSearch::measure_within(const geometry::Box& search_box) {
  met_.clear();
  if (!geometry::boxes_overlap(search_box, index_->mesh_bounds())) return;
  StepCounters ignored;
  const bool located = region_.contains(search_box) || region_.search(search_box, std::nullopt, ignored);
  if (!located) {
    // The box's centre lies beyond the convex coarse mesh: its shards, by their bounds.
    for (std::uint32_t shard = 0; shard < index_->shard_count(); ++shard) {
      const geometry::Box& bounds = index_->shard_bounds(shard);
      if (!geometry::boxes_overlap(search_box, bounds) ||
          beyond(geometry::box_distance_lower_bound(bounds, world_box_), reach_))
        continue;
      const ShardPin pin = index_->cache().acquire(shard);
      collect_shard(*pin, search_box);
      measure_pending();
    }
    return;
  }
  for (std::size_t k = 0; k < region_.size(); ++k) {
    if (!geometry::boxes_overlap(search_box, region_.reach(k)) ||
        beyond(geometry::box_distance_lower_bound(region_.reach(k), world_box_), reach_))
      continue;
    ShardPin local_pin;
    collect_shard(region_.acquire(k, local_pin, ignored), search_box);
    measure_pending();
  }
}

double DistanceSearch::lower_bound_to(const geometry::Box& box) const {
  geometry::Box ball;
  for (int a = 0; a < 3; ++a) ball.lo[a] = ball.hi[a] = ball_centre_[a];
  return std::max(geometry::box_distance_lower_bound(box, world_box_),
                  geometry::box_distance_lower_bound(box, ball) - ball_radius_);
}

void DistanceSearch::measure_pending() {
  // Nearest first: the reach shrinks soonest, and the rest is cut off at once.
  std::sort(pending_.begin(), pending_.end(),
            [](const Pending& a, const Pending& b) { return a.lower_bound < b.lower_bound; });
  for (const Pending& candidate : pending_) {
    if (beyond(candidate.lower_bound, reach_)) break;
    if (geometry::triangle_outside_ball(candidate.environment, ball_centre_, ball_radius_ + reach_)) continue;
    measure_triangle(candidate.environment, candidate.id, candidate.part, 0);
  }
  pending_.clear();
}

void DistanceSearch::collect_shard(const Shard& shard, const geometry::Box& search_box) {
  // Exact and double copies of a triangle are the same in every shard: measured once.
  const bool same_copies =
      index_->stores_input_coordinates() || shard.precision() == StoredPrecision::float64;
  auto near = [this](const geometry::Box& node_box, std::uint32_t) {
    return !beyond(lower_bound_to(node_box), reach_);
  };
  auto visit = [&](std::uint32_t local, const geometry::Triangle& environment) {
    const std::uint64_t id = shard.triangle_id(local);
    if (same_copies && !met_.insert(id)) return;
    const std::uint32_t part = index_->component_part(shard.component_id(local));
    if (obstacles_ && obstacles_->hidden(part)) return;
    const double lower_bound = lower_bound_to(geometry::box_of(environment));
    if (beyond(lower_bound, reach_)) return;
    pending_.push_back({lower_bound, environment, id, part});
  };
  shard.for_each_box_candidate(search_box, near, visit);
}

void DistanceSearch::measure_dynamic_parts(const DynamicObstacles& obstacles) {
  auto measure_part = [&](const DynamicObstacles::Part& part) {
    if (beyond(lower_bound_to(part.world_box), reach_)) return true;
    const TriangleSoup& mesh = part.model->mesh;
    const auto rotation = rotation_matrix(part.pose.rotation);
    for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
      geometry::Triangle placed;
      for (int c = 0; c < 3; ++c)
        placed[c] = apply_pose(rotation, part.pose.translation, mesh.vertices[mesh.triangles[t][c]]);
      if (beyond(lower_bound_to(geometry::box_of(placed)), reach_) ||
          geometry::triangle_outside_ball(placed, ball_centre_, ball_radius_ + reach_))
        continue;
      measure_triangle(placed, t, Contact::kDynamicPart, part.id);
    }
    return true;
  };
  // Without a bound yet (nothing in the index), every part; else those within reach.
  if (!std::isfinite(reach_)) {
    for (const DynamicObstacles::Part& part : obstacles.parts()) measure_part(part);
    return;
  }
  obstacles.for_each_in_box(geometry::inflated(world_box_, reach_), measure_part);
}

void DistanceSearch::measure_triangle(const geometry::Triangle& environment, std::uint64_t id,
                                      std::uint32_t part, std::uint32_t dynamic_part) {
  ++result_->candidates;
  // The triangle in the object's frame, its box grown far beyond the frame change's rounding:
  // the BVH prunes by distances there, and every pair is measured on world coordinates.
  geometry::Box framed;
  double margin = 0;
  for (const geometry::Point& corner : environment) {
    framed.extend(object_->to_object_frame(corner));
    margin = std::max(margin, object_->frame_margin(corner));
  }
  framed = geometry::inflated(framed, margin);
  // The best pair's direction, in the object's frame: object nodes that lie beyond the
  // triangle along it by more than the reach are pruned.
  const Vec3 axis = object_->direction_to_object_frame(axis_);
  const double axis_length = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  double triangle_reach = -kInfinity;  // the triangle's farthest extent along the axis
  for (const geometry::Point& corner : environment) {
    const Vec3 x = object_->to_object_frame(corner);
    triangle_reach = std::max(triangle_reach, axis[0] * x[0] + axis[1] * x[1] + axis[2] * x[2]);
  }
  auto node_beyond = [&](const geometry::Box& node, double reach) {
    if (!(axis_length > 0)) return false;
    double nearest = 0;  // the node's least extent along the axis
    for (int a = 0; a < 3; ++a) nearest += axis[a] * (axis[a] > 0 ? node.lo[a] : node.hi[a]);
    // Margins far beyond the roundings of the frame change and of these sums.
    const double slack = (margin + 0x1p-40 * (std::fabs(nearest) + std::fabs(triangle_reach))) * axis_length;
    return nearest - triangle_reach - slack > reach * axis_length * (1 + 0x1p-40);
  };
  model_->bvh.for_each_near(
      framed, node_beyond, [this] { return reach_; },
      [&](std::uint32_t object_triangle) {
        const geometry::Triangle placed = object_->world_triangle(object_triangle);
        if (geometry::farther_than_cheaply(environment, placed, reach_, axis_)) return true;
        ++result_->pair_tests;
        offer(geometry::triangle_distance(environment, placed), environment, id, part, object_triangle,
              dynamic_part);
        return true;
      });
}

void DistanceSearch::offer(const geometry::TriangleDistance& distance,
                           const geometry::Triangle& environment, std::uint64_t id,
                           std::uint32_t part, std::uint32_t object_triangle,
                           std::uint32_t dynamic_part) {
  lowest_bound_ = std::min(lowest_bound_, distance.lower_bound);
  lowest_upper_ = std::min(lowest_upper_, distance.upper_bound);
  // No pair farther than a pair's upper bound can be the closest.
  reach_ = std::min(reach_, distance.upper_bound);
  if (found_ && distance.distance >= best_.distance.distance) return;
  found_ = true;
  best_ = {
      distance, environment, {part, id, object_triangle, ContactSite::kNoComponent, dynamic_part}};
  for (int a = 0; a < 3; ++a) axis_[a] = distance.on_second[a] - distance.on_first[a];
}

}  // namespace tetrapage
