#pragma once
/// @file PoseMotion.h
/// A rigid motion between two poses over the time [0, 1]: the translation linear, the
/// rotation by slerp (the shorter arc), and a bound on how fast any point of an object moves.

#include "tetrapage/formats/mesh/Pose.h"

namespace tetrapage {

class PoseMotion {
 public:
  /// @throw InputError for a non-finite pose or a quaternion far from unit (as queries do).
  PoseMotion(const Pose& from, const Pose& to);

  /// The pose at time t in [0, 1] (from at 0, to at 1 up to the quaternion's sign).
  Pose at(double t) const;
  /// An upper bound on the speed (distance per unit of time) of any point within `radius` of
  /// the object's origin: |translation change| + rotation angle x radius, rounded up.
  double speed_bound(double radius) const;
  /// The rotation angle from `from` to `to`, in radians (in [0, pi]).
  double angle() const { return angle_; }

 private:
  Pose from_, to_;  ///< quaternions unit, to_'s on from_'s side
  double angle_ = 0;
};

}  // namespace tetrapage
