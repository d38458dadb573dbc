// Several flying objects, each from its own thread, through one index under a shared budget
// (two of them instances of one shared ObjectModel): the same answers as one thread alone, and
// the budget holds. Lean on purpose (no generators,
// no oracle library): `make test` also runs it in an AddressSanitizer + UBSan build.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <thread>

#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/preprocess/Preprocess.h"
#include "tetrapage/runtime/query/FlyingObject.h"

namespace tetrapage {
namespace {

namespace fs = std::filesystem;

// Random small tetrahedra in the unit cube (as triangles), and an octahedron object.
TriangleSoup tetrahedra(std::size_t count, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> unit(0, 1), small(-0.03, 0.03);
  TriangleSoup soup;
  soup.part_names = {"tetrahedra"};
  for (std::size_t k = 0; k < count; ++k) {
    const Vec3 c{unit(random), unit(random), unit(random)};
    const auto base = std::uint32_t(soup.vertices.size());
    for (int v = 0; v < 4; ++v) soup.vertices.push_back({c[0] + small(random), c[1] + small(random), c[2] + small(random)});
    for (const auto& t : {std::array<std::uint32_t, 3>{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}})
      soup.triangles.push_back({base + t[0], base + t[1], base + t[2]});
  }
  soup.part_of.assign(soup.triangles.size(), 0);
  return soup;
}

TriangleSoup octahedron(double r) {
  TriangleSoup soup;
  soup.part_names = {"octahedron"};
  soup.vertices = {{r, 0, 0}, {-r, 0, 0}, {0, r, 0}, {0, -r, 0}, {0, 0, r}, {0, 0, -r}};
  soup.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  soup.part_of.assign(8, 0);
  return soup;
}

std::vector<Pose> random_walk(std::size_t steps, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> step(-0.01, 0.01), angle(-0.1, 0.1);
  std::vector<Pose> poses;
  Pose pose;
  pose.translation = {0.5, 0.5, 0.5};
  double yaw = 0;
  for (std::size_t i = 0; i < steps; ++i) {
    for (auto& t : pose.translation) t = std::clamp(t + step(random), 0.02, 0.98);
    yaw += angle(random);
    pose.rotation = {std::cos(yaw / 2), 0, 0, std::sin(yaw / 2)};
    poses.push_back(pose);
  }
  return poses;
}

// The index of tetrahedra(1500, 3) in `name`/tetrahedra.tpi, exact, in regions of 150 triangles.
fs::path tetrahedra_index(const std::string& name) {
  const fs::path folder = fs::path(TETRAPAGE_TEST_TMP) / name;
  fs::remove_all(folder);
  fs::create_directories(folder);
  write_mesh(folder / "tetrahedra.ply", tetrahedra(1500, 3));
  PreprocessOptions options;
  options.region_triangles = 150;
  options.precision = StoredPrecision::float64;
  preprocess({folder / "tetrahedra.ply"}, folder / "tetrahedra.tpi", options);
  return folder;
}

TEST(FlyingThreads, SeveralObjectsAgreeWithOneUnderASharedBudget) {
  const fs::path folder = tetrahedra_index("flying-threads");

  const TriangleSoup object = octahedron(0.04);
  const std::vector<Pose> poses = random_walk(600, 5);
  std::vector<std::uint8_t> alone;
  {
    auto index = std::make_shared<const CollisionIndex>(folder / "tetrahedra.tpi");
    FlyingObject flying(index, object);
    for (const Pose& pose : poses) alone.push_back(flying.query(pose).collides);
  }
  std::size_t collisions = 0;
  for (auto a : alone) collisions += a;
  ASSERT_GT(collisions, 10u);
  ASSERT_LT(collisions, poses.size() - 10);

  CollisionIndexOptions shared;
  shared.memory_budget_bytes = std::make_shared<const CollisionIndex>(folder / "tetrahedra.tpi")->total_shard_bytes() / 6;
  auto index = std::make_shared<const CollisionIndex>(folder / "tetrahedra.tpi", shared);
  constexpr int kThreads = 4;
  std::vector<std::vector<std::uint8_t>> answers(kThreads, std::vector<std::uint8_t>(poses.size()));
  std::vector<std::thread> threads;
  // Threads 1 and 3 fly instances of one shared model; 0 and 2 build their own.
  const auto shared_model = std::make_shared<const ObjectModel>(object);
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t] {
      FlyingObject flying = t % 2 == 1 ? FlyingObject(index, shared_model) : FlyingObject(index, object);
      QueryOptions query;
      query.mode = t % 2 == 0 ? QueryMode::first_hit : QueryMode::all_contacts;
      QueryResult result;
      for (std::size_t k = 0; k < poses.size(); ++k) {
        const std::size_t i = (k + std::size_t(t) * poses.size() / kThreads) % poses.size();
        for (int attempt = 0;; ++attempt) {
          try {
            flying.query(poses[i], query, result);
            break;
          } catch (const InputError&) {
            // The shared budget was momentarily full of the other threads' pins.
            if (attempt == 3) throw;
          }
        }
        answers[t][i] = result.collides;
      }
    });
  for (auto& thread : threads) thread.join();
  for (int t = 0; t < kThreads; ++t) EXPECT_EQ(answers[t], alone) << "thread " << t;
  EXPECT_LE(index->cache().peak_resident_bytes(), shared.memory_budget_bytes);
}

// The shards' id ranges are read on the first id lookup, here while another thread pages shards
// in under a small budget (HDF5 is not thread-safe): every lookup finds the triangle written.
TEST(FlyingThreads, IdLookupsWhileAnotherThreadPagesIn) {
  const fs::path folder = tetrahedra_index("flying-threads-lookups");
  const TriangleSoup soup = tetrahedra(1500, 3);
  CollisionIndexOptions paged;
  paged.memory_budget_bytes = CollisionIndex(folder / "tetrahedra.tpi").total_shard_bytes() / 6;
  auto index = std::make_shared<const CollisionIndex>(folder / "tetrahedra.tpi", paged);
  std::thread flier([&] {
    FlyingObject flying(index, octahedron(0.04));
    for (const Pose& pose : random_walk(600, 5)) {
      for (int attempt = 0;; ++attempt) {
        try {
          flying.query(pose);
          break;
        } catch (const InputError&) {
          if (attempt == 3) throw;  // the budget was momentarily full of the lookups' pins
        }
      }
    }
  });
  std::mt19937_64 random(7);
  for (int k = 0; k < 200; ++k) {
    const std::uint64_t id = random() % soup.triangle_count();
    const auto stored = index->stored_triangle(id);
    ASSERT_TRUE(stored) << id;
    EXPECT_EQ(stored->corners, soup.corners(id)) << id;
  }
  flier.join();
}

}  // namespace
}  // namespace tetrapage
