// Poses and pose files. This file is compiled with -ffp-contract=off (formats/CMakeLists.txt):
// apply_pose defines the world coordinates every collision answer is checked against, so a
// compiler must not fuse its multiply-adds differently in different builds.

#include "tetrapage/formats/mesh/Pose.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "InputFile.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/TextNumbers.h"
#include "tetrapage/formats/base/UnitQuaternion.h"
#include "tetrapage/formats/mesh/OutputFile.h"

namespace tetrapage {

std::array<double, 4> unit_quaternion(const std::array<double, 4>& q) {
  const double norm2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
  // Unit up to rounding: kept, so that writing poses and reading them back is exact.
  if (!(norm2 > 0) || !std::isfinite(norm2) || std::abs(norm2 - 1.0) <= 8 * std::numeric_limits<double>::epsilon())
    return q;
  const double norm = std::sqrt(norm2);
  return {q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm};
}

std::array<double, 9> rotation_matrix(const std::array<double, 4>& unnormalised) {
  const auto q = unit_quaternion(unnormalised);
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  return {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
          2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
          2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
}

Vec3 apply_pose(const std::array<double, 9>& rotation, const Vec3& translation, const Vec3& x) {
  Vec3 world;
  for (int row = 0; row < 3; ++row) {
    const double rotated =
        rotation[3 * row] * x[0] + rotation[3 * row + 1] * x[1] + rotation[3 * row + 2] * x[2];
    world[row] = rotated + translation[row];
  }
  return world;
}

namespace {

constexpr const char* field_names[7] = {"tx", "ty", "tz", "qw", "qx", "qy", "qz"};

std::string_view trimmed(std::string_view text) {
  detail::skip_spaces(text);
  while (!text.empty() && detail::is_space(text.back())) text.remove_suffix(1);
  return text;
}

/// Splits a CSV line (no quoting: the format has only numbers) into at most `limit` fields;
/// returns how many there were (may exceed `limit`).
std::size_t split_fields(std::string_view line, std::string_view* fields, std::size_t limit) {
  std::size_t count = 0;
  for (;;) {
    const std::size_t comma = line.find(',');
    if (count < limit) fields[count] = trimmed(line.substr(0, comma));
    ++count;
    if (comma == std::string_view::npos) return count;
    line.remove_prefix(comma + 1);
  }
}

std::string where(const detail::InputFile& file) {
  return file.name() + ": line " + std::to_string(file.line_number()) + ": ";
}

}  // namespace

std::vector<Pose> read_poses(const std::filesystem::path& path) {
  detail::InputFile file(path, 1u << 20);
  std::string_view line;
  std::string_view fields[7];
  if (!file.next_line(line)) {
    throw FormatError(path.string() + ": empty file, expected the header 'tx,ty,tz,qw,qx,qy,qz'");
  }
  if (line.starts_with("\xEF\xBB\xBF")) line.remove_prefix(3);  // a spreadsheet's UTF-8 mark
  bool header_ok = split_fields(line, fields, 7) == 7;
  for (int k = 0; header_ok && k < 7; ++k) header_ok = fields[k] == field_names[k];
  if (!header_ok) {
    throw FormatError(where(file) + "expected the header 'tx,ty,tz,qw,qx,qy,qz', got " +
                      detail::quote_token(line));
  }
  std::vector<Pose> poses;
  while (file.next_line(line)) {
    if (trimmed(line).empty()) continue;
    const std::size_t count = split_fields(line, fields, 7);
    if (count != 7) {
      throw FormatError(where(file) + "expected 7 comma-separated values, got " +
                        std::to_string(count) + " in " + detail::quote_token(line));
    }
    double values[7];
    for (int k = 0; k < 7; ++k) {
      if (!detail::parse_double(fields[k], values[k])) {
        throw FormatError(where(file) + field_names[k] +
                          " is not a number: " + detail::quote_token(fields[k]));
      }
      if (!std::isfinite(values[k])) {
        throw InputError(where(file) + field_names[k] +
                         " is not finite: " + detail::quote_token(fields[k]));
      }
    }
    Pose pose;
    pose.translation = {values[0], values[1], values[2]};
    pose.rotation = {values[3], values[4], values[5], values[6]};
    const double norm2 = values[3] * values[3] + values[4] * values[4] + values[5] * values[5] +
                         values[6] * values[6];
    if (!is_unit_quaternion(pose.rotation)) {
      char text[160];
      std::snprintf(text, sizeof text,
                    "the quaternion (qw, qx, qy, qz) has length %.9g: a rotation is a unit "
                    "quaternion (squared length within %g of 1)",
                    std::sqrt(norm2), kUnitQuaternionTolerance);
      throw InputError(where(file) + text);
    }
    pose.rotation = unit_quaternion(pose.rotation);
    poses.push_back(pose);
  }
  return poses;
}

void write_poses(const std::filesystem::path& path, std::span<const Pose> poses) {
  for (std::size_t i = 0; i < poses.size(); ++i) {
    for (const double value : poses[i].translation) {
      if (!std::isfinite(value))
        throw InputError("writing '" + path.string() + "': pose " + std::to_string(i) +
                         " is not finite");
    }
    for (const double value : poses[i].rotation) {
      if (!std::isfinite(value))
        throw InputError("writing '" + path.string() + "': pose " + std::to_string(i) +
                         " is not finite");
    }
  }
  OutputFile output(path);
  output.write("tx,ty,tz,qw,qx,qy,qz\n");
  for (const Pose& pose : poses) {
    char* line = output.reserve(8 * detail::max_double_chars);
    char* end = line;
    const double values[7] = {pose.translation[0], pose.translation[1], pose.translation[2],
                              pose.rotation[0],    pose.rotation[1],    pose.rotation[2],
                              pose.rotation[3]};
    for (int k = 0; k < 7; ++k) {
      end = detail::write_double(end, values[k]);
      *end++ = k < 6 ? ',' : '\n';
    }
    output.advance(static_cast<std::size_t>(end - line));
  }
  output.commit();
}

}  // namespace tetrapage
