// Dynamic obstacles (DynamicObstacles.h): the latency of insert, move and remove, and what the
// overlay costs a flight's steps. The index preloaded (everything in memory); the parts are
// copies of one mesh (PART, ~100 triangles) of --part-size times the mesh box's longest side,
// scattered at random poses in the mesh box.
//  latency  N parts inserted one by one (a shared model, and from the mesh: the model built),
//           each moved by a small step, then removed: median and 99th percentile
//  steps    the flight replayed by one FlyingObject (exact, first hit) with no overlay and with
//           0, 1, 100, 10,000 parts standing still, and with one of them moved every step
//           (a new version every step: the free box is dropped); steps/s per repetition
//
//   tetrapage_bench_dynamic INDEX OBJECT PART FLIGHT [--repeat 3] [--steps K] [--part-size 0.01]

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/runtime/paging/CollisionIndex.h"
#include "tetrapage/runtime/query/DynamicObstacles.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/tools/Random.h"

namespace {

using namespace tetrapage;
using Clock = std::chrono::steady_clock;

double micros_since(Clock::time_point start) {
  return std::chrono::duration<double, std::micro>(Clock::now() - start).count();
}

double percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  return values[std::min(values.size() - 1, std::size_t(q * double(values.size())))];
}

// The mesh scaled about its box's centre to `size` (its longest side).
TriangleSoup fitted(TriangleSoup mesh, double size) {
  BoundingBox box;
  for (const auto& v : mesh.vertices) box.extend(v);
  const double side = std::max({box.hi[0] - box.lo[0], box.hi[1] - box.lo[1], box.hi[2] - box.lo[2]});
  for (auto& v : mesh.vertices)
    for (int a = 0; a < 3; ++a) v[a] = (v[a] - (box.lo[a] + box.hi[a]) / 2) * size / side;
  return mesh;
}

struct Scatter {
  const BoundingBox& bounds;
  Random random;
  Pose operator()() {
    Pose pose;
    for (int a = 0; a < 3; ++a) pose.translation[a] = random.uniform(bounds.lo[a], bounds.hi[a]);
    pose.rotation = unit_quaternion({random.normal(), random.normal(), random.normal(), random.normal()});
    return pose;
  }
  Pose nudged(Pose pose, double by) {
    for (int a = 0; a < 3; ++a) pose.translation[a] += random.uniform(-by, by);
    return pose;
  }
};

void print_latency(const char* what, const std::vector<double>& us) {
  std::printf("  %-28s median %8.2f us   p99 %8.2f us   (%zu)\n", what, percentile(us, 0.5), percentile(us, 0.99),
              us.size());
}

// Insert, move, remove of `count` parts, and inserts that build the model from the mesh.
void measure_latency(const std::shared_ptr<const CollisionIndex>& index, const TriangleSoup& part, double step,
                     std::size_t count) {
  DynamicObstacles overlay(index);
  Scatter scatter{index->mesh_bounds(), Random(7)};
  const auto model = std::make_shared<const ObjectModel>(part);
  std::vector<double> insert_us, build_us, move_us, remove_us;
  std::vector<DynamicPartId> ids;
  for (std::size_t k = 0; k < count; ++k) {
    const Pose pose = scatter();
    const auto start = Clock::now();
    ids.push_back(overlay.insert(model, pose));
    insert_us.push_back(micros_since(start));
  }
  for (std::size_t k = 0; k < std::min<std::size_t>(count, 1000); ++k) {
    const Pose pose = scatter();
    const auto start = Clock::now();
    const DynamicPartId id = overlay.insert(part, pose);
    build_us.push_back(micros_since(start));
    overlay.remove(id);
  }
  for (const DynamicPartId id : ids) {
    const Pose pose = scatter.nudged(overlay.find(id)->pose, step);
    const auto start = Clock::now();
    overlay.move(id, pose);
    move_us.push_back(micros_since(start));
  }
  for (const DynamicPartId id : ids) {
    const auto start = Clock::now();
    overlay.remove(id);
    remove_us.push_back(micros_since(start));
  }
  std::printf("latency with up to %zu parts:\n", count);
  print_latency("insert (shared model)", insert_us);
  print_latency("insert (model built)", build_us);
  print_latency("move (small step)", move_us);
  print_latency("remove", remove_us);
}

// Steps per second over the flight with `overlay` (null: none); `mover` moves one part per step.
double steps_per_second(const std::shared_ptr<const CollisionIndex>& index, const TriangleSoup& object,
                        const std::vector<Pose>& poses, std::shared_ptr<DynamicObstacles> overlay, bool move_one,
                        std::size_t& collisions) {
  FlyingObject flying(index, object);
  if (overlay) flying.set_obstacles(overlay);
  Scatter scatter{index->mesh_bounds(), Random(3)};
  const DynamicPartId moved = overlay && overlay->size() > 0 ? overlay->parts()[0].id : kNoDynamicPart;
  QueryResult result;
  collisions = 0;
  const auto start = Clock::now();
  for (const Pose& pose : poses) {
    if (move_one && moved != kNoDynamicPart) overlay->move(moved, scatter.nudged(overlay->find(moved)->pose, 1e-4));
    flying.query(pose, {}, result);
    collisions += result.collides;
  }
  return double(poses.size()) / (micros_since(start) * 1e-6);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("Dynamic obstacles: insert/move/remove latency, and steps/s of a flight with 0 to 10,000 parts");
  std::string index_path, object_path, part_path, flight_path;
  std::size_t repeat = 3, limit = 0;
  double part_size = 0.01;
  app.add_option("index", index_path, "Index (.tpi)")->required()->check(CLI::ExistingFile);
  app.add_option("object", object_path, "Flying object mesh")->required()->check(CLI::ExistingFile);
  app.add_option("part", part_path, "Dynamic part mesh (~100 triangles)")->required()->check(CLI::ExistingFile);
  app.add_option("flight", flight_path, "Pose file (CSV tx,ty,tz,qw,qx,qy,qz)")->required()->check(CLI::ExistingFile);
  app.add_option("--repeat", repeat, "Repetitions of each measurement")->check(CLI::PositiveNumber);
  app.add_option("--steps", limit, "Only the first K poses (0: all)");
  app.add_option("--part-size", part_size, "A part's longest side, as a fraction of the mesh box's");
  CLI11_PARSE(app, argc, argv);
  try {
    CollisionIndexOptions options;
    options.memory_budget_bytes = std::uint64_t(1) << 40;
    options.prefetch = false;
    auto index = std::make_shared<const CollisionIndex>(index_path, options);
    index->preload();
    std::vector<Pose> poses = read_poses(flight_path);
    if (limit > 0 && limit < poses.size()) poses.resize(limit);
    const TriangleSoup object = read_mesh(object_path);
    const BoundingBox& bounds = index->mesh_bounds();
    const double side = std::max({bounds.hi[0] - bounds.lo[0], bounds.hi[1] - bounds.lo[1], bounds.hi[2] - bounds.lo[2]});
    const TriangleSoup part = fitted(read_mesh(part_path), part_size * side);
    std::printf("part: %zu triangles, %.4g wide; flight: %zu steps\n", part.triangles.size(), part_size * side,
                poses.size());
    for (std::size_t r = 0; r < repeat; ++r) measure_latency(index, part, part_size * side * 0.01, 10000);
    const auto model = std::make_shared<const ObjectModel>(part);
    std::printf("\n%-24s", "steps/s");
    for (std::size_t r = 0; r < repeat; ++r) std::printf("  run %-8zu", r + 1);
    std::printf("  collisions\n");
    auto row = [&](const std::string& name, std::size_t parts, bool overlay_on, bool move_one) {
      std::printf("%-24s", name.c_str());
      std::size_t collisions = 0;
      for (std::size_t r = 0; r < repeat; ++r) {
        std::shared_ptr<DynamicObstacles> overlay;
        if (overlay_on) {
          overlay = std::make_shared<DynamicObstacles>(index);
          Scatter scatter{bounds, Random(11)};
          for (std::size_t k = 0; k < parts; ++k) overlay->insert(model, scatter());
        }
        std::printf("  %-12.0f", steps_per_second(index, object, poses, overlay, move_one, collisions));
        std::fflush(stdout);
      }
      std::printf("  %zu\n", collisions);
    };
    row("no overlay", 0, false, false);
    for (const std::size_t n : {0, 1, 100, 10000}) row(std::to_string(n) + " parts", n, true, false);
    for (const std::size_t n : {1, 100, 10000}) row(std::to_string(n) + " parts, 1 moving", n, true, true);
    return 0;
  } catch (const Error& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
