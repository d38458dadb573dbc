#include "tetrapage/runtime/ObjectGroup.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "ContainmentCheck.h"
#include "PlacedObject.h"
#include "StepClock.h"
#include "tetrapage/formats/Error.h"
#include "tetrapage/runtime/geometry/TriangleTriangle.h"

namespace tetrapage {

namespace {

// One object of a pair: its model and its placement at the step's pose.
struct PairSide {
  const ObjectModel& model;
  PlacedObject& placed;
  const geometry::Box& world_box;
};

// The two objects' frames seen from each other: x_second = M x_first + d and back, x_first =
// M^T x_second + e, computed in double and rounded, so node boxes are compared with a margin
// far beyond those roundings and the placements' (the comparison only prunes: each triangle
// pair is decided on world vertices). A box of one, taken into the other's frame, must meet
// the other's box, and the other way round: the six face axes of a separating-axis test.
class RelativeFrame {
 public:
  RelativeFrame(const PairSide& first, const PairSide& second) {
    const auto& ra = first.placed.rotation();
    const auto& rb = second.placed.rotation();
    const Vec3& ta = first.placed.translation();
    const Vec3& tb = second.placed.translation();
    // world = R x + t for both, so x_second = Rb^T (Ra x_first + ta - tb).
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j)
        to_second_.m[3 * i + j] = rb[i] * ra[j] + rb[3 + i] * ra[3 + j] + rb[6 + i] * ra[6 + j];
      to_second_.d[i] =
          rb[i] * (ta[0] - tb[0]) + rb[3 + i] * (ta[1] - tb[1]) + rb[6 + i] * (ta[2] - tb[2]);
    }
    // And x_first = Ra^T (Rb x_second + tb - ta).
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) to_first_.m[3 * i + j] = to_second_.m[3 * j + i];
      to_first_.d[i] =
          ra[i] * (tb[0] - ta[0]) + ra[3 + i] * (tb[1] - ta[1]) + ra[6 + i] * (tb[2] - ta[2]);
    }
    for (Map* map : {&to_second_, &to_first_})
      for (int k = 0; k < 9; ++k) map->abs_m[k] = std::fabs(map->m[k]);
    const double magnitude =
        first.model.radius + second.model.radius +
        3 * (first.placed.translation_magnitude() + second.placed.translation_magnitude());
    margin_ = magnitude * 0x1p-40;
  }

  // Can a point of `mine` (first frame) lie in `theirs` (second frame)? Conservative.
  bool boxes_meet(const geometry::Box& mine, const geometry::Box& theirs) const {
    return lands_in(to_second_, mine, theirs) && lands_in(to_first_, theirs, mine);
  }

 private:
  struct Map {
    std::array<double, 9> m{}, abs_m{};
    Vec3 d{};
  };

  // Does the box `from`, mapped by `map` (grown by the margin), meet the box `to`?
  bool lands_in(const Map& map, const geometry::Box& from, const geometry::Box& to) const {
    const Vec3 c{(from.lo[0] + from.hi[0]) / 2, (from.lo[1] + from.hi[1]) / 2,
                 (from.lo[2] + from.hi[2]) / 2};
    const Vec3 h{(from.hi[0] - from.lo[0]) / 2, (from.hi[1] - from.lo[1]) / 2,
                 (from.hi[2] - from.lo[2]) / 2};
    for (int i = 0; i < 3; ++i) {
      const double centre =
          map.m[3 * i] * c[0] + map.m[3 * i + 1] * c[1] + map.m[3 * i + 2] * c[2] + map.d[i];
      const double half = map.abs_m[3 * i] * h[0] + map.abs_m[3 * i + 1] * h[1] +
                          map.abs_m[3 * i + 2] * h[2] + margin_;
      if (centre - half > to.hi[i] || centre + half < to.lo[i]) return false;
    }
    return true;
  }

  Map to_second_, to_first_;
  double margin_ = 0;
};

// Both BVHs descended together; each pair of triangles in leaves that meet, and whose placed
// boxes meet, decided by the exact test on both placed triangles. `found(first_triangle,
// second_triangle)` returns whether to go on.
template <class Found>
void find_triangle_pairs(const PairSide& first, const PairSide& second, GroupCounters& counters,
                         Found&& found) {
  const RelativeFrame frame(first, second);
  first.model.bvh.for_each_pair(
      second.model.bvh,
      [&](const geometry::Box& mine, const geometry::Box& theirs) {
        return frame.boxes_meet(mine, theirs);
      },
      [&](std::uint32_t a, std::uint32_t b) {
        ++counters.candidates;
        const geometry::Triangle ta = first.placed.world_triangle(a);
        const geometry::Triangle tb = second.placed.world_triangle(b);
        if (!geometry::boxes_overlap(geometry::box_of(ta), geometry::box_of(tb))) return true;
        ++counters.triangle_tests;
        return !geometry::triangles_intersect(ta, tb) || found(a, b);
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
