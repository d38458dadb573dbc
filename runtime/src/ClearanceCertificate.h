#pragma once
/// @file ClearanceCertificate.h
/// Coherence between steps (the study's walk from where you were, for the whole step): a step
/// that finds the object free may also prove a lower bound D on the object's distance to every
/// environment triangle. A later pose whose every object point lies less than D from where it
/// was is then free too, with no test at all:
///  - no contact: each point of the object's surface moved less than D, and no environment
///    point lay within D of the surface;
///  - no containment either way: along the straight motion of the placed vertices (every point
///    of the surface moves less than D on the way), no surface crosses the other's points, so
///    every point stays on the side of every closed surface it was on, and the first pose was
///    free.
/// The motion bound of a rigid motion is |c1 - c0| + |R1 - R0| r for a ball of radius r at c,
/// and |R1 - R0| = 2 sin(theta / 2) = 2 |v| for the relative quaternion (w, v).

#include <algorithm>
#include <array>
#include <cmath>

#include "tetrapage/formats/Pose.h"
#include "tetrapage/runtime/ObjectModel.h"

namespace tetrapage {

/// Where the object is, for motion bounds: its ball's placed centre and its unit quaternion.
struct PlacedBall {
  Vec3 centre{};
  std::array<double, 4> quaternion{1, 0, 0, 0};
  double translation_magnitude = 0;  ///< the largest |t| component, for the rounding margin
};

/// The ball of `model` placed by the unit quaternion q (and its matrix) and translation t.
inline PlacedBall placed_ball(const ObjectModel& model, const std::array<double, 4>& unit_q,
                              const std::array<double, 9>& rotation, const Vec3& translation) {
  return {apply_pose(rotation, translation, model.ball_centre), unit_q,
          std::max({std::fabs(translation[0]), std::fabs(translation[1]), std::fabs(translation[2])})};
}

/// An upper bound on how far any placed vertex of `model` lies from where it lay at `from`
/// when the object is at `to` (placements rounded as apply_pose rounds them).
inline double motion_bound(const ObjectModel& model, const PlacedBall& from, const PlacedBall& to) {
  const Vec3 d{to.centre[0] - from.centre[0], to.centre[1] - from.centre[1], to.centre[2] - from.centre[2]};
  const auto& a = from.quaternion;
  const auto& b = to.quaternion;
  // The vector part of conj(a) b.
  const double vx = a[0] * b[1] - a[1] * b[0] - a[2] * b[3] + a[3] * b[2];
  const double vy = a[0] * b[2] + a[1] * b[3] - a[2] * b[0] - a[3] * b[1];
  const double vz = a[0] * b[3] - a[1] * b[2] + a[2] * b[1] - a[3] * b[0];
  const double sine = std::sqrt(vx * vx + vy * vy + vz * vz);
  // The placements, the matrices and this arithmetic round by a few ulps of these magnitudes;
  // the margin is far beyond.
  const double magnitude = model.radius + model.ball_radius + from.translation_magnitude + to.translation_magnitude;
  return std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) + 2 * sine * model.ball_radius + magnitude * 0x1p-38;
}

/// The last proven clearance: every environment triangle lay at least `clearance` from the
/// object placed at `at`.
class ClearanceCertificate {
 public:
  /// The object at `now` is free (no contact, no containment) for the question the
  /// certificate was proven for.
  bool covers(const ObjectModel& model, const PlacedBall& now) const {
    return clearance_ > 0 && motion_bound(model, at_, now) < clearance_;
  }
  void keep(const PlacedBall& at, double clearance) {
    at_ = at;
    clearance_ = clearance;
  }
  void clear() { clearance_ = 0; }
  double clearance() const { return clearance_; }

 private:
  PlacedBall at_;
  double clearance_ = 0;
};

}  // namespace tetrapage
