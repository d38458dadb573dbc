#pragma once
/// @file DistanceQuery.h
/// What a distance query asks and answers (FlyingObject::distance): the minimum distance
/// between the placed object and the environment, its two closest points and the triangles
/// they lie on, certified by bounds on the double computation.

#include <cstdint>
#include <limits>

#include "tetrapage/runtime/geometry/Shapes.h"

namespace tetrapage {

enum class Containment : std::uint8_t;

struct DistanceOptions {
  /// Distances beyond this are not measured: the answer is then only "farther", which is
  /// cheap when the object lies in free space (the usual case for planners). Must be >= 0;
  /// infinity measures any distance.
  double max_distance = std::numeric_limits<double>::infinity();
};

enum class Separation : std::uint8_t {
  /// The object touches the environment, or one body holds the other (decided exactly, as the
  /// collision query decides it): the distance is 0.
  touching,
  /// Apart, by `distance`, within max_distance.
  apart,
  /// Farther than max_distance (certified: no pair is within max_distance; lower_bound is at
  /// least max_distance), or an empty environment; the closest points are not measured.
  farther,
};

/// "touching", "apart", "farther": the words of answer files and bindings.
constexpr const char* to_string(Separation separation) {
  constexpr const char* kNames[] = {"touching", "apart", "farther"};
  return kNames[static_cast<int>(separation)];
}

struct DistanceResult {
  Separation separation = Separation::farther;
  /// The computed distance |on_environment - on_object|; 0 when touching; when farther, the
  /// certified lower bound.
  double distance = 0;
  /// The true distance (between the stored environment and the object as apply_pose places
  /// it) lies in [lower_bound, upper_bound]. Their gap is the error bound of the double
  /// computation: about 150 u M, with u = 2^-53 and M the coordinates' magnitude near the
  /// closest pair (TriangleDistance.h). Both are 0 when touching; upper_bound is infinite
  /// when farther.
  double lower_bound = 0;
  double upper_bound = std::numeric_limits<double>::infinity();
  /// The closest points, in world coordinates (when touching: a point both surfaces share,
  /// or nothing measured for a containment).
  geometry::Point on_environment{};
  geometry::Point on_object{};
  /// The closest pair's triangles (none when farther, or for a containment).
  static constexpr std::uint64_t kNoTriangle = std::numeric_limits<std::uint64_t>::max();
  std::uint64_t environment_triangle = kNoTriangle;
  std::uint32_t environment_part = 0;
  std::uint32_t object_triangle = 0;
  /// The closest triangle belongs to a dynamic obstacle (DynamicObstacles.h) with this id:
  /// environment_part is then Contact::kDynamicPart and environment_triangle the triangle's
  /// index in that part's mesh; 0 for the index's triangles.
  std::uint32_t dynamic_part = 0;
  /// Touching without contact: which body holds the other (its part in containing_part).
  Containment containment{};
  std::uint32_t containing_part = 0;
  std::uint32_t containing_dynamic_part = 0;  ///< as QueryResult's
  /// Environment triangles measured against the object, and triangle pairs measured.
  std::uint64_t candidates = 0;
  std::uint64_t pair_tests = 0;
  /// The step started from the last step's closest pair (coherence), or found a free box far
  /// enough to answer "farther" without measuring.
  bool from_last_pair = false;
  bool from_free_box = false;
};

}  // namespace tetrapage
