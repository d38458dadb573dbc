#include "tetrapage/runtime/ObjectGroup.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "ContainmentCheck.h"
#include "PlacedObject.h"
#include "StepClock.h"
#include "tetrapage/formats/Error.h"
#include "tetrapage/runtime/geometry/TriangleBox.h"
#include "tetrapage/runtime/geometry/TriangleTriangle.h"

namespace tetrapage {

namespace {

geometry::Box intersection_of(const geometry::Box& a, const geometry::Box& b) {
  geometry::Box out;
  for (int k = 0; k < 3; ++k) {
    out.lo[k] = std::max(a.lo[k], b.lo[k]);
    out.hi[k] = std::min(a.hi[k], b.hi[k]);
  }
  return out;
}

// How far a world point may move when the object's frame change rounds it: far beyond the
// rounding of to_object_frame and of apply_pose (the box it grows only prunes).
double frame_rounding(const ObjectModel& model, const PlacedObject& placed,
                      const geometry::Point& p) {
  double magnitude = model.radius;
  for (int a = 0; a < 3; ++a)
    magnitude = std::max(magnitude, std::fabs(p[a]) + std::fabs(placed.translation()[a]));
  return magnitude * 0x1p-40;
}

// The world points taken into the object's frame: the box of their images, grown beyond the
// rounding. Every object triangle whose placed copy meets the points' hull lies in it.
template <std::size_t N>
geometry::Box box_in_frame(const std::array<geometry::Point, N>& points, const ObjectModel& model,
                           const PlacedObject& placed) {
  geometry::Box framed;
  double grow = 0;
  for (const auto& p : points) {
    framed.extend(placed.to_object_frame(p));
    grow = std::max(grow, frame_rounding(model, placed, p));
  }
  for (int a = 0; a < 3; ++a) framed.lo[a] -= grow, framed.hi[a] += grow;
  return framed;
}

std::array<geometry::Point, 8> corners_of(const geometry::Box& box) {
  std::array<geometry::Point, 8> corners;
  for (int c = 0; c < 8; ++c)
    corners[c] = {(c & 1) ? box.hi[0] : box.lo[0], (c & 2) ? box.hi[1] : box.lo[1],
                  (c & 4) ? box.hi[2] : box.lo[2]};
  return corners;
}

// One object of a pair: its model and its placement at the step's pose.
struct PairSide {
  const ObjectModel& model;
  PlacedObject& placed;
  const geometry::Box& world_box;
};

// The triangles of `probe` near `tree`, each searched in tree's BVH from tree's frame, each
// candidate decided exactly on both placed triangles. `found(probe_triangle, tree_triangle)`
// returns whether to go on.
template <class Found>
void find_triangle_pairs(const PairSide& probe, const PairSide& tree, GroupCounters& counters,
                         Found&& found) {
  // A contact point lies in both placed objects, so in both world boxes.
  const geometry::Box shared = intersection_of(probe.world_box, tree.world_box);
  const geometry::Box probe_query = box_in_frame(corners_of(shared), probe.model, probe.placed);
  bool go_on = true;
  probe.model.bvh.for_each_in_box(probe_query, [&](std::uint32_t p) {
    const geometry::Triangle world = probe.placed.world_triangle(p);
    if (!geometry::triangle_intersects_box(world, shared)) return true;
    ++counters.candidates;
    const geometry::Box tree_query = box_in_frame(world, tree.model, tree.placed);
    tree.model.bvh.for_each_in_box(tree_query, [&](std::uint32_t t) {
      ++counters.triangle_tests;
      if (geometry::triangles_intersect(world, tree.placed.world_triangle(t))) go_on = found(p, t);
      return go_on;
    });
    return go_on;
  });
}

// With no surface contact between them, does a component of `inner` lie inside a closed
// component of `outer`? One vertex decides for its whole component (it crosses no surface of
// outer): the interior grid answers away from outer's surface, a crossing parity elsewhere.
bool holds_a_component(const PairSide& outer, const PairSide& inner) {
  if (!outer.model.closed) return false;
  for (const std::uint32_t v : inner.model.component_vertices) {
    const geometry::Point& p = inner.placed.world_vertex(v);
    if (!geometry::box_contains(outer.world_box, p)) continue;
    switch (outer.model.interior_grid.classify(outer.placed.to_object_frame(p),
                                               outer.placed.frame_margin(p))) {
      case ObjectInteriorGrid::Side::inside:
        return true;
      case ObjectInteriorGrid::Side::outside:
        break;
      case ObjectInteriorGrid::Side::unknown:
        if (crossing_parity_holds(outer.model, outer.placed, p, outer.world_box)) return true;
        break;
    }
  }
  return false;
}

}  // namespace

struct ObjectGroup::Parts {
  std::vector<std::shared_ptr<const ObjectModel>> models;
  std::vector<FlyingObject> flying;  ///< one per object, with an index
  std::vector<PlacedObject> placed;  ///< one per object, for the pairs
  std::vector<std::uint32_t> by_low_x;  ///< the sweep's order
};

ObjectGroup::ObjectGroup(std::shared_ptr<const CollisionIndex> index,
                         std::vector<std::shared_ptr<const ObjectModel>> models)
    : index_(std::move(index)), parts_(std::make_unique<Parts>()) {
  if (models.empty()) throw InputError("an object group needs at least one object");
  if (models.size() >= std::size_t(0xffffffffu))
    throw InputError("an object group holds fewer than 2^32 - 1 objects, not " +
                     std::to_string(models.size()));
  for (std::size_t i = 0; i < models.size(); ++i)
    if (!models[i]) throw InputError("object " + std::to_string(i) + " of the group has no model");
  parts_->placed.reserve(models.size());
  for (const auto& model : models) {
    parts_->placed.emplace_back(*model);
    if (index_) parts_->flying.emplace_back(index_, model);
  }
  parts_->models = std::move(models);
}

ObjectGroup::~ObjectGroup() = default;
ObjectGroup::ObjectGroup(ObjectGroup&&) noexcept = default;
ObjectGroup& ObjectGroup::operator=(ObjectGroup&&) noexcept = default;

std::size_t ObjectGroup::size() const { return parts_->models.size(); }

const std::shared_ptr<const ObjectModel>& ObjectGroup::model(std::size_t object) const {
  return parts_->models.at(object);
}

void ObjectGroup::step(std::span<const Pose> poses, const GroupQueryOptions& options,
                       GroupResult& result) {
  if (poses.size() != size())
    throw InputError("the group has " + std::to_string(size()) + " objects but the step has " +
                     std::to_string(poses.size()) + " poses");
  result.pairs.clear();
  result.triangle_pairs.clear();
  result.counters = {};
  result.world_boxes.resize(size());
  for (std::size_t i = 0; i < size(); ++i) {
    try {
      parts_->placed[i].place(poses[i]);
    } catch (const InputError& e) {
      throw InputError("object " + std::to_string(i) + " of the group: " + e.what());
    }
  }
  const auto start = Clock::now();
  query_environment(poses, options, result);
  result.counters.environment_seconds = seconds_since(start);
  const auto pairs_start = Clock::now();
  if (options.check_pairs) test_pairs(options, result);
  result.counters.pair_seconds = seconds_since(pairs_start);
}

void ObjectGroup::query_environment(std::span<const Pose> poses, const GroupQueryOptions& options,
                                    GroupResult& result) {
  if (!index_ || !options.check_environment) {
    result.environment.clear();
    return;
  }
  result.environment.resize(size());
  // Each FlyingObject is its own: objects run in parallel without sharing anything but the
  // index, which is made for it.
  const auto query = [&](std::size_t i) {
    parts_->flying[i].query(poses[i], options.environment, result.environment[i]);
  };
  if (options.parallel && size() > 1)
    tbb::parallel_for(std::size_t(0), size(), query);
  else
    for (std::size_t i = 0; i < size(); ++i) query(i);
}

void ObjectGroup::test_pairs(const GroupQueryOptions& options, GroupResult& result) {
  const std::size_t n = size();
  for (std::size_t i = 0; i < n; ++i) result.world_boxes[i] = parts_->placed[i].world_box();
  // Sort and sweep on x: each object meets the later ones whose boxes start before it ends.
  auto& order = parts_->by_low_x;
  order.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) order[i] = i;
  const auto& boxes = result.world_boxes;
  std::sort(order.begin(), order.end(),
            [&](std::uint32_t a, std::uint32_t b) { return boxes[a].lo[0] < boxes[b].lo[0]; });
  const bool all = options.pair_mode == QueryMode::all_contacts;
  for (std::size_t k = 0; k < n; ++k) {
    for (std::size_t l = k + 1; l < n && boxes[order[l]].lo[0] <= boxes[order[k]].hi[0]; ++l) {
      const std::uint32_t i = std::min(order[k], order[l]), j = std::max(order[k], order[l]);
      if (!geometry::boxes_overlap(boxes[i], boxes[j])) continue;
      ++result.counters.box_pairs;
      const PairSide first{*parts_->models[i], parts_->placed[i], boxes[i]};
      const PairSide second{*parts_->models[j], parts_->placed[j], boxes[j]};
      CollidingPair pair{i, j, PairContainment::none, std::uint32_t(result.triangle_pairs.size()), 0};
      // The object with fewer triangles probes the other's BVH.
      const bool first_probes = first.model.bvh.triangle_count() < second.model.bvh.triangle_count();
      find_triangle_pairs(first_probes ? first : second, first_probes ? second : first, result.counters,
                          [&](std::uint32_t p, std::uint32_t t) {
                            result.triangle_pairs.push_back(first_probes ? TrianglePair{p, t}
                                                                         : TrianglePair{t, p});
                            return all;
                          });
      pair.triangle_pairs_end = std::uint32_t(result.triangle_pairs.size());
      if (pair.triangle_pairs_end == pair.triangle_pairs_begin && options.pair_containment) {
        if (holds_a_component(second, first))
          pair.containment = PairContainment::first_inside_second;
        else if (holds_a_component(first, second))
          pair.containment = PairContainment::second_inside_first;
        else
          continue;
      } else if (pair.triangle_pairs_end == pair.triangle_pairs_begin) {
        continue;
      }
      std::sort(result.triangle_pairs.begin() + pair.triangle_pairs_begin, result.triangle_pairs.end());
      result.pairs.push_back(pair);
    }
  }
  std::sort(result.pairs.begin(), result.pairs.end(), [](const CollidingPair& a, const CollidingPair& b) {
    return std::pair(a.first, a.second) < std::pair(b.first, b.second);
  });
}

}  // namespace tetrapage
