#pragma once
/// @file PeerCollider.h
/// One interface over the colliders the peer benchmark replays a flight through: FCL, CGAL's
/// AABB tree (the reference oracle) and tetrapage's runtime, so that every one answers the same
/// poses in the same loop and is timed the same way.

#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "tetrapage/formats/mesh/Pose.h"

namespace tetrapage {

/// What "collides" means for a collider: mesh/mesh libraries (FCL, a plain AABB-tree test)
/// only see surfaces; the oracle and tetrapage also count an object lying inside an obstacle.
enum class CollisionQuestion : std::uint8_t {
  surfaces,            ///< some object triangle meets some environment triangle
  surfaces_or_inside,  ///< that, or the object lies inside an obstacle (ReferenceCollider.h)
};

/// "surfaces" or "surfaces_or_inside".
const char* to_string(CollisionQuestion question);

class PeerCollider {
 public:
  virtual ~PeerCollider() = default;

  /// What the collider is, as tables print it ("FCL 0.7 BVHModel<OBBRSS>").
  virtual std::string description() const = 0;
  virtual CollisionQuestion question() const = 0;

  /// Answers one pose: the object's own coordinates x placed at R(q) x + t. Not const:
  /// a collider may keep state from step to step (tetrapage's runtime does).
  virtual bool collides(const Pose& pose) = 0;

  /// The bytes of the collider's own structures as it counts them; 0 when it does not say.
  virtual std::uint64_t structure_bytes() const { return 0; }

  /// Figures particular to the collider (page-ins, cache hit rate, ...), for the report.
  virtual nlohmann::json figures() const { return nlohmann::json::object(); }
};

}  // namespace tetrapage
