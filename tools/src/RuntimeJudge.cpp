#include "tetrapage/tools/RuntimeJudge.h"

#include <cmath>

#include "tetrapage/formats/base/Error.h"

namespace tetrapage {

RuntimeJudge::RuntimeJudge(std::shared_ptr<const CollisionIndex> index, const TriangleSoup& object)
    : vertices_(object.vertices), flying_(index, object) {
  // The input model's box, as the oracle's workspace is (shard bounds may be conservative).
  workspace_ = index->header().bounds;
  if (workspace_.empty() || index->shard_count() == 0) throw InputError(index->path().string() + ": the index stores no triangle");
  for (const auto& v : vertices_) radius_ = std::max(radius_, std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]));
}

BoundingBox RuntimeJudge::object_bounds(const Pose& pose) const {
  const auto rotation = rotation_matrix(pose.rotation);
  BoundingBox box;
  for (const auto& v : vertices_) box.extend(apply_pose(rotation, pose.translation, v));
  return box;
}

}  // namespace tetrapage
