#include "tetrapage/bench/FclCollider.h"

#include <fcl/math/bv/OBBRSS.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/collision_object.h>

#include "FclModel.h"

namespace tetrapage {
namespace {

using Model = fcl::BVHModel<fcl::OBBRSSd>;

std::shared_ptr<Model> build_model(const TriangleSoup& soup, const char* what) {
  return fcl_model::build<fcl::OBBRSSd>(soup, "FCL collider", what, "OBBRSS");
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
    object_.setTransform(fcl_model::transform_of(pose));
    result_.clear();
    fcl::collide(&environment_, &object_, request_, result_);
    return result_.isCollision();
  }

  std::uint64_t structure_bytes() const { return fcl_model::bytes(*environment_model_) + fcl_model::bytes(*object_model_); }

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
