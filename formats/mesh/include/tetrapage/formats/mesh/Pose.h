#pragma once
/// @file Pose.h
/// Rigid poses of a flying object and the pose-file format (CSV `tx,ty,tz,qw,qx,qy,qz`).
/// A pose maps the object's own coordinates x to R(q) x + t, q a unit quaternion.

#include <array>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <span>
#include <vector>

#include "tetrapage/formats/base/TriangleSoup.h"

namespace tetrapage {

/// The largest magnitude of a model coordinate, an object coordinate or a pose translation
/// that every query answers: R(q) x + t stays under 3e150, so the differences of placed and
/// model coordinates stay under 6e150, and the sums of their squares (distances, box gaps,
/// motion speeds) under 1.1e302, far from overflow (DBL_MAX is 1.8e308). Beyond about 1.3e154
/// a squared difference overflows: an infinite distance.
inline constexpr double kMaxCoordinateMagnitude = 1e150;

/// The first vertex coordinate of `soup` beyond kMaxCoordinateMagnitude (NaN is not), as
/// vertex, axis and value; `found` is false if there is none. Objects and environments both
/// refuse such a soup: its placed or enlarged boxes would overflow.
struct CoordinateBeyondLimit {
  bool found = false;
  std::size_t vertex = 0;
  int axis = 0;
  double value = 0;
};
inline CoordinateBeyondLimit find_coordinate_beyond_limit(const TriangleSoup& soup) {
  for (std::size_t v = 0; v < soup.vertices.size(); ++v)
    for (int a = 0; a < 3; ++a)
      if (std::fabs(soup.vertices[v][a]) > kMaxCoordinateMagnitude)
        return {true, v, a, soup.vertices[v][a]};
  return {};
}

struct Pose {
  Vec3 translation{0.0, 0.0, 0.0};
  std::array<double, 4> rotation{1.0, 0.0, 0.0, 0.0};  ///< unit quaternion qw, qx, qy, qz
};

/// q as the unit quaternion of its rotation: one unit up to rounding (its squared norm within
/// 8 epsilon of 1) bit for bit, any other divided by its norm (a zero or non-finite one is
/// returned as it is: callers reject it).
std::array<double, 4> unit_quaternion(const std::array<double, 4>& q);

/// Row-major 3x3 rotation matrix of unit_quaternion(q): every placement (the runtime, the
/// oracle, the peers) turns a slightly non-unit q into the same orthogonal matrix, whose
/// product does not stretch the object. The identity quaternion gives exactly the identity.
std::array<double, 9> rotation_matrix(const std::array<double, 4>& q);

/// R(q) x + t, computed in double the one canonical way: every component of the product
/// in the order r0*x + r1*y + r2*z, then + t. The collision answers are defined on these
/// world coordinates.
Vec3 apply_pose(const std::array<double, 9>& rotation, const Vec3& translation, const Vec3& x);
inline Vec3 apply_pose(const Pose& pose, const Vec3& x) {
  return apply_pose(rotation_matrix(pose.rotation), pose.translation, x);
}

/// Reads a pose file: the header `tx,ty,tz,qw,qx,qy,qz` exactly (blanks around the names, a
/// UTF-8 byte-order mark and CRLF line ends are tolerated), then one pose per line; blank lines
/// are skipped. Quaternions are normalised on read (one that is unit up to rounding, within
/// 8 epsilon in its squared norm, is kept bit for bit, so write_poses + read_poses is exact).
/// @throw IoError if the file cannot be read; FormatError for a wrong header or a malformed
///        line; InputError for NaN/infinite values or a zero quaternion (names line and value).
std::vector<Pose> read_poses(const std::filesystem::path& path);

/// Writes poses with round-trip precision (shortest exact form of every double), under a
/// temporary name (`<path>.tmp`) renamed on success.
/// @throw InputError for a non-finite value; IoError on failure (naming the file).
void write_poses(const std::filesystem::path& path, std::span<const Pose> poses);

}  // namespace tetrapage
