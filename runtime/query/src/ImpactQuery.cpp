// FlyingObject::time_of_impact: conservative advancement along a PoseMotion, with an exact
// collision query closing the bracket.

#include <algorithm>
#include <cmath>
#include <string>

#include "FlyingObjectParts.h"
#include "PlacedObject.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/runtime/query/PoseMotion.h"

namespace tetrapage {

namespace {

// The contact that closes the bracket.
void report_hit(const QueryResult& touch, double free_until, double at, ImpactResult& result) {
  result.impact = Impact::hit;
  result.free_until = free_until;
  result.contact_at = at;
  result.containment = touch.containment;
  result.containing_part = touch.containing_part;
  result.containing_dynamic_part = touch.containing_dynamic_part;
  if (touch.contacts.empty()) return;
  result.contact = touch.contacts.front();
  result.contact.environment_component = ContactSite::kNoComponent;  // as a distance's site
}

// How far the poses that PoseMotion::at computes may lie from the exact motion's (their
// rounding, and the placement's), far beyond it: distances are trusted only beyond this.
double pose_rounding(const Pose& from, const Pose& to, double radius) {
  double magnitude = radius;
  for (int a = 0; a < 3; ++a)
    magnitude += std::max(std::fabs(from.translation[a]), std::fabs(to.translation[a]));
  return magnitude * 0x1p-48;
}

}  // namespace

ImpactResult FlyingObject::time_of_impact(const Pose& from, const Pose& to,
                                          const ImpactOptions& options) {
  if (!(options.tolerance > 0 && options.tolerance <= 1))
    throw InputError("time of impact: the tolerance must be in (0, 1], not " +
                     std::to_string(options.tolerance));
  // Both ends, before any step: advancement may certify the motion free before it reaches
  // an end that no query could place.
  check_translation_within_limit(from.translation);
  check_translation_within_limit(to.translation);
  const PoseMotion motion(from, to);
  const double radius = model_->radius * (1 + 0x1p-40);
  const double speed = motion.speed_bound(radius);
  const double rounding = pose_rounding(from, to, radius);
  ImpactResult result;
  QueryResult& touch = parts_->touch;
  DistanceResult distance_result;
  auto certified_free = [&result] {
    result.impact = Impact::none;
    result.free_until = result.contact_at = 1;
    return result;
  };
  double t = 0;
  result.free_until = 0;
  while (result.iterations < options.max_iterations) {
    // Nothing farther than the rest of the motion can be reached: that is the query's reach.
    const double reach = speed * (1 - t) + 2 * rounding;
    distance(motion.at(t), DistanceOptions{reach}, distance_result);
    ++result.iterations;
    if (distance_result.separation == Separation::touching) {
      report_hit(parts_->touch, result.free_until, t, result);
      return result;
    }
    if (distance_result.separation == Separation::farther) return certified_free();
    // No point of the object covers lower_bound before (lower_bound / speed) has passed.
    const double clearance = distance_result.lower_bound - 2 * rounding;
    const double advance = clearance > 0 && speed > 0 ? clearance / speed * (1 - 0x1p-40) : 0;
    if (speed == 0 && clearance > 0) return certified_free();
    result.free_until = std::min(1.0, t + advance);
    if (result.free_until >= 1) return certified_free();
    if (advance < options.tolerance) {
      // Near contact: the end of a bracket of the tolerance's width, decided exactly.
      double probe = std::min(1.0, result.free_until + options.tolerance);
      while (probe - result.free_until > options.tolerance) probe = std::nextafter(probe, 0.0);
      query(motion.at(probe), QueryOptions{}, touch);
      if (touch.collides) {
        report_hit(touch, result.free_until, probe, result);
        return result;
      }
      // Closer than the poses' rounding, yet not touching: advancement cannot go on.
      if (advance == 0) break;
    }
    t = result.free_until;
  }
  result.impact = Impact::unresolved;
  result.contact_at = 1;
  return result;
}

}  // namespace tetrapage
