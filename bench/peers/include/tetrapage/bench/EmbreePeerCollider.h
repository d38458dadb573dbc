#pragma once
/// @file EmbreePeerCollider.h
/// Embree 3's rtcCollide as a peer (tools' EmbreeCollider: user-geometry BVHs of both bodies,
/// the object's refitted per pose, candidate pairs decided by CGAL's exact test), on one thread.

#include "tetrapage/bench/PeerCollider.h"
#include "tetrapage/tools/EmbreeCollider.h"

namespace tetrapage {

class EmbreePeerCollider final : public PeerCollider {
 public:
  /// @throw InputError / Error as EmbreeCollider's constructor.
  EmbreePeerCollider(const TriangleSoup& environment, const TriangleSoup& object)
      : collider_(environment, object, 1) {}

  std::string description() const override {
    return "Embree 3 rtcCollide (user geometries, one thread), pairs decided exactly";
  }
  CollisionQuestion question() const override { return CollisionQuestion::surfaces; }
  bool collides(const Pose& pose) override { return collider_.query(pose).surfaces_touch; }

 private:
  EmbreeCollider collider_;
};

}  // namespace tetrapage
