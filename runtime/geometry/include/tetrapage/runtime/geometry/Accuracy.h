#pragma once
/// @file Accuracy.h
/// The accuracy of the collision decisions, chosen at run time by the caller, and the one API
/// that runs each primitive under it.
///
///  - exact (default): exact signs on the stored coordinates; touching counts.
///  - double_eps, float_eps: the classic epsilon-threshold floating tests (EpsilonTests.h);
///    faster on some inputs, may answer wrongly near contact.
///  - clearance d: everything within distance d counts; never misses a true contact.

#include <algorithm>
#include <cstdint>
#include <string>
#include <string_view>

#include "tetrapage/runtime/geometry/Box.h"

namespace tetrapage::geometry {

enum class AccuracyMode : std::uint8_t { exact, double_eps, float_eps, clearance };

struct Accuracy {
  AccuracyMode mode = AccuracyMode::exact;
  /// clearance mode: the distance d (>= 0).
  double clearance = 0.0;
  /// epsilon modes: the relative epsilon; 0 selects the mode's default
  /// (epsilon::kDefaultDoubleEpsilon or kDefaultFloatEpsilon).
  double relative_epsilon = 0.0;

  static Accuracy exact() { return {}; }
  static Accuracy double_eps(double relative_epsilon = 0.0) {
    return {AccuracyMode::double_eps, 0.0, relative_epsilon};
  }
  static Accuracy float_eps(double relative_epsilon = 0.0) {
    return {AccuracyMode::float_eps, 0.0, relative_epsilon};
  }
  /// @throw InputError if d is negative, NaN or infinite.
  static Accuracy within(double d);

  /// The relative epsilon in use (the default when relative_epsilon is 0); 0 for other modes.
  double effective_epsilon() const;
};

/// Parses "exact", "double_eps", "float_eps" (optionally ":EPSILON", e.g. "float_eps:1e-4"),
/// or "clearance:D" (e.g. "clearance:0.01").
/// @throw InputError naming the text when it is none of these or a number is invalid.
Accuracy parse_accuracy(std::string_view text);

/// The inverse of parse_accuracy ("clearance:0.01", "exact", ...).
std::string to_string(const Accuracy& accuracy);

/// How far a query box must be grown so that box pruning never drops a pair that
/// triangles_collide accepts, for a query of box extent `query_extent` against triangles of
/// box extent at most `other_extent` (extent: the largest side of a triangle's box).
double collision_margin(const Accuracy& accuracy, double query_extent, double other_extent);

/// The largest side of the box.
inline double extent(const Box& box) {
  return std::max({box.hi[0] - box.lo[0], box.hi[1] - box.lo[1], box.hi[2] - box.lo[2]});
}

/// Do the two triangles collide under `accuracy`? Exact: closed triangles meet. Epsilon
/// modes: their boxes, grown by collision_margin, overlap and the epsilon test says so.
/// Clearance d: within_distance(a, b, d).
bool triangles_collide(const Triangle& a, const Triangle& b, const Accuracy& accuracy);

/// The segment against the triangle under `accuracy` (clearance: within distance d).
bool segment_collides_with_triangle(const Segment& s, const Triangle& t, const Accuracy& accuracy);

/// The triangle against the box under `accuracy` (clearance: the box grown by d).
bool triangle_collides_with_box(const Triangle& t, const Box& box, const Accuracy& accuracy);

}  // namespace tetrapage::geometry
