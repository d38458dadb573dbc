#pragma once
/// @file PairTests.h (private)
/// Two placed rigid meshes against each other, exactly on their placed vertices (apply_pose):
/// their triangle pairs that meet (both BVHs descended together), and whether one holds a
/// component of the other. Shared by ObjectGroup (object against object) and FlyingObject
/// (the object against a dynamic obstacle's containment).

#include <array>
#include <cmath>
#include <cstdint>

#include "PlacedObject.h"
#include "tetrapage/runtime/geometry/TriangleTriangle.h"
#include "tetrapage/runtime/query/ObjectGroup.h"
#include "tetrapage/runtime/query/ObjectModel.h"

namespace tetrapage {

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
inline void find_triangle_pairs(const PairSide& first, const PairSide& second,
                                GroupCounters& counters, Found&& found) {
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
bool holds_a_component(const PairSide& outer, const PairSide& inner);

}  // namespace tetrapage
