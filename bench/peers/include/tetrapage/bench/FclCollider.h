#pragma once
/// @file FclCollider.h
/// FCL 0.7 as a peer: the environment and the object each as a BVHModel<OBBRSS>, one
/// fcl::collide per pose with num_max_contacts 1 (stop at the first contact).
///
/// The object's transform is rotation_matrix(q) and t, the matrix apply_pose uses; FCL places
/// the object's triangles itself, in double, and decides triangle pairs in floating point, so
/// its answers may differ from the exact oracle's near contact (the benchmark counts them).
/// It answers CollisionQuestion::surfaces: an object wholly inside an obstacle is not a hit.

#include <memory>

#include "tetrapage/bench/PeerCollider.h"
#include "tetrapage/formats/base/TriangleSoup.h"

namespace tetrapage {

class FclCollider final : public PeerCollider {
 public:
  /// Builds both models (FCL copies the coordinates: the soups may be dropped afterwards).
  /// @throw InputError for an empty soup; Error when FCL refuses a model (its status code).
  FclCollider(const TriangleSoup& environment, const TriangleSoup& object);
  ~FclCollider() override;
  FclCollider(const FclCollider&) = delete;
  FclCollider& operator=(const FclCollider&) = delete;

  std::string description() const override;
  CollisionQuestion question() const override { return CollisionQuestion::surfaces; }
  bool collides(const Pose& pose) override;
  /// The arrays both built models hold (BV nodes, triangles, primitive indices, vertices).
  std::uint64_t structure_bytes() const override;

 private:
  class Impl;  // keeps FCL's headers out of every includer
  std::unique_ptr<Impl> impl_;
};

}  // namespace tetrapage
