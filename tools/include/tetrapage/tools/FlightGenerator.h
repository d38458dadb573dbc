#pragma once
/// @file FlightGenerator.h
/// The study's billiard flights (section 4.1): the object moves by a displacement and a
/// rotation that are randomly perturbed each step; when a pose collides, the motion is
/// reversed; the path starts from a collision-free placement and stays inside the
/// environment's bounding box (the workspace).

#include <cstdint>
#include <optional>
#include <vector>

#include "tetrapage/formats/base/Progress.h"
#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/tools/ReferenceCollider.h"

namespace tetrapage {

/// The default distance moved per step as a fraction of the diagonal of the environment's
/// bounding box: the study's 0.005 in its unit cube (whose diagonal is sqrt(3)), about 1/346.
inline constexpr double default_displacement_per_diagonal = 0.005 / 1.7320508075688772;

struct FlightOptions {
  std::size_t steps = 10000;
  std::uint64_t seed = 1;
  /// Distance moved per step, in model units; by default default_displacement_per_diagonal
  /// times the diagonal of the environment's bounding box, so that a model in millimetres
  /// gets the steps it would in metres.
  std::optional<double> displacement;
  double max_rotation = 0.05;     ///< radians per step at most
  double perturbation = 0.3;      ///< relative random change of the motion per step
  std::size_t start_attempts = 100000;  ///< random placements tried for a free start
};

/// The distance moved per step: options.displacement, else the default for the workspace.
double flight_displacement(const FlightOptions& options, const BoundingBox& workspace);

struct Flight {
  double displacement = 0;  ///< the distance moved per step (flight_displacement)
  std::vector<Pose> poses;
  std::vector<std::uint8_t> collides;  ///< the oracle's answer for each pose
  std::uint64_t collisions = 0;
  std::uint64_t boundary_reversals = 0;  ///< moves refused because they left the workspace
  std::uint64_t start_attempts = 0;
  std::vector<double> query_seconds;     ///< oracle time per emitted pose
};

/// What decides a billiard flight's collisions: the reference oracle (exact, in core), or for
/// models too large for it tetrapage's own exact runtime over an index (RuntimeJudge.h).
class CollisionJudge {
 public:
  virtual ~CollisionJudge() = default;
  /// The workspace the object stays in.
  virtual const BoundingBox& environment_bounds() const = 0;
  /// Radius of the object's bounding sphere around its own origin.
  virtual double object_radius() const = 0;
  /// Box of the object placed at `pose` (from all its placed vertices).
  virtual BoundingBox object_bounds(const Pose& pose) const = 0;
  virtual bool collides(const Pose& pose) = 0;
};

/// Generates a billiard flight, `judge` deciding collisions (the same moves for every judge
/// that gives the same answers).
Flight generate_billiard_flight(CollisionJudge& judge, const FlightOptions& options,
                                Progress& progress = Progress::silent());

/// Generates a billiard flight with the reference oracle deciding collisions.
/// A colliding pose is followed by the exact reverse of the move that led into it, so the
/// object is back at a free placement the step after; the last pose is collision-free.
/// @throw InputError if no collision-free start is found within options.start_attempts, or if
///        the object does not fit inside the workspace.
Flight generate_billiard_flight(const ReferenceCollider& oracle, const FlightOptions& options,
                                Progress& progress = Progress::silent());

/// Near-contact poses for the accuracy benchmarks: for each colliding pose of `billiard` whose
/// predecessor is free, the step between them is bisected with the oracle (Answer::collides)
/// and the brackets are emitted where the step's motion across them falls below each of
/// `distances` (object motion = translation + rotation angle x object radius): free poses
/// approaching the contact, then colliding poses leaving it, in the order of the motion,
/// between the free predecessor and the colliding pose. The grazing flight is those runs,
/// one after another; `collides` holds the oracle's answers.
struct GrazingOptions {
  std::vector<double> distances{1e-6, 1e-7, 1e-8, 1e-9};
};
Flight generate_grazing_flight(const ReferenceCollider& oracle, const Flight& billiard,
                               const GrazingOptions& options = {});

}  // namespace tetrapage
