// The paged runtime against the exact oracle (tools' ReferenceCollider: CGAL AABB tree with
// Epick predicates, sharing no code with the runtime) on billiard flights through scenes,
// tetras and terrains; a tight budget gives the same answers and never exceeds itself;
// several threads agree with one; bad poses and damaged indexes fail cleanly.

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <future>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <thread>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/index/IndexReader.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/formats/mesh/SurfaceComponents.h"
#include "tetrapage/preprocess/Preprocess.h"
#include "tetrapage/runtime/geometry/TriangleBox.h"
#include "tetrapage/runtime/geometry/TriangleTriangle.h"
#include "tetrapage/runtime/paging/ShardArena.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/tools/FlightGenerator.h"
#include "tetrapage/tools/MeshLibrary.h"
#include "tetrapage/tools/ObjectGenerator.h"
#include "tetrapage/tools/ReferenceCollider.h"
#include "tetrapage/tools/SceneGenerator.h"
#include "tetrapage/tools/StudyEnvironment.h"
#include "tetrapage/tools/TerrainGenerator.h"
#include "tetrapage/tools/TetrasGenerator.h"

namespace tetrapage {
namespace {

namespace fs = std::filesystem;

const MeshLibrary& library() {
  static const MeshLibrary instance = MeshLibrary::load_default();
  return instance;
}

struct World {
  fs::path environment_path, index_path;
  TriangleSoup environment, object;
  Flight flight;
};

using Kind = EnvironmentKind;

// Generates an environment and an object, preprocesses (the default storage: the stored
// geometry is the input's, so exact answers must equal the oracle's), and flies a billiard
// path. A scene opens `open_fraction` of its copies (one file of closed and open solids).
World make_world(Kind kind, std::uint64_t triangles, std::uint64_t object_triangles, std::size_t steps,
                 std::uint64_t seed, std::size_t region_triangles = 400, double open_fraction = 0) {
  const std::string name = to_string(kind);
  // One folder per test: ctest runs the tests of this file in parallel.
  const std::string test_name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
  const fs::path folder = fs::path(TETRAPAGE_TEST_TMP) / "flying" / test_name / (name + std::to_string(seed));
  fs::remove_all(folder);
  fs::create_directories(folder);
  World world;
  world.environment_path = folder / "environment.ply";
  {
    MeshWriter writer(world.environment_path);
    if (kind == Kind::scene && open_fraction > 0) {
      SceneOptions scene;
      scene.triangles = triangles;
      scene.seed = seed;
      scene.open_fraction = open_fraction;
      generate_scene(library(), scene, writer);
    } else {
      generate_environment(kind, triangles, seed, writer);
    }
    writer.commit();
  }
  world.environment = read_mesh(world.environment_path);
  ObjectOptions object_options;
  object_options.triangles = object_triangles;
  object_options.seed = seed;
  world.object = generate_object(object_options, &library()).soup;
  const ReferenceCollider oracle(world.environment, world.object);
  FlightOptions flight_options;
  flight_options.steps = steps;
  flight_options.seed = seed;
  world.flight = generate_billiard_flight(oracle, flight_options);
  world.index_path = folder / "environment.tpi";
  PreprocessOptions options;
  options.region_triangles = region_triangles;
  // Interiors too: the oracle counts an object inside a closed obstacle as a collision.
  options.interiors = true;
  preprocess({world.environment_path}, world.index_path, options);
  return world;
}

std::vector<std::uint8_t> fly(const World& world, CollisionIndexOptions options, std::uint64_t* peak = nullptr) {
  auto index = std::make_shared<const CollisionIndex>(world.index_path, options);
  FlyingObject object(index, world.object);
  std::vector<std::uint8_t> answers;
  QueryResult result;
  for (const Pose& pose : world.flight.poses) {
    object.query(pose, {}, result);
    answers.push_back(result.collides ? 1 : 0);
    // The budget is a promise at every step.
    EXPECT_LE(index->cache().peak_resident_bytes(), options.memory_budget_bytes);
  }
  if (peak) *peak = index->cache().peak_resident_bytes();
  return answers;
}

void expect_same_answers(const std::vector<std::uint8_t>& got, const World& world, const std::string& what) {
  ASSERT_EQ(got.size(), world.flight.collides.size());
  std::size_t wrong = 0, collisions = 0;
  for (std::size_t i = 0; i < got.size(); ++i) {
    collisions += world.flight.collides[i];
    if (got[i] != world.flight.collides[i] && ++wrong <= 5)
      ADD_FAILURE() << what << ": step " << i << " runtime " << int(got[i]) << " oracle " << int(world.flight.collides[i]);
  }
  EXPECT_EQ(wrong, 0u) << what;
  EXPECT_GT(collisions, 0u) << what << ": the flight must test collisions, not only free space";
}

TEST(FlyingObject, ExactAnswersEqualTheOracleOnScenesTetrasAndTerrains) {
  const World scene = make_world(Kind::scene, 30000, 500, 1500, 1);
  expect_same_answers(fly(scene, {}), scene, "scene");
  const World tetras = make_world(Kind::tetras, 4000, 116, 1500, 2, 200);
  // The study's sphere is pruned by the ball around it in phase I: these flights check it.
  EXPECT_TRUE(ObjectModel(tetras.object).ball_prunes);
  EXPECT_FALSE(ObjectModel(scene.object).ball_prunes);
  expect_same_answers(fly(tetras, {}), tetras, "tetras");
  const World terrain = make_world(Kind::terrain, 8000, 116, 1500, 3);
  expect_same_answers(fly(terrain, {}), terrain, "terrain");
}

// A file of closed solids and open shells (as CAD exports are), in default settings: billiard
// flights of a closed object through it, and of the same object over a terrain (open).
TEST(FlyingObject, ExactAnswersEqualTheOracleOnAFileOfClosedAndOpenSolids) {
  const World mixed = make_world(Kind::scene, 30000, 500, 1500, 1, 400, 0.5);
  const SurfaceComponents split = find_surface_components(mixed.environment);
  const std::size_t closed = split.closed_count();
  EXPECT_GT(closed, 0u);
  EXPECT_LT(closed, split.components.size()) << "some copies must be open";
  expect_same_answers(fly(mixed, {}), mixed, "mixed scene");
  const World terrain = make_world(Kind::terrain, 8000, 2000, 1500, 5);
  expect_same_answers(fly(terrain, {}), terrain, "closed object over a terrain");
}

TEST(FlyingObject, StepsInFreeBoxesAgreeWithTheOracle) {
  // Most billiard steps are far from obstacles: they find a box around them that holds no
  // triangle, or lie in the last one found, and skip phase I. Their answers are the oracle's.
  const World scene = make_world(Kind::scene, 30000, 500, 2000, 13);
  auto index = std::make_shared<const CollisionIndex>(scene.index_path);
  FlyingObject object(index, scene.object);
  std::vector<std::uint8_t> answers;
  std::size_t in_free_box = 0, found_free_box = 0;
  QueryResult result;
  for (const Pose& pose : scene.flight.poses) {
    object.query(pose, {}, result);
    answers.push_back(result.collides ? 1 : 0);
    if (result.counters.in_free_box) {
      ++in_free_box;
      EXPECT_EQ(result.counters.shards_touched, 0u);
    }
    found_free_box += result.counters.found_free_box;
    EXPECT_FALSE(result.counters.in_free_box && result.collides);
  }
  expect_same_answers(answers, scene, "scene");
  EXPECT_GT(in_free_box, scene.flight.poses.size() / 4) << "steps inside a free box";
  EXPECT_GT(found_free_box, scene.flight.poses.size() / 20) << "steps that found a free box";
}

/// The object's triangles placed at `pose` (apply_pose, as the oracle places them), and
/// their box.
std::vector<geometry::Triangle> placed_triangles(const TriangleSoup& object, const Pose& pose, geometry::Box& box) {
  std::vector<geometry::Triangle> placed(object.triangle_count());
  for (std::uint32_t k = 0; k < object.triangle_count(); ++k) {
    const auto o = object.triangles[k];
    placed[k] = {apply_pose(pose, object.vertices[o[0]]), apply_pose(pose, object.vertices[o[1]]),
                 apply_pose(pose, object.vertices[o[2]])};
    for (const auto& p : placed[k]) box.extend(p);
  }
  return placed;
}

/// Checks every step's contacts; adds the repeats the steps skipped (StepCounters) to `repeats`.
void check_all_contacts(const World& world, std::uint64_t& repeats) {
  auto index = std::make_shared<const CollisionIndex>(world.index_path);
  FlyingObject object(index, world.object);
  QueryOptions all;
  all.mode = QueryMode::all_contacts;
  for (std::size_t i = 0; i < world.flight.poses.size(); ++i) {
    const Pose& pose = world.flight.poses[i];
    const QueryResult first = object.query(pose);
    const QueryResult every = object.query(pose, all);
    // A triangle that several of the step's shards hold is a candidate once: never more
    // candidates than triangles whose boxes meet the step's box (phase I's own test).
    std::size_t meeting = 0;
    for (std::size_t t = 0; t < world.environment.triangle_count(); ++t)
      meeting += geometry::boxes_overlap(geometry::box_of(world.environment.corners(t)), every.world_box);
    EXPECT_LE(every.counters.candidates, meeting) << "step " << i;
    repeats += every.counters.repeats;
    ASSERT_EQ(first.collides, every.collides);
    ASSERT_EQ(every.collides, !every.contacts.empty());
    if (!every.collides) continue;
    // Each contact pair really touches (exact test on the same world coordinates), and
    // none is repeated.
    std::set<std::pair<std::uint64_t, std::uint32_t>> seen;
    for (const Contact& c : every.contacts) {
      EXPECT_TRUE(seen.insert({c.environment_triangle, c.object_triangle}).second);
      const auto e = world.environment.corners(c.environment_triangle);
      const auto o = world.object.triangles[c.object_triangle];
      const geometry::Triangle placed{apply_pose(pose, world.object.vertices[o[0]]),
                                      apply_pose(pose, world.object.vertices[o[1]]),
                                      apply_pose(pose, world.object.vertices[o[2]])};
      EXPECT_TRUE(geometry::triangles_intersect(e, placed)) << "step " << i;
    }
    // Brute force over every environment triangle near the placed object (its box from its
    // own placed vertices, not the runtime's): the same number of pairs.
    geometry::Box box;
    const std::vector<geometry::Triangle> placed = placed_triangles(world.object, pose, box);
    std::size_t expected = 0;
    for (std::size_t t = 0; t < world.environment.triangle_count(); ++t) {
      const auto e = world.environment.corners(t);
      if (!geometry::boxes_overlap(geometry::box_of(e), box)) continue;
      for (const auto& o : placed) expected += geometry::triangles_intersect(e, o);
    }
    EXPECT_EQ(every.contacts.size(), expected) << "step " << i;
  }
}

TEST(FlyingObject, AllContactsAgreeWithBruteForceAndFirstHit) {
  std::uint64_t repeats = 0;
  check_all_contacts(make_world(Kind::scene, 10000, 116, 400, 4, 200), repeats);
  // A larger object meets triangles that several regions' shards hold: each pair is still
  // reported once, and the steps skipped repeats (so the bound on the candidates tested
  // something).
  repeats = 0;
  check_all_contacts(make_world(Kind::scene, 30000, 2000, 300, 12, 200), repeats);
  EXPECT_GT(repeats, 0u);
}

TEST(FlyingObject, ANearlyUnitQuaternionAnswersAsItsNormalisedPose) {
  // A caller's quaternion may be off unit norm by up to 1e-6 in its square (a float's
  // rounding): its matrix would stretch the object beyond the pruning margins, so
  // rotation_matrix normalises it, and the step answers as the oracle does for the unit pose.
  const World world = make_world(Kind::tetras, 4000, 500, 1500, 21, 200);
  auto index = std::make_shared<const CollisionIndex>(world.index_path);
  FlyingObject object(index, world.object);
  std::vector<std::uint8_t> answers;
  for (std::size_t i = 0; i < world.flight.poses.size(); ++i) {
    Pose stretched = world.flight.poses[i];
    const double scale = i % 2 == 0 ? 1 + 4e-7 : 1 - 4e-7;
    for (double& component : stretched.rotation) component *= scale;
    const QueryResult result = object.query(stretched);
    answers.push_back(result.collides ? 1 : 0);
    for (const auto& v : world.object.vertices) {
      const Vec3 placed = apply_pose(world.flight.poses[i], v);
      for (int a = 0; a < 3; ++a) {
        ASSERT_LE(result.world_box.lo[a], placed[a]) << "step " << i;
        ASSERT_GE(result.world_box.hi[a], placed[a]) << "step " << i;
      }
    }
  }
  expect_same_answers(answers, world, "stretched quaternions");
}

// Within a clearance d, every pair the brute force finds within d (the same triangle test) is
// reported, and no other.
void expect_clearance_contacts_equal_brute_force(const World& world) {
  auto index = std::make_shared<const CollisionIndex>(world.index_path);
  FlyingObject object(index, world.object);
  QueryOptions options;
  options.mode = QueryMode::all_contacts;
  std::size_t near_steps = 0;
  for (const double d : {1e-3, 5e-3}) {
    options.accuracy = geometry::Accuracy::within(d);
    for (std::size_t i = 0; i < world.flight.poses.size(); ++i) {
      const Pose& pose = world.flight.poses[i];
      const QueryResult result = object.query(pose, options);
      geometry::Box box;
      const std::vector<geometry::Triangle> placed = placed_triangles(world.object, pose, box);
      box = geometry::inflated(box, 2 * d);
      std::set<std::pair<std::uint64_t, std::uint32_t>> expected, got;
      for (std::size_t t = 0; t < world.environment.triangle_count(); ++t) {
        const auto e = world.environment.corners(t);
        if (!geometry::boxes_overlap(geometry::box_of(e), box)) continue;
        for (std::uint32_t k = 0; k < placed.size(); ++k)
          if (geometry::triangles_collide(e, placed[k], options.accuracy)) expected.insert({t, k});
      }
      for (const Contact& c : result.contacts) got.insert({c.environment_triangle, c.object_triangle});
      EXPECT_EQ(got, expected) << "step " << i << ", clearance " << d;
      near_steps += !expected.empty();
    }
  }
  EXPECT_GT(near_steps, 20u) << "the flight must come within the clearance of obstacles";
}

TEST(FlyingObject, ClearanceContactsOfPrunedObjectsEqualBruteForce) {
  // The sphere is pruned by its ball, the tetrahedron by its hull's planes, both placed in the
  // world and in the object's frame.
  const World sphere = make_world(Kind::scene, 10000, 116, 1500, 5, 200);
  ASSERT_TRUE(ObjectModel(sphere.object).ball_prunes);
  expect_clearance_contacts_equal_brute_force(sphere);
  const World tetrahedron = make_world(Kind::scene, 30000, 4, 1500, 6, 200);
  ASSERT_FALSE(ObjectModel(tetrahedron.object).hull_planes.empty());
  expect_clearance_contacts_equal_brute_force(tetrahedron);
}

// Real shards decoded into an arena: the same shards, their arrays in the arena, and their bytes
// counted as the arena's blocks (at least what they hold, at most an eighth more, or a 64-byte
// step for each of a shard's 13 arrays).
TEST(FlyingObject, ShardsDecodeIntoTheArenaAlike) {
  const World world = make_world(Kind::scene, 30000, 500, 50, 11, 200);
  const IndexReader reader(world.index_path);
  ShardArena arena(std::size_t(64) << 20, 0);
  ASSERT_GT(reader.shard_count(), 0u);
  std::size_t plain_bytes = 0, kept_bytes = 0;
  for (std::uint32_t s = 0; s < reader.shard_count(); ++s) {
    const std::vector<std::byte> payload = reader.read_shard(s);
    const Shard plain = Shard::decode(payload);
    const Shard kept = Shard::decode(payload, "shard", DecodeChecks::structure, &arena);
    ASSERT_EQ(kept.triangle_count(), plain.triangle_count()) << "shard " << s;
    for (std::uint32_t t = 0; t < plain.triangle_count(); ++t) {
      ASSERT_EQ(kept.triangle(t), plain.triangle(t)) << "shard " << s;
      ASSERT_EQ(kept.triangle_id(t), plain.triangle_id(t)) << "shard " << s;
    }
    EXPECT_GE(kept.memory_bytes(), plain.memory_bytes()) << "shard " << s;
    EXPECT_LE(8 * kept.memory_bytes(), 9 * plain.memory_bytes() + 8 * 13 * 64) << "shard " << s;
    plain_bytes += plain.memory_bytes();
    kept_bytes += kept.memory_bytes();
  }
#if !defined(__SANITIZE_ADDRESS__)  // there the arena leaves everything to malloc
  EXPECT_GT(arena.arena_blocks(), 0u);
  EXPECT_GT(kept_bytes, plain_bytes);  // the blocks' slack is counted
#endif
}

TEST(FlyingObject, ATightBudgetGivesTheSameAnswersWithinItself) {
  const World world = make_world(Kind::scene, 30000, 500, 1500, 5, 200);
  const std::vector<std::uint8_t> unlimited = fly(world, {});
  auto probe = std::make_shared<const CollisionIndex>(world.index_path);
  CollisionIndexOptions tight;
  tight.memory_budget_bytes = probe->total_shard_bytes() / 20;  // 5 %
  std::uint64_t peak = 0;
  // No prefetcher; the region's shards; and the next region's; shards in malloc's memory
  // instead of the arena; the prefetcher with waits that sleep at once.
  for (const int variant : {0, 1, 2, 3, 4}) {
    tight.prefetch = variant == 1 || variant == 2 || variant == 4;
    tight.prefetch_ahead = variant == 2;
    tight.shard_arena = variant != 3;
    tight.spin_before_sleep = variant == 4 ? std::chrono::microseconds(0) : std::chrono::microseconds(200);
    const std::vector<std::uint8_t> paged = fly(world, tight, &peak);
    EXPECT_EQ(paged, unlimited) << "variant " << variant;
    EXPECT_LE(peak, tight.memory_budget_bytes);
    EXPECT_GT(peak, 0u);
  }
  expect_same_answers(unlimited, world, "unlimited");
}

TEST(FlyingObject, SeveralThreadsAgreeWithOne) {
  const World world = make_world(Kind::scene, 20000, 116, 800, 6, 200);
  const std::vector<std::uint8_t> alone = fly(world, {});
  CollisionIndexOptions options;
  options.memory_budget_bytes = std::make_shared<const CollisionIndex>(world.index_path)->total_shard_bytes() / 8;
  auto index = std::make_shared<const CollisionIndex>(world.index_path, options);
  constexpr int kThreads = 3;
  std::vector<std::vector<std::uint8_t>> answers(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t] {
      FlyingObject object(index, world.object);
      QueryResult result;
      // Each thread flies the path from a different start, wrapping around.
      const std::size_t n = world.flight.poses.size();
      answers[t].assign(n, 0);
      for (std::size_t k = 0; k < n; ++k) {
        const std::size_t i = (k + std::size_t(t) * n / kThreads) % n;
        try {
          object.query(world.flight.poses[i], {}, result);
        } catch (const InputError&) {
          // The budget may be too small for all threads' pins at once; retry alone.
          object.query(world.flight.poses[i], {}, result);
        }
        answers[t][i] = result.collides;
      }
    });
  for (auto& thread : threads) thread.join();
  for (int t = 0; t < kThreads; ++t) EXPECT_EQ(answers[t], alone) << "thread " << t;
  EXPECT_LE(index->cache().peak_resident_bytes(), options.memory_budget_bytes);
}

TEST(FlyingObject, BadPosesAndFarPoses) {
  const World world = make_world(Kind::tetras, 2000, 4, 50, 7, 200);
  auto index = std::make_shared<const CollisionIndex>(world.index_path);
  FlyingObject object(index, world.object);
  Pose nan_pose;
  nan_pose.translation = {std::nan(""), 0, 0};
  EXPECT_THROW(object.query(nan_pose), InputError);
  Pose bad_rotation;
  bad_rotation.rotation = {2, 0, 0, 0};
  EXPECT_THROW(object.query(bad_rotation), InputError);
  for (const double far : {10.0, -1e6, 1e12}) {
    Pose pose;
    pose.translation = {far, 0.5, 0.5};
    const QueryResult result = object.query(pose);
    EXPECT_FALSE(result.collides);
    EXPECT_TRUE(result.outside_model);
  }
  // Back inside after leaving: the walk restarts and answers again.
  for (std::size_t i = 0; i < world.flight.poses.size(); ++i)
    EXPECT_EQ(object.query(world.flight.poses[i]).collides, bool(world.flight.collides[i])) << i;
}

TEST(FlyingObject, DamagedIndexesFailCleanly) {
  const World world = make_world(Kind::tetras, 2000, 4, 20, 8, 200);
  const fs::path folder = world.index_path.parent_path();
  EXPECT_THROW(CollisionIndex(folder / "missing.tpi"), IoError);
  const auto size = fs::file_size(world.index_path);
  std::vector<char> bytes(size);
  std::ifstream(world.index_path, std::ios::binary).read(bytes.data(), std::streamsize(size));
  for (const double fraction : {0.0, 0.1, 0.5, 0.9, 0.999}) {
    const fs::path truncated = folder / "truncated.tpi";
    std::ofstream(truncated, std::ios::binary).write(bytes.data(), std::streamsize(double(size) * fraction));
    EXPECT_THROW(CollisionIndex{truncated}, Error) << fraction;
  }
  // Bit flips anywhere: opening or flying throws tetrapage::Error, or (a flip in padding or
  // metadata no query reads) every answer is still the oracle's; never a crash.
  std::size_t caught = 0;
  for (std::size_t k = 1; k < 24; ++k) {
    std::vector<char> flipped = bytes;
    flipped[k * size / 24] ^= 0x5a;
    const fs::path path = folder / "flipped.tpi";
    std::ofstream(path, std::ios::binary).write(flipped.data(), std::streamsize(size));
    try {
      auto index = std::make_shared<const CollisionIndex>(path);
      FlyingObject object(index, world.object);
      for (std::size_t i = 0; i < world.flight.poses.size(); ++i)
        ASSERT_EQ(object.query(world.flight.poses[i]).collides, bool(world.flight.collides[i]))
            << "flip at byte " << k * size / 24 << ", step " << i;
    } catch (const Error&) {
      ++caught;
    }
  }
  EXPECT_GT(caught, 0u);  // the flips do reach checked data
}

template <class Body>
void expect_input_error(Body&& body, const std::vector<std::string>& words) {
  try {
    body();
    ADD_FAILURE() << "no InputError; expected one naming " << words.front();
  } catch (const InputError& e) {
    for (const auto& word : words)
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what() << " (expected " << word << ")";
  }
}

// A step that would collect more contacts than QueryOptions::max_contacts is refused naming the
// limit; one at the limit answers in full.
TEST(FlyingObject, AllContactsStopAtTheirLimit) {
  const World world = make_world(Kind::scene, 10000, 116, 200, 7, 200);
  auto index = std::make_shared<const CollisionIndex>(world.index_path);
  FlyingObject object(index, world.object);
  QueryOptions all;
  all.mode = QueryMode::all_contacts;
  all.accuracy =
      geometry::Accuracy::within(0.05);  // a billiard flight keeps clear: a margin meets triangles
  std::size_t busiest = 0;
  Pose busiest_pose;
  for (const Pose& pose : world.flight.poses) {
    const std::size_t found = object.query(pose, all).contacts.size();
    if (found > busiest) busiest = found, busiest_pose = pose;
  }
  ASSERT_GE(busiest, 2u) << "the flight must come near several triangles at once";
  all.max_contacts = busiest;
  EXPECT_EQ(object.query(busiest_pose, all).contacts.size(), busiest);
  all.max_contacts = busiest - 1;
  expect_input_error([&] { object.query(busiest_pose, all); },
                     {"more than " + std::to_string(busiest - 1), "contacts"});
  // The object answers the next step as before.
  all.max_contacts = busiest;
  EXPECT_EQ(object.query(busiest_pose, all).contacts.size(), busiest);
}

// Problems that used to surface at the first query ("mesh walk: point (-nan ...)", "no tet
// reachable", a cache error) are input errors where the bad value is given.
TEST(FlyingObject, BadObjectsPosesAndBudgetsAreRejectedUpFront) {
  const World world = make_world(Kind::tetras, 2000, 4, 20, 10, 200);
  auto index = std::make_shared<const CollisionIndex>(world.index_path);

  TriangleSoup degenerate;  // collinear corners and a repeated corner: no triangle has area
  degenerate.part_names = {"object"};
  degenerate.vertices = {{0, 0, 0}, {0.01, 0.01, 0.01}, {0.02, 0.02, 0.02}, {0.5, 0.1, 0.3}};
  degenerate.triangles = {{0, 1, 2}, {0, 3, 3}, {3, 0, 3}};
  degenerate.part_of = {0, 0, 0};
  expect_input_error([&] { FlyingObject(index, degenerate); }, {"all 3 triangles have zero area"});
  degenerate.triangles.push_back({0, 1, 3});  // one triangle with an area is enough
  degenerate.part_of.push_back(0);
  EXPECT_NO_THROW(FlyingObject(index, degenerate));

  TriangleSoup huge = world.object;
  huge.vertices[1][2] = -1e308;
  expect_input_error([&] { FlyingObject(index, huge); }, {"vertex 1", "-1e+308", "overflow"});
  huge.vertices[1][2] = kMaxCoordinateMagnitude;  // the bound itself is accepted
  EXPECT_NO_THROW(FlyingObject(index, huge));
  // A cube with corners at 0 and 1e308: its BVH's box sums overflowed, and the build crashed
  // before the coordinates were checked.
  TriangleSoup far_cube;
  far_cube.part_names = {"object"};
  for (double x : {0.0, 1e308})
    for (double y : {0.0, 1e308})
      for (double z : {0.0, 1e308}) far_cube.vertices.push_back({x, y, z});
  far_cube.triangles = {{0, 1, 3}, {0, 3, 2}, {4, 6, 7}, {4, 7, 5}, {0, 4, 5}, {0, 5, 1},
                        {2, 3, 7}, {2, 7, 6}, {0, 2, 6}, {0, 6, 4}, {1, 5, 7}, {1, 7, 3}};
  far_cube.part_of.assign(far_cube.triangles.size(), 0);
  expect_input_error([&] { FlyingObject(index, far_cube); }, {"1e+308", "overflow"});

  FlyingObject object(index, world.object);
  Pose far = world.flight.poses.front();
  far.translation = {1e308, 1e308, 1e308};
  expect_input_error([&] { object.query(far); }, {"1e+308", "overflow"});
  far.translation[0] = 0.5, far.translation[1] = -1e301;
  expect_input_error([&] { object.query(far); }, {"translation y", "-1e+301", "overflow"});
  // The object is unharmed: the flight answers as the oracle.
  for (std::size_t i = 0; i < world.flight.poses.size(); ++i)
    EXPECT_EQ(object.query(world.flight.poses[i]).collides, bool(world.flight.collides[i])) << "step " << i;

  std::uint64_t largest = 0;
  std::uint32_t largest_shard = 0;
  for (std::uint32_t s = 0; s < index->shard_count(); ++s)
    if (index->shard_bytes(s) > largest) largest = index->shard_bytes(s), largest_shard = s;
  CollisionIndexOptions options;
  options.memory_budget_bytes = largest - 1;
  expect_input_error([&] { CollisionIndex(world.index_path, options); },
                     {world.index_path.string(), "budget of " + std::to_string(largest - 1) + " bytes",
                      "shard " + std::to_string(largest_shard), std::to_string(largest) + " bytes"});
  options.memory_budget_bytes = largest;
  EXPECT_NO_THROW(CollisionIndex(world.index_path, options));
}

// Runs `body` on its own thread; a hang fails the whole test program (it cannot be cancelled).
template <class Body>
void within(std::chrono::seconds limit, Body&& body) {
  auto done = std::async(std::launch::async, std::forward<Body>(body));
  if (done.wait_for(limit) == std::future_status::timeout) {
    std::fprintf(stderr, "FAILED: still running after %lld s: a hang\n", static_cast<long long>(limit.count()));
    std::_Exit(1);
  }
  done.get();
}

// The step of the flight at which each shard is first acquired (max() for never), from a
// run without prefetching in a budget that holds everything (each shard paged in once).
std::vector<std::size_t> first_needs(const World& world) {
  CollisionIndexOptions options;
  options.prefetch = false;
  auto index = std::make_shared<const CollisionIndex>(world.index_path, options);
  std::vector<std::size_t> first(index->shard_count(), std::numeric_limits<std::size_t>::max());
  FlyingObject object(index, world.object);
  for (std::size_t i = 0; i < world.flight.poses.size(); ++i) {
    (void)object.query(world.flight.poses[i]);
    const auto page_ins = index->cache().page_ins_per_shard();
    for (std::uint32_t s = 0; s < page_ins.size(); ++s)
      if (page_ins[s] > 0 && first[s] == std::numeric_limits<std::size_t>::max()) first[s] = i;
  }
  return first;
}

// The shards the prefetcher pages in before the step that first needs them, when each step
// waits for the prefetcher to settle (as fly_through_damage does), and at which step.
std::map<std::uint32_t, std::size_t> prefetched_early(const World& world, const std::vector<std::size_t>& first) {
  auto index = std::make_shared<const CollisionIndex>(world.index_path);
  std::map<std::uint32_t, std::size_t> early;
  FlyingObject object(index, world.object);
  for (std::size_t i = 0; i < world.flight.poses.size(); ++i) {
    (void)object.query(world.flight.poses[i]);
    index->cache().wait_prefetch_idle();
    const auto page_ins = index->cache().page_ins_per_shard();
    for (std::uint32_t s = 0; s < page_ins.size(); ++s)
      if (page_ins[s] > 0 && first[s] > i && first[s] != std::numeric_limits<std::size_t>::max())
        early.emplace(s, i);  // the first step only
  }
  return early;
}

struct Damage {
  std::uint32_t victim = 0;        ///< the shard damaged on purpose
  std::uint64_t cut = 0;           ///< truncation: the new file size; else 0
  std::set<std::uint32_t> shards;  ///< every shard the damage reaches
  std::size_t earliest = 0;        ///< the first step that needs one of them
};

// A shard the prefetcher loads (after step `from`) before it is needed, overwritten in the
// middle of its chunks or (truncate) with the file cut at its first chunk; of the choices,
// the one whose damage the flight meets latest.
std::optional<Damage> plan_damage(const IndexReader& reader, const std::vector<std::size_t>& first,
                                  const std::map<std::uint32_t, std::size_t>& prefetched, std::size_t from,
                                  bool truncate) {
  std::optional<Damage> best;
  for (const auto& [victim, step] : prefetched) {
    if (step < from) continue;
    Damage damage;
    damage.victim = victim;
    damage.shards = {victim};
    if (truncate) {
      damage.cut = reader.shard_chunks(victim).front().file_offset;
      for (std::uint32_t s = 0; s < reader.shard_count(); ++s) {
        if (reader.shard_size(s) == 0) continue;
        const StoredChunk last = reader.shard_chunks(s).back();
        if (last.file_offset + last.stored_bytes > damage.cut) damage.shards.insert(s);
      }
    }
    damage.earliest = first[victim];
    for (const std::uint32_t s : damage.shards) damage.earliest = std::min(damage.earliest, first[s]);
    if (damage.earliest > from && (!best || damage.earliest > best->earliest)) best = damage;
  }
  return best;
}

// What a process writing over the file does: through the page cache, under the index reader.
void apply_damage(const fs::path& path, const IndexReader& reader, const Damage& damage) {
  if (damage.cut > 0) return fs::resize_file(path, damage.cut);
  std::fstream file(path, std::ios::in | std::ios::out | std::ios::binary);
  std::uint32_t noise = 12345;
  for (const StoredChunk& chunk : reader.shard_chunks(damage.victim)) {
    std::vector<char> garbage(std::max<std::uint64_t>(1, chunk.stored_bytes / 2));
    for (char& c : garbage) c = char((noise = noise * 1664525u + 1013904223u) >> 24);
    file.seekp(std::streamoff(chunk.file_offset + chunk.stored_bytes / 4));
    file.write(garbage.data(), std::streamsize(garbage.size()));
  }
  ASSERT_TRUE(file.flush()) << path;
}

// The damaged shard that the error names with the file, or max() when it names none.
std::uint32_t named_damage(const Error& e, const fs::path& path, const Damage& damage) {
  const std::string message = e.what();
  if (message.find(path.string()) == std::string::npos) return std::numeric_limits<std::uint32_t>::max();
  for (const std::uint32_t s : damage.shards) {
    const std::string name = "shard " + std::to_string(s);
    const auto at = message.find(name);
    if (at != std::string::npos && !std::isdigit(static_cast<unsigned char>(message[at + name.size()]))) return s;
  }
  return std::numeric_limits<std::uint32_t>::max();
}

void fly_through_damage(const World& world, const std::vector<std::size_t>& first,
                        const std::map<std::uint32_t, std::size_t>& prefetched, bool truncate) {
  const fs::path copy = world.index_path.parent_path() / (truncate ? "truncated-copy.tpi" : "overwritten-copy.tpi");
  fs::copy_file(world.index_path, copy, fs::copy_options::overwrite_existing);
  constexpr std::size_t kDamageStep = 10;
  const IndexReader reader(copy);
  const auto planned = plan_damage(reader, first, prefetched, kDamageStep, truncate);
  ASSERT_TRUE(planned) << "no shard is prefetched after step " << kDamageStep << " and needed later";
  const Damage& damage = *planned;
  const std::size_t k = first[damage.victim];
  const auto& poses = world.flight.poses;
  const auto& oracle = world.flight.collides;

  auto index = std::make_shared<const CollisionIndex>(copy);  // the prefetcher on, by default
  ASSERT_GT(index->options().prefetch_threads, 0u);
  FlyingObject a(index, world.object);
  for (std::size_t i = 0; i < kDamageStep; ++i) {
    ASSERT_EQ(a.query(poses[i]).collides, bool(oracle[i])) << i;
    index->cache().wait_prefetch_idle();  // as prefetched_early: the same shards are hinted
  }
  // (Other shards the truncation reaches may be resident already: they answer from memory.)
  ASSERT_FALSE(index->cache().contains(damage.victim)) << "shard " << damage.victim << " must be on disk only";
  apply_damage(copy, reader, damage);

  std::uint64_t prefetch_failures = 0;
  std::size_t failed = 0;
  bool failed_at_k = false;
  for (std::size_t i = kDamageStep; i < poses.size(); ++i) {
    // Every load that failed so far and failed no query was the prefetcher's (a failing
    // query stops at its first failed load).
    if (i == k) prefetch_failures = index->cache().counters().load_failures - failed;
    try {
      EXPECT_EQ(a.query(poses[i]).collides, bool(oracle[i])) << "step " << i;
    } catch (const Error& e) {
      ++failed;
      failed_at_k |= i == k;
      // Only a step that needs a damaged shard fails, naming it and the file.
      const std::uint32_t named = named_damage(e, copy, damage);
      EXPECT_NE(named, std::numeric_limits<std::uint32_t>::max()) << "step " << i << ": " << e.what();
      if (named != std::numeric_limits<std::uint32_t>::max()) {
        EXPECT_LE(first[named], i) << e.what();
      }
    }
    // Settled before the next step, so that the prefetcher meets the fault before the step.
    index->cache().wait_prefetch_idle();
  }
  EXPECT_TRUE(failed_at_k) << "step " << k << " needs the damaged shard " << damage.victim;
  // The prefetcher met the fault first: it was hinted the shard before step k needed it.
  EXPECT_GT(prefetch_failures, 0u) << "the prefetcher did not load shard " << damage.victim;

  // Another object, in the regions the flight crossed before the damage: all answers.
  FlyingObject b(index, world.object);
  for (std::size_t i = 0; i < damage.earliest; ++i)
    EXPECT_EQ(b.query(poses[i]).collides, bool(oracle[i])) << "object b, step " << i;
  // The fault is not forgotten: the step that needs the shard fails again, and nothing is
  // left reserved in the cache.
  try {
    (void)a.query(poses[k]);
    ADD_FAILURE() << "step " << k << " answered with shard " << damage.victim << " damaged";
  } catch (const Error& e) {
    EXPECT_NE(named_damage(e, copy, damage), std::numeric_limits<std::uint32_t>::max()) << e.what();
  }
  index->cache().wait_prefetch_idle();
  EXPECT_EQ(index->cache().counters().reserved_bytes, 0u);
  EXPECT_GT(failed, 0u);
}

// An I/O or checksum fault met by the prefetch thread in the middle of a flight: the query
// that needs the shard throws an Error naming it and the file; other regions keep answering.
TEST(FlyingObject, AShardDamagedMidFlightFailsOnlyTheQueriesThatNeedIt) {
  const World world = make_world(Kind::tetras, 4000, 116, 400, 11, 200);
  const std::vector<std::size_t> first = first_needs(world);
  const std::map<std::uint32_t, std::size_t> prefetched = prefetched_early(world, first);
  for (const bool truncate : {false, true}) {
    SCOPED_TRACE(truncate ? "truncated" : "overwritten");
    within(std::chrono::seconds(300), [&] { fly_through_damage(world, first, prefetched, truncate); });
  }
}

}  // namespace
}  // namespace tetrapage
