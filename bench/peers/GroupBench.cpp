// tetrapage_bench_group: N copies of one object random-walking in a box where they collide now
// and then, checked against each other at every step by tetrapage's ObjectGroup and by FCL's
// DynamicAABBTreeCollisionManager (BVHModel<OBBRSS> per object, as FclCollider builds it), on
// identical poses. Object/object only: FCL's manager compares objects with each other, so the
// environment is left out of both. Surfaces only: tetrapage's containment test is off, as FCL
// has none. Prints, per N, steps per second and latency percentiles of both, their ratio, and
// the steps and pairs on which FCL (floating point) disagrees with tetrapage (exact).
//
//   tetrapage_bench_group [--counts 2,8,64] [--steps 500] [--triangles 1000] [--repeats 3]
//                         [--seed 1] [--report R.json]

#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/collision_object.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/runtime/query/ObjectGroup.h"
#include "tetrapage/tools/LatencySummary.h"
#include "tetrapage/tools/MeshLibrary.h"
#include "tetrapage/tools/ObjectGenerator.h"

namespace tetrapage {
namespace {

using Clock = std::chrono::steady_clock;
using PairSet = std::vector<std::pair<std::uint32_t, std::uint32_t>>;  // sorted (i < j)
using Flight = std::vector<std::vector<Pose>>;                         // [step][object]

std::array<double, 4> multiply(const std::array<double, 4>& a, const std::array<double, 4>& b) {
  return {a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
          a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
          a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
          a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]};
}

// n objects of size `size` random-walking in a cube whose side grows with cbrt(n), so that the
// share of time an object spends touching another is about the same for every n: each step a
// small move (bouncing off the walls) and a small turn.
Flight random_walk(std::size_t n, std::size_t steps, double size, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  const double side = 2.5 * size * std::cbrt(double(n));
  std::uniform_real_distribution<double> unit(0, 1);
  std::normal_distribution<double> normal;
  std::vector<Pose> poses(n);
  std::vector<Vec3> velocity(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a)
      poses[i].translation[a] = unit(random) * side, velocity[i][a] = normal(random);
    const double norm = std::hypot(velocity[i][0], velocity[i][1], velocity[i][2]);
    for (auto& v : velocity[i]) v *= 0.1 * size / norm;
  }
  Flight flight;
  for (std::size_t step = 0; step < steps; ++step) {
    for (std::size_t i = 0; i < n; ++i) {
      for (int a = 0; a < 3; ++a) {
        double& t = poses[i].translation[a];
        t += velocity[i][a];
        if (t < 0 || t > side) velocity[i][a] = -velocity[i][a], t = std::clamp(t, 0.0, side);
      }
      std::array<double, 4> turn{1, 0.05 * normal(random), 0.05 * normal(random),
                                 0.05 * normal(random)};
      poses[i].rotation = unit_quaternion(multiply(poses[i].rotation, unit_quaternion(turn)));
    }
    flight.push_back(poses);
  }
  return flight;
}

struct Run {
  std::vector<double> seconds;   // per step
  std::vector<PairSet> answers;  // per step
};

Run run_tetrapage(const std::shared_ptr<const ObjectModel>& model, const Flight& flight) {
  ObjectGroup group(nullptr,
                    std::vector<std::shared_ptr<const ObjectModel>>(flight[0].size(), model));
  GroupQueryOptions options;
  options.check_environment = false;
  options.pair_containment = false;  // the question FCL answers: do surfaces meet?
  GroupResult result;
  Run run;
  for (const auto& poses : flight) {
    const auto start = Clock::now();
    group.step(poses, options, result);
    run.seconds.push_back(std::chrono::duration<double>(Clock::now() - start).count());
    PairSet pairs;
    for (const auto& p : result.pairs) pairs.emplace_back(p.first, p.second);
    run.answers.push_back(std::move(pairs));
  }
  return run;
}

using FclModel = fcl::BVHModel<fcl::OBBRSSd>;

std::shared_ptr<FclModel> fcl_model(const TriangleSoup& soup) {
  std::vector<fcl::Vector3d> points;
  for (const auto& v : soup.vertices) points.emplace_back(v[0], v[1], v[2]);
  std::vector<fcl::Triangle> triangles;
  for (const auto& t : soup.triangles) triangles.emplace_back(t[0], t[1], t[2]);
  auto model = std::make_shared<FclModel>();
  int status = model->beginModel(int(triangles.size()), int(points.size()));
  if (status == fcl::BVH_OK) status = model->addSubModel(points, triangles);
  if (status == fcl::BVH_OK) status = model->endModel();
  if (status != fcl::BVH_OK)
    throw Error("FCL: BVHModel<OBBRSS> failed with status " + std::to_string(status));
  return model;
}

fcl::Transform3d fcl_transform(const Pose& pose) {
  // The matrix apply_pose uses.
  const auto r = rotation_matrix(pose.rotation);
  fcl::Transform3d transform = fcl::Transform3d::Identity();
  transform.linear() << r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8];
  transform.translation() << pose.translation[0], pose.translation[1], pose.translation[2];
  return transform;
}

// What the manager's callback fills: every pair of objects whose meshes meet.
struct FclPairs {
  fcl::CollisionRequestd request{1, false};
  PairSet pairs;
};

bool collect_pair(fcl::CollisionObjectd* a, fcl::CollisionObjectd* b, void* data) {
  auto& found = *static_cast<FclPairs*>(data);
  fcl::CollisionResultd result;
  fcl::collide(a, b, found.request, result);
  if (result.isCollision()) {
    const auto i = std::uint32_t(reinterpret_cast<std::uintptr_t>(a->getUserData()));
    const auto j = std::uint32_t(reinterpret_cast<std::uintptr_t>(b->getUserData()));
    found.pairs.emplace_back(std::min(i, j), std::max(i, j));
  }
  return false;  // go on: every colliding pair
}

Run run_fcl(const TriangleSoup& soup, const Flight& flight) {
  const auto model = fcl_model(soup);
  std::vector<std::unique_ptr<fcl::CollisionObjectd>> objects;
  fcl::DynamicAABBTreeCollisionManagerd manager;
  for (std::size_t i = 0; i < flight[0].size(); ++i) {
    objects.push_back(std::make_unique<fcl::CollisionObjectd>(model, fcl_transform(flight[0][i])));
    objects.back()->setUserData(reinterpret_cast<void*>(std::uintptr_t(i)));
    manager.registerObject(objects.back().get());
  }
  manager.setup();
  Run run;
  FclPairs found;
  for (const auto& poses : flight) {
    const auto start = Clock::now();
    for (std::size_t i = 0; i < poses.size(); ++i) {
      objects[i]->setTransform(fcl_transform(poses[i]));
      objects[i]->computeAABB();
    }
    manager.update();
    found.pairs.clear();
    manager.collide(&found, collect_pair);
    run.seconds.push_back(std::chrono::duration<double>(Clock::now() - start).count());
    std::sort(found.pairs.begin(), found.pairs.end());
    run.answers.push_back(found.pairs);
  }
  return run;
}

double total(const std::vector<double>& seconds) {
  double sum = 0;
  for (const double s : seconds) sum += s;
  return sum;
}

struct Disagreement {
  std::size_t steps = 0, pairs = 0, colliding_pairs = 0;
};

Disagreement compare(const Run& exact, const Run& fcl) {
  Disagreement d;
  for (std::size_t s = 0; s < exact.answers.size(); ++s) {
    PairSet differ;
    std::set_symmetric_difference(exact.answers[s].begin(), exact.answers[s].end(),
                                  fcl.answers[s].begin(), fcl.answers[s].end(),
                                  std::back_inserter(differ));
    d.steps += !differ.empty();
    d.pairs += differ.size();
    d.colliding_pairs += exact.answers[s].size();
  }
  return d;
}

}  // namespace
}  // namespace tetrapage

int main(int argc, char** argv) {
  using namespace tetrapage;
  CLI::App app{
      "N copies of an object checked against each other: tetrapage's ObjectGroup vs FCL's "
      "DynamicAABBTreeCollisionManager"};
  std::vector<std::size_t> counts{2, 8, 64};
  std::size_t steps = 500, repeats = 3;
  std::uint64_t triangles = 1000, seed = 1;
  std::string report;
  app.add_option("--counts", counts, "numbers of objects")->delimiter(',');
  app.add_option("--steps", steps, "steps of the random walk")->check(CLI::PositiveNumber);
  app.add_option("--triangles", triangles, "triangles of the object (tetrapage generate object)")
      ->check(CLI::PositiveNumber);
  app.add_option("--repeats", repeats, "times each run is repeated (noise)")
      ->check(CLI::PositiveNumber);
  app.add_option("--seed", seed, "seed of the random walk");
  app.add_option("--report", report, "write the figures as JSON");
  CLI11_PARSE(app, argc, argv);
  try {
    std::optional<MeshLibrary> library;
    if (object_needs_meshes(triangles)) library = MeshLibrary::load_default();
    ObjectOptions object_options;
    object_options.triangles = triangles;
    const GeneratedObject object = generate_object(object_options, library ? &*library : nullptr);
    const auto model = std::make_shared<const ObjectModel>(object.soup);
    std::printf("object: %s, %zu triangles, size %g; %zu steps, %zu repeats\n\n",
                object.source.c_str(), object.soup.triangle_count(), object_options.size, steps,
                repeats);
    std::printf(
        "| N | colliding pairs/step | tetrapage steps/s | p50 us | p99 us | FCL steps/s | p50 us | "
        "p99 us | "
        "FCL/tetrapage time | disagreeing steps (pairs) "
        "|\n|---|---|---|---|---|---|---|---|---|---|\n");
    nlohmann::json runs = nlohmann::json::array();
    for (const std::size_t n : counts) {
      const Flight flight = random_walk(n, steps, object_options.size, seed + n);
      for (std::size_t r = 0; r < repeats; ++r) {
        // Alternate which runs first, so that neither always gets the warmer caches.
        Run ours, theirs;
        if (r % 2 == 0)
          ours = run_tetrapage(model, flight), theirs = run_fcl(object.soup, flight);
        else
          theirs = run_fcl(object.soup, flight), ours = run_tetrapage(model, flight);
        const auto a = LatencySummary::of(ours.seconds), b = LatencySummary::of(theirs.seconds);
        const double ta = total(ours.seconds), tb = total(theirs.seconds);
        const Disagreement d = compare(ours, theirs);
        std::printf("| %zu | %.2f | %.0f | %.1f | %.1f | %.0f | %.1f | %.1f | %.2f | %zu (%zu) |\n",
                    n, double(d.colliding_pairs) / double(steps), double(steps) / ta, a.p50_us,
                    a.p99_us, double(steps) / tb, b.p50_us, b.p99_us, tb / ta, d.steps, d.pairs);
        runs.push_back(
            {{"objects", n},
             {"repeat", r},
             {"steps", steps},
             {"colliding_pairs", d.colliding_pairs},
             {"tetrapage", {{"steps_per_second", double(steps) / ta}, {"latency_us", a.to_json()}}},
             {"fcl", {{"steps_per_second", double(steps) / tb}, {"latency_us", b.to_json()}}},
             {"fcl_over_tetrapage_time", tb / ta},
             {"disagreeing_steps", d.steps},
             {"disagreeing_pairs", d.pairs}});
      }
    }
    if (!report.empty()) {
      std::ofstream out(report);
      out << nlohmann::json{{"object", object.source},
                            {"triangles", object.soup.triangle_count()},
                            {"runs", runs}}
                 .dump(2)
          << "\n";
      if (!out) throw IoError("cannot write " + report);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tetrapage_bench_group: %s\n", e.what());
    return 1;
  }
  return 0;
}
