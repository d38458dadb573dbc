#pragma once
/// @file CgalCollider.h
/// CGAL's AABB_tree as a peer: the reference oracle itself (tools' ReferenceCollider, exact
/// predicates), asked either its full question (surfaces or inside, what the answer files
/// hold and tetrapage answers) or only the surface test (FCL's question, decided exactly).

#include "tetrapage/bench/PeerCollider.h"
#include "tetrapage/tools/ReferenceCollider.h"

namespace tetrapage {

class CgalCollider final : public PeerCollider {
 public:
  /// Builds the oracle's trees (it copies the triangles: the soups may be dropped afterwards).
  /// @throw InputError for an empty soup.
  CgalCollider(const TriangleSoup& environment, const TriangleSoup& object, CollisionQuestion question);

  std::string description() const override;
  CollisionQuestion question() const override { return question_; }
  bool collides(const Pose& pose) override;

 private:
  ReferenceCollider oracle_;
  CollisionQuestion question_;
};

}  // namespace tetrapage
