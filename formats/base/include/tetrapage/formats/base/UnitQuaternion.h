#pragma once
/// @file UnitQuaternion.h
/// When a pose's quaternion stands for a rotation: one rule for pose files (read_poses), the
/// runtime's queries (FlyingObject, ObjectGroup), the C API and Python.

#include <array>
#include <cmath>

namespace tetrapage {

/// How far a pose's quaternion may be from unit, in its squared length, and still stand for a
/// rotation (it is then normalised). Farther is a mistake (a scale, a wrong column), not
/// rounding, and is refused rather than normalised.
inline constexpr double kUnitQuaternionTolerance = 1e-6;

/// True when q's squared length is finite and within kUnitQuaternionTolerance of 1.
inline bool is_unit_quaternion(const std::array<double, 4>& q) {
  const double norm2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
  return std::isfinite(norm2) && std::fabs(norm2 - 1) <= kUnitQuaternionTolerance;
}

}  // namespace tetrapage
