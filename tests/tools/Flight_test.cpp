// The reference oracle against brute force over every triangle pair (CGAL's exact
// construction kernel, no tree), and the billiard flight's promises.

#include <iterator>
#include <gtest/gtest.h>

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/preprocess/Preprocess.h"
#include "tetrapage/tools/AnswerFile.h"
#include "tetrapage/tools/FlightGenerator.h"
#include "tetrapage/tools/Random.h"
#include "tetrapage/tools/ReferenceCollider.h"
#include "tetrapage/tools/RuntimeJudge.h"

#include "BoxSoup.h"
#include "RunCli.h"

namespace tetrapage {
namespace {

using Exact = CGAL::Exact_predicates_exact_constructions_kernel;

using test::add_box;

// A unit-cube workspace (its corners are two tiny boxes) holding a few box obstacles.
TriangleSoup boxes_environment(std::uint64_t seed, int count) {
  TriangleSoup soup;
  add_box(soup, {0, 0, 0}, {0.001, 0.001, 0.001});
  add_box(soup, {0.999, 0.999, 0.999}, {1, 1, 1});
  Random random(seed);
  for (int i = 0; i < count; ++i) {
    Vec3 lo, hi;
    for (int a = 0; a < 3; ++a) {
      lo[a] = random.uniform(0.05, 0.8);
      hi[a] = lo[a] + random.uniform(0.03, 0.15);
    }
    add_box(soup, lo, hi);
  }
  return soup;
}

TriangleSoup tetra_object(double size) {
  TriangleSoup soup;
  soup.vertices = {{size, size, size}, {size, -size, -size}, {-size, size, -size}, {-size, -size, size}};
  soup.triangles = {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};
  soup.part_of = {0, 0, 0, 0};
  soup.part_names = {"tetra"};
  return soup;
}

Exact::Point_3 exact_point(const Vec3& v) { return {v[0], v[1], v[2]}; }

bool brute_force_touch(const TriangleSoup& environment, const TriangleSoup& object, const Pose& pose) {
  std::vector<Vec3> placed;
  for (const auto& v : object.vertices) placed.push_back(apply_pose(pose, v));
  for (std::size_t e = 0; e < environment.triangle_count(); ++e) {
    const auto c = environment.corners(e);
    const Exact::Triangle_3 obstacle(exact_point(c[0]), exact_point(c[1]), exact_point(c[2]));
    for (const auto& t : object.triangles) {
      const Exact::Triangle_3 moving(exact_point(placed[t[0]]), exact_point(placed[t[1]]),
                                     exact_point(placed[t[2]]));
      if (CGAL::do_intersect(obstacle, moving)) return true;
    }
  }
  return false;
}

// Parity along a direction different from the oracle's, by brute force in exact arithmetic.
bool brute_force_inside(const TriangleSoup& environment, const Vec3& p) {
  const Exact::Ray_3 ray(exact_point(p), Exact::Vector_3(0.3141592653, -0.2718281828, -1.0));
  int crossings = 0;
  for (std::size_t e = 0; e < environment.triangle_count(); ++e) {
    const auto c = environment.corners(e);
    if (CGAL::do_intersect(ray, Exact::Triangle_3(exact_point(c[0]), exact_point(c[1]), exact_point(c[2]))))
      ++crossings;
  }
  return crossings % 2 == 1;
}

Pose random_pose(Random& random) {
  Pose pose;
  for (auto& t : pose.translation) t = random.uniform(0.0, 1.0);
  std::array<double, 4> q{random.normal(), random.normal(), random.normal(), random.normal()};
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (auto& c : q) c /= n;
  pose.rotation = q;
  return pose;
}

TEST(ReferenceCollider, AgreesWithBruteForceOnRandomPoses) {
  const std::uint64_t seed = 7;
  SCOPED_TRACE("seed " + std::to_string(seed));
  const TriangleSoup environment = boxes_environment(seed, 12);
  const TriangleSoup object = tetra_object(0.04);
  const ReferenceCollider oracle(environment, object);
  Random random(seed);
  int touching = 0;
  for (int i = 0; i < 3000; ++i) {
    const Pose pose = random_pose(random);
    const auto answer = oracle.query(pose);
    ASSERT_EQ(answer.surfaces_touch, brute_force_touch(environment, object, pose)) << "pose " << i;
    if (!answer.surfaces_touch) {
      ASSERT_EQ(answer.object_inside, brute_force_inside(environment, apply_pose(pose, object.vertices[0])))
          << "pose " << i;
    }
    touching += answer.surfaces_touch;
  }
  EXPECT_GT(touching, 30) << "the test poses should include contacts";
}

TEST(ReferenceCollider, TouchingAlongAnEdgeCounts) {
  TriangleSoup environment;
  add_box(environment, {0, 0, 0}, {1, 1, 1});
  const TriangleSoup object = tetra_object(0.25);
  const ReferenceCollider oracle(environment, object);
  // Half a turn about z maps (x, y, z) to (-x, -y, z) exactly; with this translation the
  // tetra's edge from vertex 0 to vertex 1 lies exactly on the box's face x = 1.
  Pose touching;
  touching.translation = {1.25, 0.5, 0.5};
  touching.rotation = {0, 0, 0, 1};
  ASSERT_EQ(apply_pose(touching, object.vertices[0]), (Vec3{1.0, 0.25, 0.75}));
  EXPECT_TRUE(oracle.query(touching).surfaces_touch);
  Pose apart = touching;
  apart.translation[0] = 1.25 + 1.0 / 1024;
  EXPECT_FALSE(oracle.query(apart).surfaces_touch);
}

TEST(ReferenceCollider, ObjectInsideAClosedObstacleCollides) {
  TriangleSoup environment;
  add_box(environment, {0, 0, 0}, {1, 1, 1});
  const ReferenceCollider oracle(environment, tetra_object(0.01));
  Pose inside;
  inside.translation = {0.5, 0.5, 0.5};
  const auto answer = oracle.query(inside);
  EXPECT_FALSE(answer.surfaces_touch);
  EXPECT_TRUE(answer.object_inside);
  EXPECT_TRUE(answer.collides);
  Pose outside;
  outside.translation = {1.5, 0.5, 0.5};
  EXPECT_FALSE(oracle.query(outside).collides);
}

TEST(ReferenceCollider, RejectsEmptyInput) {
  EXPECT_THROW(ReferenceCollider(TriangleSoup{}, tetra_object(0.01)), InputError);
  EXPECT_THROW(ReferenceCollider(boxes_environment(1, 1), TriangleSoup{}), InputError);
}

class BilliardFlight : public ::testing::TestWithParam<std::uint64_t> {};

TEST_P(BilliardFlight, KeepsItsPromises) {
  const std::uint64_t seed = GetParam();
  SCOPED_TRACE("seed " + std::to_string(seed));
  const TriangleSoup environment = boxes_environment(seed, 25);
  const TriangleSoup object = tetra_object(0.02);
  const ReferenceCollider oracle(environment, object);
  FlightOptions options;
  options.steps = 1500;
  options.seed = seed;
  const Flight flight = generate_billiard_flight(oracle, options);
  ASSERT_EQ(flight.poses.size(), options.steps);
  ASSERT_EQ(flight.collides.size(), options.steps);

  // Deterministic: the same seed gives the same poses, bit for bit.
  const Flight again = generate_billiard_flight(oracle, options);
  for (std::size_t i = 0; i < options.steps; ++i) {
    ASSERT_EQ(flight.poses[i].translation, again.poses[i].translation) << "pose " << i;
    ASSERT_EQ(flight.poses[i].rotation, again.poses[i].rotation) << "pose " << i;
  }

  const BoundingBox& workspace = environment.bounds();
  std::uint64_t collisions = 0;
  double travelled = 0;
  for (std::size_t i = 0; i < options.steps; ++i) {
    const Pose& pose = flight.poses[i];
    const bool touch = brute_force_touch(environment, object, pose);
    ASSERT_EQ(bool(flight.collides[i]), touch) << "pose " << i << ": recorded answer is wrong";
    // Never inside an obstacle: a pose is either touching or outside every obstacle.
    if (!touch) {
      ASSERT_FALSE(brute_force_inside(environment, apply_pose(pose, object.vertices[0]))) << "pose " << i;
    }
    // Inside the workspace.
    for (const auto& v : object.vertices) {
      const Vec3 w = apply_pose(pose, v);
      for (int a = 0; a < 3; ++a) {
        ASSERT_GE(w[a], workspace.lo[a]);
        ASSERT_LE(w[a], workspace.hi[a]);
      }
    }
    // A collision is followed by the reverse move back to free space.
    if (i > 0 && flight.collides[i - 1]) {
      ASSERT_FALSE(flight.collides[i]) << "pose " << i;
    }
    if (i > 0) {
      double d2 = 0;
      for (int a = 0; a < 3; ++a) {
        const double d = pose.translation[a] - flight.poses[i - 1].translation[a];
        d2 += d * d;
      }
      travelled += std::sqrt(d2);
    }
    collisions += flight.collides[i];
  }
  EXPECT_FALSE(flight.collides.front());
  EXPECT_FALSE(flight.collides.back());
  EXPECT_EQ(collisions, flight.collisions);
  EXPECT_GT(collisions, 0u) << "a cluttered scene should produce bounces";
  EXPECT_NEAR(travelled / double(options.steps - 1), flight.displacement, 1e-9);
}

// `generate flight` moves in the model's units: the same environment and object scaled by 1000
// give steps 1000 times as long, measured on the poses written; an explicit --displacement is
// kept as given.
TEST(BilliardFlight, DefaultStepsScaleWithTheModel) {
  const std::filesystem::path folder =
      std::filesystem::path(TETRAPAGE_TEST_TMP) / ("flight-units-" + std::to_string(::getpid()));
  std::filesystem::create_directories(folder);
  const auto scaled = [](TriangleSoup soup, double factor) {
    for (auto& v : soup.vertices)
      for (double& c : v) c *= factor;
    return soup;
  };
  const auto step_lengths = [&](const std::string& name, const std::string& env,
                                const std::string& object, const std::string& extra) {
    std::string out;
    EXPECT_EQ(test::run_cli("generate flight --env " + (folder / env).string() + " --object " +
                                (folder / object).string() + " --steps 300 --seed 3 -o " +
                                (folder / name).string() + " " + extra,
                            out),
              0);
    const std::vector<Pose> poses = read_poses(folder / name);
    std::vector<double> lengths;
    for (std::size_t i = 1; i < poses.size(); ++i) {
      double d2 = 0;
      for (int a = 0; a < 3; ++a)
        d2 += std::pow(poses[i].translation[a] - poses[i - 1].translation[a], 2);
      lengths.push_back(std::sqrt(d2));
    }
    return lengths;
  };
  const TriangleSoup environment = boxes_environment(3, 12);
  const TriangleSoup object = tetra_object(0.02);
  write_mesh(folder / "env.ply", environment);
  write_mesh(folder / "object.ply", object);
  write_mesh(folder / "env-mm.ply", scaled(environment, 1000));
  write_mesh(folder / "object-mm.ply", scaled(object, 1000));
  const auto metres = step_lengths("m.csv", "env.ply", "object.ply", "");
  const auto millimetres = step_lengths("mm.csv", "env-mm.ply", "object-mm.ply", "");
  ASSERT_EQ(metres.size(), 299u);
  ASSERT_EQ(millimetres.size(), metres.size());
  for (std::size_t i = 0; i < metres.size(); ++i) {
    ASSERT_GT(metres[i], 0.0);
    EXPECT_NEAR(millimetres[i] / metres[i], 1000.0, 1e-6) << "step " << i;
  }
  for (const double length :
       step_lengths("given.csv", "env-mm.ply", "object-mm.ply", "--displacement 2.5"))
    EXPECT_NEAR(length, 2.5, 1e-9);
  std::filesystem::remove_all(folder);
}

// An object named by a manifest flies as its mesh does (a manifest is read everywhere a mesh
// is): the same seed gives the same flight and the same answers.
TEST(BilliardFlight, AnObjectGivenByAManifestFliesAsItsMesh) {
  const std::filesystem::path folder =
      std::filesystem::path(TETRAPAGE_TEST_TMP) / ("flight-manifest-" + std::to_string(::getpid()));
  std::filesystem::create_directories(folder);
  write_mesh(folder / "env.ply", boxes_environment(3, 12));
  write_mesh(folder / "object.ply", tetra_object(0.02));
  std::ofstream(folder / "object.json") << R"({"parts": [{"file": "object.ply"}]})";
  const auto flight = [&](const std::string& object, const std::string& name) {
    std::string out;
    EXPECT_EQ(test::run_cli("generate flight --env " + (folder / "env.ply").string() + " --object " +
                                (folder / object).string() + " --steps 200 --seed 4 -o " +
                                (folder / (name + ".csv")).string() + " --answers " +
                                (folder / (name + "-answers.csv")).string(),
                            out),
              0)
        << out;
    std::ifstream poses(folder / (name + ".csv")), answers(folder / (name + "-answers.csv"));
    return std::string(std::istreambuf_iterator<char>(poses), {}) +
           std::string(std::istreambuf_iterator<char>(answers), {});
  };
  const std::string from_mesh = flight("object.ply", "mesh");
  EXPECT_GT(from_mesh.size(), 200u * 20);
  EXPECT_EQ(flight("object.json", "manifest"), from_mesh);
  std::filesystem::remove_all(folder);
}

INSTANTIATE_TEST_SUITE_P(Seeds, BilliardFlight, ::testing::Values(1, 2, 3));

TEST(BilliardFlight, DifferentSeedsDiffer) {
  const TriangleSoup environment = boxes_environment(5, 10);
  const ReferenceCollider oracle(environment, tetra_object(0.02));
  FlightOptions a, b;
  a.steps = b.steps = 50;
  a.seed = 1;
  b.seed = 2;
  EXPECT_NE(generate_billiard_flight(oracle, a).poses.back().translation,
            generate_billiard_flight(oracle, b).poses.back().translation);
}

TEST(BilliardFlight, RefusesAnObjectLargerThanTheWorkspace) {
  const TriangleSoup environment = boxes_environment(5, 1);
  const ReferenceCollider oracle(environment, tetra_object(2.0));
  EXPECT_THROW(generate_billiard_flight(oracle, FlightOptions{}), InputError);
}

// For models too large for the oracle, the runtime judges the flight: where it answers as the
// oracle does (double storage, interiors), the flight is the oracle's, pose for pose.
TEST(BilliardFlight, TheRuntimeJudgeFliesTheOraclesFlight) {
  const TriangleSoup environment = boxes_environment(7, 25);
  const TriangleSoup object = tetra_object(0.02);
  const std::filesystem::path folder =
      std::filesystem::path(TETRAPAGE_TEST_TMP) / ("runtime-judge-" + std::to_string(::getpid()));
  std::filesystem::create_directories(folder);
  write_mesh(folder / "boxes.ply", environment);
  PreprocessOptions options;
  options.region_triangles = 16;
  options.precision = StoredPrecision::float64;
  options.interiors = true;
  preprocess({folder / "boxes.ply"}, folder / "boxes.tpi", options);
  const ReferenceCollider oracle(environment, object);
  RuntimeJudge judge(std::make_shared<const CollisionIndex>(folder / "boxes.tpi"), object);
  EXPECT_EQ(judge.environment_bounds().lo, oracle.environment_bounds().lo);
  EXPECT_EQ(judge.environment_bounds().hi, oracle.environment_bounds().hi);
  EXPECT_EQ(judge.object_radius(), oracle.object_radius());
  FlightOptions flight_options;
  flight_options.steps = 3000;
  flight_options.seed = 9;
  const Flight expected = generate_billiard_flight(oracle, flight_options);
  const Flight flight = generate_billiard_flight(judge, flight_options);
  EXPECT_GT(expected.collisions, 5u);
  ASSERT_EQ(flight.poses.size(), expected.poses.size());
  EXPECT_EQ(flight.collides, expected.collides);
  for (std::size_t i = 0; i < flight.poses.size(); ++i) {
    ASSERT_EQ(flight.poses[i].translation, expected.poses[i].translation) << "pose " << i;
    ASSERT_EQ(flight.poses[i].rotation, expected.poses[i].rotation) << "pose " << i;
  }

  // `fly --preload`, the all-resident reference of the scale series: no page-in during the
  // flight, the oracle's answers; refused when the shards exceed the budget.
  write_poses(folder / "flight.csv", flight.poses);
  write_answers(folder / "answers.csv", expected.collides);
  write_mesh(folder / "object.ply", object);
  const std::string fly = std::string(TETRAPAGE_CLI) + " fly " + (folder / "boxes.tpi").string() + " --object " +
                          (folder / "object.ply").string() + " --path " + (folder / "flight.csv").string() +
                          " --check " + (folder / "answers.csv").string() + " --report " +
                          (folder / "fly.json").string() + " > /dev/null 2>&1";
  ASSERT_EQ(std::system((fly + " --memory 64M --preload").c_str()), 0);
  std::ifstream report_file(folder / "fly.json");
  const auto report = nlohmann::json::parse(report_file);
  EXPECT_TRUE(report["preloaded"].get<bool>());
  EXPECT_EQ(report["page_ins"].get<std::uint64_t>(), 0u);
  EXPECT_EQ(report["cache_hit_rate"].get<double>(), 1.0);
  EXPECT_NE(std::system((fly + " --memory 1K --preload").c_str()), 0);
  std::filesystem::remove_all(folder);
}

TEST(AnswerFile, RoundTripsAndRejectsBadRows) {
  const std::filesystem::path folder = std::filesystem::path(TETRAPAGE_TEST_TMP) / "answers";
  std::filesystem::create_directories(folder);
  const std::vector<std::uint8_t> answers{0, 1, 1, 0, 0};
  write_answers(folder / "a.csv", answers);
  EXPECT_EQ(read_answers(folder / "a.csv"), answers);
  EXPECT_FALSE(std::filesystem::exists(folder / "a.csv.tmp"));

  std::ofstream(folder / "bad.csv") << "step,collides\n0,1\n1,2\n";
  try {
    read_answers(folder / "bad.csv");
    FAIL() << "expected FormatError";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.csv"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("line 3"), std::string::npos) << e.what();
  }
  std::ofstream(folder / "header.csv") << "collides\n0\n";
  EXPECT_THROW(read_answers(folder / "header.csv"), FormatError);
  EXPECT_THROW(read_answers(folder / "missing.csv"), IoError);
}

}  // namespace
}  // namespace tetrapage
