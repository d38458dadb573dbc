#include "tetrapage/bench/CgalCollider.h"

namespace tetrapage {

CgalCollider::CgalCollider(const TriangleSoup& environment, const TriangleSoup& object, CollisionQuestion question)
    : oracle_(environment, object), question_(question) {}

std::string CgalCollider::description() const {
  return question_ == CollisionQuestion::surfaces ? "CGAL AABB_tree, exact, surfaces only"
                                                  : "CGAL AABB_tree, exact oracle (surfaces + inside test)";
}

bool CgalCollider::collides(const Pose& pose) {
  return question_ == CollisionQuestion::surfaces ? oracle_.surfaces_touch(pose) : oracle_.query(pose).collides;
}

}  // namespace tetrapage
