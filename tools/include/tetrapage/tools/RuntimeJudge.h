#pragma once
/// @file RuntimeJudge.h
/// tetrapage's exact runtime as the judge of a billiard flight, for models whose triangles do
/// not fit the reference oracle's in-core tree (about 150 B a triangle): the flight then moves
/// through the index, paged under a budget, and its answers are the runtime's (checked against
/// the oracle on the models that fit).

#include <memory>

#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/tools/FlightGenerator.h"

namespace tetrapage {

class RuntimeJudge final : public CollisionJudge {
 public:
  /// The workspace is the box of the indexed model (the index header's bounds).
  /// @throw InputError for an empty object or index.
  RuntimeJudge(std::shared_ptr<const CollisionIndex> index, const TriangleSoup& object);

  const BoundingBox& environment_bounds() const override { return workspace_; }
  double object_radius() const override { return radius_; }
  BoundingBox object_bounds(const Pose& pose) const override;
  bool collides(const Pose& pose) override { return flying_.query(pose).collides; }

 private:
  BoundingBox workspace_;
  std::vector<Vec3> vertices_;
  double radius_ = 0;
  FlyingObject flying_;
};

}  // namespace tetrapage
