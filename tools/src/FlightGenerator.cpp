#include "tetrapage/tools/FlightGenerator.h"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <functional>
#include <string>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/tools/Random.h"

namespace tetrapage {
namespace {

using Quaternion = std::array<double, 4>;

Quaternion multiply(const Quaternion& a, const Quaternion& b) {
  return {a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
          a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
          a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
          a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]};
}

Quaternion normalized(const Quaternion& q) {
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  return {q[0] / n, q[1] / n, q[2] / n, q[3] / n};
}

// Rotation by the axis-angle vector w (angle = |w|).
Quaternion exp_map(const Vec3& w) {
  const double angle = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
  if (angle == 0.0) return {1.0, 0.0, 0.0, 0.0};
  const double s = std::sin(0.5 * angle) / angle;
  return {std::cos(0.5 * angle), w[0] * s, w[1] * s, w[2] * s};
}

double norm(const Vec3& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

// The shortest text that reads back as the same double (a millimetre model's sizes survive).
std::string number_text(double value) {
  char text[32];
  return std::string(text, std::to_chars(text, text + sizeof text, value).ptr);
}

Vec3 random_direction(Random& random) {
  for (;;) {
    Vec3 v{random.normal(), random.normal(), random.normal()};
    const double n = norm(v);
    if (n > 1e-9) return {v[0] / n, v[1] / n, v[2] / n};
  }
}

Quaternion random_rotation(Random& random) {
  for (;;) {
    Quaternion q{random.normal(), random.normal(), random.normal(), random.normal()};
    const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (n > 1e-9) return {q[0] / n, q[1] / n, q[2] / n, q[3] / n};
  }
}

bool inside_workspace(const BoundingBox& object, const BoundingBox& workspace) {
  for (int a = 0; a < 3; ++a)
    if (object.lo[a] < workspace.lo[a] || object.hi[a] > workspace.hi[a]) return false;
  return true;
}

Pose moved(const Pose& pose, const Vec3& velocity, const Vec3& spin) {
  Pose next;
  for (int a = 0; a < 3; ++a) next.translation[a] = pose.translation[a] + velocity[a];
  next.rotation = normalized(multiply(exp_map(spin), pose.rotation));
  return next;
}

}  // namespace

namespace {

class OracleJudge final : public CollisionJudge {
 public:
  explicit OracleJudge(const ReferenceCollider& oracle) : oracle_(oracle) {}
  const BoundingBox& environment_bounds() const override { return oracle_.environment_bounds(); }
  double object_radius() const override { return oracle_.object_radius(); }
  BoundingBox object_bounds(const Pose& pose) const override { return oracle_.object_bounds(pose); }
  bool collides(const Pose& pose) override { return oracle_.query(pose).collides; }

 private:
  const ReferenceCollider& oracle_;
};

}  // namespace

double flight_displacement(const FlightOptions& options, const BoundingBox& workspace) {
  if (options.displacement) return *options.displacement;
  return default_displacement_per_diagonal * norm(workspace.size());
}

Flight generate_billiard_flight(const ReferenceCollider& oracle, const FlightOptions& options,
                                Progress& progress) {
  OracleJudge judge(oracle);
  return generate_billiard_flight(judge, options, progress);
}

namespace {

// The step length, once the object is known to fit the workspace.
// @throw InputError when it does not, or for a step or rotation out of range.
double checked_displacement(const CollisionJudge& judge, const FlightOptions& options) {
  const BoundingBox& workspace = judge.environment_bounds();
  const double radius = judge.object_radius();
  for (int a = 0; a < 3; ++a) {
    if (workspace.hi[a] - workspace.lo[a] <= 2.0 * radius)
      throw InputError("flight: the object (radius " + number_text(radius) +
                       ") does not fit inside the environment's bounding box along axis " +
                       std::to_string(a) + " (" + number_text(workspace.hi[a] - workspace.lo[a]) +
                       " wide)");
  }
  const double displacement = flight_displacement(options, workspace);
  if (!(displacement > 0.0) || !std::isfinite(displacement) || !(options.max_rotation >= 0.0))
    throw InputError("flight: the displacement (" + number_text(displacement) +
                     ") must be positive and the rotation (" + number_text(options.max_rotation) +
                     ") non-negative");
  return displacement;
}

// A free start: random placements (centre at least the object's radius from the walls).
// @throw InputError when none is found within options.start_attempts.
Pose free_start(CollisionJudge& judge, const FlightOptions& options, Random& random,
                std::uint64_t& attempts) {
  const BoundingBox& workspace = judge.environment_bounds();
  const double radius = judge.object_radius();
  Pose pose;
  while (attempts < options.start_attempts) {
    ++attempts;
    for (int a = 0; a < 3; ++a)
      pose.translation[a] = random.uniform(workspace.lo[a] + radius, workspace.hi[a] - radius);
    pose.rotation = random_rotation(random);
    if (inside_workspace(judge.object_bounds(pose), workspace) && !judge.collides(pose))
      return pose;
  }
  throw InputError("flight: no collision-free start placement found in " +
                   std::to_string(options.start_attempts) + " random attempts (seed " +
                   std::to_string(options.seed) + ")");
}

// The motion's random walk: direction and spin perturbed; the speed stays `displacement`,
// the spin within options.max_rotation.
void perturb(Vec3& velocity, Vec3& spin, double displacement, const FlightOptions& options,
             Random& random) {
  Vec3 v;
  for (int a = 0; a < 3; ++a)
    v[a] = velocity[a] + options.perturbation * displacement * random.normal();
  const double n = norm(v);
  if (n > 0.0)
    for (int a = 0; a < 3; ++a) velocity[a] = v[a] / n * displacement;
  for (int a = 0; a < 3; ++a)
    spin[a] += options.perturbation * options.max_rotation * random.normal();
  const double s = norm(spin);
  if (s > options.max_rotation)
    for (auto& c : spin) c *= options.max_rotation / s;
}

}  // namespace

Flight generate_billiard_flight(CollisionJudge& oracle, const FlightOptions& options,
                                Progress& progress) {
  if (options.steps == 0) throw InputError("flight: --steps must be at least 1");
  Random random(options.seed);
  const BoundingBox& workspace = oracle.environment_bounds();
  const double displacement = checked_displacement(oracle, options);

  Flight flight;
  flight.displacement = displacement;
  flight.poses.reserve(options.steps);
  flight.collides.reserve(options.steps);
  flight.query_seconds.reserve(options.steps);
  Pose pose = free_start(oracle, options, random, flight.start_attempts);

  const auto record = [&](const Pose& p, bool collides, double seconds) {
    flight.poses.push_back(p);
    flight.collides.push_back(collides ? 1 : 0);
    flight.query_seconds.push_back(seconds);
    if (collides) ++flight.collisions;
    progress.advance();
  };
  record(pose, false, 0.0);

  Vec3 direction = random_direction(random);
  Vec3 velocity{direction[0] * displacement, direction[1] * displacement,
                direction[2] * displacement};
  Vec3 spin = random_direction(random);
  const double initial_spin = random.uniform(0.0, options.max_rotation);
  for (auto& s : spin) s *= initial_spin;
  bool replay_reverse = false;  // after a collision the next move is the exact reverse

  std::size_t boundary_streak = 0;
  std::size_t final_attempts = 0;
  while (flight.poses.size() < options.steps) {
    if (!replay_reverse) perturb(velocity, spin, displacement, options, random);
    replay_reverse = false;
    const Pose candidate = moved(pose, velocity, spin);
    if (!inside_workspace(oracle.object_bounds(candidate), workspace)) {
      // Bounce off the workspace walls without emitting the outside pose.
      ++flight.boundary_reversals;
      for (auto& c : velocity) c = -c;
      for (auto& c : spin) c = -c;
      if (++boundary_streak > 1000)
        throw InputError("flight: the object cannot move inside the workspace (seed " +
                         std::to_string(options.seed) + ")");
      continue;
    }
    boundary_streak = 0;
    const auto start = std::chrono::steady_clock::now();
    const bool collides = oracle.collides(candidate);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const bool last = flight.poses.size() + 1 == options.steps;
    if (collides) {
      for (auto& c : velocity) c = -c;
      for (auto& c : spin) c = -c;
      replay_reverse = true;
      if (last) {
        // The path ends on a free placement: try other (perturbed) moves from the last one.
        replay_reverse = false;
        if (++final_attempts > 100000)
          throw InputError("flight: no free final move found (seed " +
                           std::to_string(options.seed) + ")");
        continue;
      }
    }
    record(candidate, collides, seconds);
    pose = candidate;
  }
  progress.finish();
  return flight;
}

Flight generate_grazing_flight(const ReferenceCollider& oracle, const Flight& billiard,
                               const GrazingOptions& options) {
  Flight flight;
  const double radius = oracle.object_radius();
  // The pose at s in [0, 1] between a and b: translation and quaternion interpolated linearly,
  // the quaternion normalised (the shorter arc).
  auto between = [](const Pose& a, const Pose& b, double s) {
    Pose p;
    for (int k = 0; k < 3; ++k) p.translation[k] = a.translation[k] + s * (b.translation[k] - a.translation[k]);
    double dot = 0;
    for (int k = 0; k < 4; ++k) dot += a.rotation[k] * b.rotation[k];
    const double sign = dot < 0 ? -1.0 : 1.0;
    double n = 0;
    for (int k = 0; k < 4; ++k) {
      p.rotation[k] = a.rotation[k] + s * (sign * b.rotation[k] - a.rotation[k]);
      n += p.rotation[k] * p.rotation[k];
    }
    n = std::sqrt(n);
    for (int k = 0; k < 4; ++k) p.rotation[k] /= n;
    return p;
  };
  auto add = [&](const Pose& pose, bool collides) {
    flight.poses.push_back(pose);
    flight.collides.push_back(collides ? 1 : 0);
    flight.collisions += collides ? 1 : 0;
  };
  std::vector<double> distances = options.distances;
  std::sort(distances.begin(), distances.end(), std::greater<>());
  for (std::size_t i = 1; i < billiard.poses.size(); ++i) {
    if (!billiard.collides[i] || billiard.collides[i - 1]) continue;
    const Pose& a = billiard.poses[i - 1];
    const Pose& b = billiard.poses[i];
    double move = 0, dot = 0;
    for (int k = 0; k < 3; ++k) move += (b.translation[k] - a.translation[k]) * (b.translation[k] - a.translation[k]);
    for (int k = 0; k < 4; ++k) dot += a.rotation[k] * b.rotation[k];
    const double angle = 2 * std::acos(std::min(1.0, std::fabs(dot)));
    move = std::sqrt(move) + angle * radius;
    if (!(move > 0)) continue;
    double lo = 0, hi = 1;
    std::vector<double> free_side, colliding_side;
    for (const double d : distances) {
      while ((hi - lo) * move > d && hi - lo > 1e-15) {
        const double mid = 0.5 * (lo + hi);
        (oracle.query(between(a, b, mid)).collides ? hi : lo) = mid;
      }
      free_side.push_back(lo);
      colliding_side.push_back(hi);
    }
    // The oracle's own answer for every emitted pose (a renormalised quaternion is not the
    // one bisected on).
    add(a, false);
    for (const double s : free_side) {
      const Pose p = between(a, b, s);
      add(p, oracle.query(p).collides);
    }
    for (auto it = colliding_side.rbegin(); it != colliding_side.rend(); ++it) {
      const Pose p = between(a, b, *it);
      add(p, oracle.query(p).collides);
    }
    add(b, true);
  }
  return flight;
}

}  // namespace tetrapage
