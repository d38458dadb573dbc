#pragma once
/// @file FclDistance.h
/// FCL 0.7's distance and continuous collision between the environment and the object, each a
/// BVHModel (OBBRSS or RSS), as the peer of FlyingObject::distance and time_of_impact.
///
/// The object's transform is rotation_matrix(q) and t (as FclCollider). FCL measures triangle
/// pairs in floating point without a certified bound, and reports 0 for meshes that cross; it
/// sees surfaces only (an object inside an obstacle is at a positive distance for it).

#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/formats/mesh/Pose.h"

namespace tetrapage {

/// The bounding volume of both models: FCL recommends RSS for distance queries, OBBRSS
/// for both collision and distance.
enum class FclVolume : std::uint8_t { obbrss, rss };

/// "OBBRSS" or "RSS".
const char* to_string(FclVolume volume);

struct FclDistanceAnswer {
  double distance = 0;
  /// The nearest points (world coordinates) when asked for; zero otherwise.
  std::array<double, 3> on_environment{}, on_object{};
};

/// How fcl::continuousCollide decides a motion.
enum class FclImpactSolver : std::uint8_t {
  /// CCDC_CONSERVATIVE_ADVANCEMENT: distance bounds over motion bounds (FCL's certified one).
  conservative_advancement,
  /// CCDC_NAIVE: fcl::collide at `samples` evenly spaced times, 0 and 1 included (FCL's
  /// default request samples 10): may step over a contact between two samples.
  naive,
};

struct FclImpactAnswer {
  bool collides = false;
  /// FCL's time of contact in [0, 1] (1 without contact).
  double time_of_contact = 1;
};

class FclDistance {
 public:
  /// Builds both models. @throw InputError for an empty soup; Error when FCL refuses a model.
  FclDistance(const TriangleSoup& environment, const TriangleSoup& object, FclVolume volume);
  ~FclDistance();
  FclDistance(const FclDistance&) = delete;
  FclDistance& operator=(const FclDistance&) = delete;

  FclVolume volume() const;
  /// The arrays both built models hold.
  std::uint64_t structure_bytes() const;

  /// fcl::distance at `pose`. exact: DistanceRequest(nearest points, signed, rel_err 0,
  /// abs_err 0); otherwise FCL's default request (no nearest points; rel_err and abs_err
  /// are 0 there too in FCL 0.7).
  FclDistanceAnswer distance(const Pose& pose, bool exact = true);

  /// fcl::continuousCollide from `from` to `to` by conservative advancement
  /// (CCDC_CONSERVATIVE_ADVANCEMENT), the object moving by an InterpMotion about its own
  /// origin: translation linear, rotation about a fixed axis at a constant rate, i.e. the
  /// slerp of PoseMotion. (FCL's mesh/mesh advancement ignores the request's toc_err and
  /// num_max_iterations: it stops when a step is under its own t_err, 1e-5.)
  /// Naive: `samples` times (at least 2).
  FclImpactAnswer time_of_impact(const Pose& from, const Pose& to,
                                 FclImpactSolver solver = FclImpactSolver::conservative_advancement,
                                 std::size_t samples = 10);

  /// fcl::collide at `pose` (first contact only): FCL's discrete answer, to check its
  /// continuous ones against.
  bool collides(const Pose& pose);
  /// Every contact at `pose` (fcl::collide with enable_contact, up to `most`): FCL's contact
  /// geometry (a point, a normal and a penetration depth per triangle pair); returns how many.
  std::size_t contacts(const Pose& pose, std::size_t most);

  class Impl;  // keeps FCL's headers out of every includer (public only for FclDistance.cpp)

 private:
  std::unique_ptr<Impl> impl_;
  FclVolume volume_ = FclVolume::obbrss;
};

}  // namespace tetrapage
