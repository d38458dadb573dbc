#include "tetrapage/bench/FclCollider.h"

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/collision_object.h>

#include <string>
#include <vector>

#include "tetrapage/formats/Error.h"

namespace tetrapage {
namespace {

using Model = fcl::BVHModel<fcl::OBBRSSd>;

std::shared_ptr<Model> build_model(const TriangleSoup& soup, const char* what) {
  if (soup.triangles.empty()) throw InputError(std::string("FCL collider: the ") + what + " has no triangle");
  std::vector<fcl::Vector3d> points;
  points.reserve(soup.vertices.size());
  for (const auto& v : soup.vertices) points.emplace_back(v[0], v[1], v[2]);
  std::vector<fcl::Triangle> triangles;
  triangles.reserve(soup.triangles.size());
  for (const auto& t : soup.triangles) triangles.emplace_back(t[0], t[1], t[2]);
  auto model = std::make_shared<Model>();
  int status = model->beginModel(int(triangles.size()), int(points.size()));
  if (status == fcl::BVH_OK) status = model->addSubModel(points, triangles);
  if (status == fcl::BVH_OK) status = model->endModel();
  if (status != fcl::BVH_OK)
    throw Error(std::string("FCL collider: BVHModel<OBBRSS> of the ") + what + " failed with status " +
                std::to_string(status));
  return model;
}

// The arrays a built BVHModel holds: BV nodes, triangles with their primitive indices, vertices.
// (BVHModel::memUsage returns a status code in FCL 0.7 and sums in int, so it cannot say.)
std::uint64_t model_bytes(const Model& model) {
  return std::uint64_t(model.getNumBVs()) * sizeof(fcl::BVNode<fcl::OBBRSSd>) +
         std::uint64_t(model.num_tris) * (sizeof(fcl::Triangle) + sizeof(unsigned int)) +
         std::uint64_t(model.num_vertices) * sizeof(fcl::Vector3d);
}

}  // namespace

class FclCollider::Impl {
 public:
  Impl(const TriangleSoup& environment, const TriangleSoup& object)
      : environment_model_(build_model(environment, "environment")),
        object_model_(build_model(object, "object")),
        environment_(environment_model_, fcl::Transform3d::Identity()),
        object_(object_model_, fcl::Transform3d::Identity()),
        request_(/*num_max_contacts=*/1, /*enable_contact=*/false) {}

  bool collides(const Pose& pose) {
    // The matrix apply_pose uses; with the environment first (identity transform), FCL's
    // relative transform is exactly this one.
    const auto r = rotation_matrix(pose.rotation);
    fcl::Transform3d transform = fcl::Transform3d::Identity();
    transform.linear() << r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8];
    transform.translation() << pose.translation[0], pose.translation[1], pose.translation[2];
    object_.setTransform(transform);
    result_.clear();
    fcl::collide(&environment_, &object_, request_, result_);
    return result_.isCollision();
  }

  std::uint64_t structure_bytes() const { return model_bytes(*environment_model_) + model_bytes(*object_model_); }

 private:
  std::shared_ptr<Model> environment_model_, object_model_;
  fcl::CollisionObjectd environment_, object_;
  fcl::CollisionRequestd request_;
  fcl::CollisionResultd result_;
};

FclCollider::FclCollider(const TriangleSoup& environment, const TriangleSoup& object)
    : impl_(std::make_unique<Impl>(environment, object)) {}
FclCollider::~FclCollider() = default;

std::string FclCollider::description() const { return "FCL 0.7 BVHModel<OBBRSS>"; }
bool FclCollider::collides(const Pose& pose) { return impl_->collides(pose); }
std::uint64_t FclCollider::structure_bytes() const { return impl_->structure_bytes(); }

}  // namespace tetrapage
