#include "tetrapage/runtime/query/PoseMotion.h"

#include <cmath>
#include <string>

#include "tetrapage/formats/base/Error.h"

namespace tetrapage {

namespace {

std::array<double, 4> unit_quaternion(const Pose& pose, const char* which) {
  const auto& q = pose.rotation;
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  bool finite = std::isfinite(norm);
  for (const double x : pose.translation) finite = finite && std::isfinite(x);
  if (!finite || std::fabs(norm * norm - 1) > 1e-6)
    throw InputError(std::string("motion: the ") + which +
                     " pose is not finite or its quaternion not unit (squared norm " +
                     std::to_string(norm * norm) + ")");
  return {q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm};
}

}  // namespace

PoseMotion::PoseMotion(const Pose& from, const Pose& to) : from_(from), to_(to) {
  from_.rotation = unit_quaternion(from, "start");
  to_.rotation = unit_quaternion(to, "end");
  double dot = 0;
  for (int k = 0; k < 4; ++k) dot += from_.rotation[k] * to_.rotation[k];
  if (dot < 0) {
    for (double& x : to_.rotation) x = -x;
    dot = -dot;
  }
  angle_ = 2 * std::acos(std::min(1.0, dot));
}

Pose PoseMotion::at(double t) const {
  Pose pose;
  for (int a = 0; a < 3; ++a)
    pose.translation[a] = (1 - t) * from_.translation[a] + t * to_.translation[a];
  // Slerp by weights sin((1-t)h)/sin h and sin(th)/sin h, h the half angle; nearly equal
  // rotations interpolate linearly (and the result is normalised either way).
  const double half = angle_ / 2;
  double wa = 1 - t, wb = t;
  if (half > 1e-6) {
    wa = std::sin((1 - t) * half) / std::sin(half);
    wb = std::sin(t * half) / std::sin(half);
  }
  double norm = 0;
  for (int k = 0; k < 4; ++k) {
    pose.rotation[k] = wa * from_.rotation[k] + wb * to_.rotation[k];
    norm += pose.rotation[k] * pose.rotation[k];
  }
  norm = std::sqrt(norm);
  for (double& x : pose.rotation) x /= norm;
  return pose;
}

double PoseMotion::speed_bound(double radius) const {
  double squared = 0;
  for (int a = 0; a < 3; ++a) {
    const double d = to_.translation[a] - from_.translation[a];
    squared += d * d;
  }
  // A point at distance r from the origin moves along an arc of angle x r; slerp turns at a
  // constant rate. The relative margin covers the roundings here and of the poses at().
  return (std::sqrt(squared) + angle_ * radius) * (1 + 0x1p-30);
}

}  // namespace tetrapage
