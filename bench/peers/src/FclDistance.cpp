#include "tetrapage/bench/FclDistance.h"

#include <fcl/math/bv/OBBRSS.h>
#include <fcl/math/bv/RSS.h>
#include <fcl/math/motion/interp_motion.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/collision_object.h>
#include <fcl/narrowphase/continuous_collision.h>
#include <fcl/narrowphase/distance.h>

#include <algorithm>

#include "FclModel.h"

namespace tetrapage {

const char* to_string(FclVolume volume) { return volume == FclVolume::rss ? "RSS" : "OBBRSS"; }

class FclDistance::Impl {
 public:
  virtual ~Impl() = default;
  virtual std::uint64_t structure_bytes() const = 0;
  virtual FclDistanceAnswer distance(const Pose& pose, bool exact) = 0;
  virtual FclImpactAnswer time_of_impact(const Pose& from, const Pose& to, FclImpactSolver solver,
                                         std::size_t samples) = 0;
  virtual bool collides(const Pose& pose) = 0;
  virtual std::size_t contacts(const Pose& pose, std::size_t most) = 0;
};

namespace {

// The object's motion from `from` to `to` about its own origin (reference point 0). Built
// with the constructor that takes the reference point and computes the velocities: the
// two-transform constructor leaves the reference point uninitialised in FCL 0.7, which moves
// a rotating object along another path than PoseMotion's.
fcl::InterpMotion<double> motion_between(const fcl::Transform3d& from, const fcl::Transform3d& to) {
  return fcl::InterpMotion<double>(from.linear(), from.translation(), to.linear(), to.translation(),
                                   fcl::Vector3d::Zero());
}

template <class BV>
class Models final : public FclDistance::Impl {
 public:
  Models(const TriangleSoup& environment, const TriangleSoup& object, const char* name)
      : environment_model_(fcl_model::build<BV>(environment, "FCL distance", "environment", name)),
        object_model_(fcl_model::build<BV>(object, "FCL distance", "object", name)),
        environment_(environment_model_, fcl::Transform3d::Identity()),
        object_(object_model_, fcl::Transform3d::Identity()),
        // FCL's best exact settings: nearest points, signed, no relative or absolute slack.
        exact_request_(true, true, 0.0, 0.0) {}

  std::uint64_t structure_bytes() const override {
    return fcl_model::bytes(*environment_model_) + fcl_model::bytes(*object_model_);
  }

  FclDistanceAnswer distance(const Pose& pose, bool exact) override {
    object_.setTransform(fcl_model::transform_of(pose));
    result_.clear();
    fcl::distance(&environment_, &object_, exact ? exact_request_ : default_request_, result_);
    FclDistanceAnswer answer;
    answer.distance = result_.min_distance;
    if (exact)
      for (int a = 0; a < 3; ++a) {
        answer.on_environment[std::size_t(a)] = result_.nearest_points[0][a];
        answer.on_object[std::size_t(a)] = result_.nearest_points[1][a];
      }
    return answer;
  }

  FclImpactAnswer time_of_impact(const Pose& from, const Pose& to, FclImpactSolver solver,
                                 std::size_t samples) override {
    // The motions keep their current time: fresh ones for every query.
    const fcl::Transform3d identity = fcl::Transform3d::Identity();
    const auto still = motion_between(identity, identity);
    const auto moving = motion_between(fcl_model::transform_of(from), fcl_model::transform_of(to));
    fcl::ContinuousCollisionRequestd request;
    request.ccd_motion_type = fcl::CCDM_LINEAR;  // informative: the motions are given
    if (solver == FclImpactSolver::naive) {
      request.ccd_solver_type = fcl::CCDC_NAIVE;
      request.num_max_iterations = std::max<std::size_t>(2, samples);  // toc_err 1e-4 caps it at 10^4
    } else {
      request.ccd_solver_type = fcl::CCDC_CONSERVATIVE_ADVANCEMENT;
    }
    fcl::ContinuousCollisionResultd result;
    fcl::continuousCollide(environment_model_.get(), &still, object_model_.get(), &moving, request, result);
    return {result.is_collide, result.time_of_contact};
  }

  bool collides(const Pose& pose) override {
    object_.setTransform(fcl_model::transform_of(pose));
    fcl::CollisionResultd result;
    fcl::collide(&environment_, &object_, collision_request_, result);
    return result.isCollision();
  }

  std::size_t contacts(const Pose& pose, std::size_t most) override {
    object_.setTransform(fcl_model::transform_of(pose));
    fcl::CollisionResultd result;
    fcl::collide(&environment_, &object_, fcl::CollisionRequestd(most, /*enable_contact=*/true), result);
    return result.numContacts();
  }

 private:
  std::shared_ptr<fcl::BVHModel<BV>> environment_model_, object_model_;
  fcl::CollisionObjectd environment_, object_;
  fcl::DistanceRequestd exact_request_, default_request_;
  fcl::DistanceResultd result_;
  fcl::CollisionRequestd collision_request_{/*num_max_contacts=*/1, /*enable_contact=*/false};
};

}  // namespace

FclDistance::FclDistance(const TriangleSoup& environment, const TriangleSoup& object, FclVolume volume) {
  if (volume == FclVolume::rss)
    impl_ = std::make_unique<Models<fcl::RSSd>>(environment, object, "RSS");
  else
    impl_ = std::make_unique<Models<fcl::OBBRSSd>>(environment, object, "OBBRSS");
  volume_ = volume;
}
FclDistance::~FclDistance() = default;

FclVolume FclDistance::volume() const { return volume_; }
std::uint64_t FclDistance::structure_bytes() const { return impl_->structure_bytes(); }
FclDistanceAnswer FclDistance::distance(const Pose& pose, bool exact) { return impl_->distance(pose, exact); }
FclImpactAnswer FclDistance::time_of_impact(const Pose& from, const Pose& to, FclImpactSolver solver,
                                            std::size_t samples) {
  return impl_->time_of_impact(from, to, solver, samples);
}
bool FclDistance::collides(const Pose& pose) { return impl_->collides(pose); }
std::size_t FclDistance::contacts(const Pose& pose, std::size_t most) { return impl_->contacts(pose, most); }

}  // namespace tetrapage
