#pragma once
/// @file ImpactQuery.h
/// What a time-of-impact query asks and answers (FlyingObject::time_of_impact): the earliest
/// time in [0, 1] at which the object, moving from one pose to another (translation linear,
/// rotation by slerp), touches the environment, certified by a bracket.

#include <cstdint>

namespace tetrapage {

enum class Containment : std::uint8_t;

struct ImpactOptions {
  /// The bracket's width at most (in the motion's time, [0, 1]).
  double tolerance = 1e-4;
  /// Conservative advancement steps at most; an object grazing the environment at a
  /// distance far below the tolerance's reach can need many.
  std::uint32_t max_iterations = 10000;
};

enum class Impact : std::uint8_t {
  none,        ///< certified: the object touches nothing during the whole motion
  hit,         ///< it touches, first at a time in (free_until, contact_at]
  unresolved,  ///< max_iterations ran out: no contact up to free_until, nothing known after
};

/// "none", "hit", "unresolved": the words of answer files and bindings.
constexpr const char* to_string(Impact impact) {
  constexpr const char* kNames[] = {"none", "hit", "unresolved"};
  return kNames[static_cast<int>(impact)];
}

struct ImpactResult {
  Impact impact = Impact::none;
  /// No contact at any time in [0, free_until) (certified by distance bounds over the
  /// motion's speed bound); 1 when impact is none.
  double free_until = 1;
  /// The pose at this time collides (decided exactly); contact_at - free_until <= tolerance.
  double contact_at = 1;
  /// The first contact found at contact_at (the collision query's first hit; absent for a
  /// containment).
  bool has_contact = false;
  std::uint64_t environment_triangle = 0;
  std::uint32_t environment_part = 0;
  std::uint32_t object_triangle = 0;
  /// The contact's dynamic obstacle (DynamicObstacles.h), or 0 for the index's triangles.
  std::uint32_t dynamic_part = 0;
  /// A hit with no contact: which body holds the other at contact_at, and its environment
  /// part (Contact::kDynamicPart with containing_dynamic_part for a dynamic obstacle).
  Containment containment{};
  std::uint32_t containing_part = 0;
  std::uint32_t containing_dynamic_part = 0;
  std::uint32_t iterations = 0;  ///< distance queries run
};

}  // namespace tetrapage
