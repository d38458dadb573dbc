#include "tetrapage/runtime/geometry/Accuracy.h"

#include <charconv>
#include <cmath>
#include <sstream>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/runtime/geometry/EpsilonTests.h"
#include "tetrapage/runtime/geometry/SegmentTriangle.h"
#include "tetrapage/runtime/geometry/TriangleBox.h"
#include "tetrapage/runtime/geometry/TriangleDistance.h"
#include "tetrapage/runtime/geometry/TriangleTriangle.h"

namespace tetrapage::geometry {
namespace {

double parse_number(std::string_view text, std::string_view whole) {
  double value = 0.0;
  const char* end = text.data() + text.size();
  const auto [ptr, error] = std::from_chars(text.data(), end, value);
  if (error != std::errc() || ptr != end || !std::isfinite(value) || value < 0)
    throw InputError("accuracy '" + std::string(whole) + "': '" + std::string(text) +
                     "' is not a finite non-negative number");
  return value;
}

}  // namespace

Accuracy Accuracy::within(double d) {
  if (!std::isfinite(d) || d < 0) {
    std::ostringstream message;
    message << "accuracy: the clearance distance must be finite and >= 0, got " << d;
    throw InputError(message.str());
  }
  return {AccuracyMode::clearance, d, 0.0};
}

double Accuracy::effective_epsilon() const {
  switch (mode) {
    case AccuracyMode::double_eps:
      return relative_epsilon > 0 ? relative_epsilon : epsilon::kDefaultDoubleEpsilon;
    case AccuracyMode::float_eps:
      return relative_epsilon > 0 ? relative_epsilon : double(epsilon::kDefaultFloatEpsilon);
    default:
      return 0.0;
  }
}

Accuracy parse_accuracy(std::string_view text) {
  const auto colon = text.find(':');
  const std::string_view name = text.substr(0, colon);
  const bool has_value = colon != std::string_view::npos;
  const std::string_view value = has_value ? text.substr(colon + 1) : std::string_view{};
  if (name == "exact" && !has_value) return Accuracy::exact();
  if (name == "double_eps")
    return Accuracy::double_eps(has_value ? parse_number(value, text) : 0.0);
  if (name == "float_eps") return Accuracy::float_eps(has_value ? parse_number(value, text) : 0.0);
  if (name == "clearance" && has_value) return Accuracy::within(parse_number(value, text));
  throw InputError("accuracy '" + std::string(text) +
                   "': expected exact, double_eps[:EPSILON], float_eps[:EPSILON] or clearance:D");
}

std::string to_string(const Accuracy& accuracy) {
  std::ostringstream out;
  out.precision(17);
  switch (accuracy.mode) {
    case AccuracyMode::exact:
      return "exact";
    case AccuracyMode::double_eps:
      out << "double_eps";
      break;
    case AccuracyMode::float_eps:
      out << "float_eps";
      break;
    case AccuracyMode::clearance:
      out << "clearance:" << accuracy.clearance;
      return out.str();
  }
  if (accuracy.relative_epsilon > 0) out << ':' << accuracy.relative_epsilon;
  return out.str();
}

double collision_margin(const Accuracy& accuracy, double query_extent, double other_extent) {
  switch (accuracy.mode) {
    case AccuracyMode::exact:
      return 0.0;
    case AccuracyMode::clearance:
      // within_distance keeps pairs whose box gap, rounded, is up to a few units above d.
      return accuracy.clearance * (1 + 0x1p-50);
    default:
      return accuracy.effective_epsilon() * (query_extent + other_extent);
  }
}

bool triangles_collide(const Triangle& a, const Triangle& b, const Accuracy& accuracy) {
  switch (accuracy.mode) {
    case AccuracyMode::exact:
      return boxes_overlap(box_of(a), box_of(b)) && triangles_intersect(a, b);
    case AccuracyMode::clearance:
      return within_distance(a, b, accuracy.clearance);
    case AccuracyMode::double_eps:
    case AccuracyMode::float_eps: {
      const Box box_a = box_of(a), box_b = box_of(b);
      const double margin = collision_margin(accuracy, extent(box_a), extent(box_b));
      if (!boxes_overlap(inflated(box_a, margin), box_b)) return false;
      return accuracy.mode == AccuracyMode::double_eps
                 ? epsilon::triangles_intersect<double>(a, b, accuracy.effective_epsilon())
                 : epsilon::triangles_intersect<float>(a, b, float(accuracy.effective_epsilon()));
    }
  }
  return false;
}

bool segment_collides_with_triangle(const Segment& s, const Triangle& t, const Accuracy& accuracy) {
  switch (accuracy.mode) {
    case AccuracyMode::exact:
      return segment_intersects_triangle(s, t);
    case AccuracyMode::clearance:
      return within_distance({s[0], s[1], s[1]}, t, accuracy.clearance);
    case AccuracyMode::double_eps:
      return epsilon::segment_intersects_triangle<double>(s, t, accuracy.effective_epsilon());
    case AccuracyMode::float_eps:
      return epsilon::segment_intersects_triangle<float>(s, t, float(accuracy.effective_epsilon()));
  }
  return false;
}

bool triangle_collides_with_box(const Triangle& t, const Box& box, const Accuracy& accuracy) {
  switch (accuracy.mode) {
    case AccuracyMode::exact:
      return triangle_intersects_box(t, box);
    case AccuracyMode::clearance:
      return box.empty() ? false : triangle_intersects_box(t, inflated(box, accuracy.clearance));
    case AccuracyMode::double_eps:
      return epsilon::triangle_intersects_box<double>(t, box, accuracy.effective_epsilon());
    case AccuracyMode::float_eps:
      return epsilon::triangle_intersects_box<float>(t, box, float(accuracy.effective_epsilon()));
  }
  return false;
}

}  // namespace tetrapage::geometry
