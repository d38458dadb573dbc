#include "tetrapage/runtime/query/ObjectGroup.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "ContainmentCheck.h"
#include "PairTests.h"
#include "PlacedObject.h"
#include "StepClock.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/runtime/geometry/TriangleTriangle.h"

namespace tetrapage {

namespace {

// One pair whose world boxes overlap: its triangle pairs (the first, or all), else whether
// one holds the other; appended to result.pairs when they collide.
void test_pair(std::uint32_t i, std::uint32_t j, const PairSide& first, const PairSide& second,
               const GroupQueryOptions& options, GroupResult& result) {
  const bool all = options.pair_mode == QueryMode::all_contacts;
  CollidingPair pair{i, j, PairContainment::none, std::uint32_t(result.triangle_pairs.size()), 0};
  find_triangle_pairs(first, second, result.counters, [&](std::uint32_t a, std::uint32_t b) {
    result.triangle_pairs.push_back({a, b});
    return all;
  });
  pair.triangle_pairs_end = std::uint32_t(result.triangle_pairs.size());
  if (pair.triangle_pairs_end > pair.triangle_pairs_begin) {
    std::sort(result.triangle_pairs.begin() + pair.triangle_pairs_begin,
              result.triangle_pairs.end());
  } else if (!options.pair_containment) {
    return;
  } else if (holds_a_component(second, first)) {
    pair.containment = PairContainment::first_inside_second;
  } else if (holds_a_component(first, second)) {
    pair.containment = PairContainment::second_inside_first;
  } else {
    return;
  }
  result.pairs.push_back(pair);
}

}  // namespace

struct ObjectGroup::Parts {
  std::vector<std::shared_ptr<const ObjectModel>> models;
  std::vector<FlyingObject> flying;     ///< one per object, with an index
  std::vector<PlacedObject> placed;     ///< one per object, for the pairs
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

std::size_t ObjectGroup::size() const {
  return parts_->models.size();
}

const std::shared_ptr<const ObjectModel>& ObjectGroup::model(std::size_t object) const {
  return parts_->models.at(object);
}

void ObjectGroup::set_obstacles(std::shared_ptr<const DynamicObstacles> obstacles) {
  if (!index_ && obstacles)
    throw InputError("a group without an index has no environment to add obstacles to");
  for (FlyingObject& flying : parts_->flying) flying.set_obstacles(obstacles);
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
    result.world_boxes[i] = parts_->placed[i].world_box();
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
  // Sort and sweep on x: each object meets the later ones whose boxes start before it ends.
  auto& order = parts_->by_low_x;
  order.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) order[i] = i;
  const auto& boxes = result.world_boxes;
  std::sort(order.begin(), order.end(),
            [&](std::uint32_t a, std::uint32_t b) { return boxes[a].lo[0] < boxes[b].lo[0]; });
  for (std::size_t k = 0; k < n; ++k) {
    for (std::size_t l = k + 1; l < n && boxes[order[l]].lo[0] <= boxes[order[k]].hi[0]; ++l) {
      const std::uint32_t i = std::min(order[k], order[l]), j = std::max(order[k], order[l]);
      if (!geometry::boxes_overlap(boxes[i], boxes[j])) continue;
      ++result.counters.box_pairs;
      const PairSide first{*parts_->models[i], parts_->placed[i], boxes[i]};
      const PairSide second{*parts_->models[j], parts_->placed[j], boxes[j]};
      test_pair(i, j, first, second, options, result);
    }
  }
  std::sort(result.pairs.begin(), result.pairs.end(),
            [](const CollidingPair& a, const CollidingPair& b) {
              return std::pair(a.first, a.second) < std::pair(b.first, b.second);
            });
}

}  // namespace tetrapage
