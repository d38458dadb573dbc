// The Embree collider (rtcCollide candidates, exact pair tests) against the exact oracle
// (ReferenceCollider, itself checked against brute force in Flight_test.cpp): on billiard
// flights through generated tetras, terrains and scenes, on poses bisected to within a few
// ulps of contact, and through `tetrapage replay --reference embree --check`.

#include <gtest/gtest.h>

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <ostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/tools/AnswerFile.h"
#include "tetrapage/tools/EmbreeCollider.h"
#include "tetrapage/tools/FlightGenerator.h"
#include "tetrapage/tools/MeshLibrary.h"
#include "tetrapage/tools/ObjectGenerator.h"
#include "tetrapage/tools/Random.h"
#include "tetrapage/tools/ReferenceCollider.h"
#include "tetrapage/tools/StudyEnvironment.h"

#include "BoxSoup.h"

namespace tetrapage {
namespace {

// Under the running test's name: ctest runs test cases in parallel processes.
std::filesystem::path test_folder(const std::string& name) {
  const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string test_name = std::string(test->test_suite_name()) + "." + test->name();
  std::replace(test_name.begin(), test_name.end(), '/', '_');
  const auto folder = std::filesystem::path(TETRAPAGE_TEST_TMP) / "embree_collider" / test_name / name;
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  return folder;
}

using Environment = EnvironmentKind;

const MeshLibrary& library() {
  static const MeshLibrary meshes = MeshLibrary::load_default();
  return meshes;
}

// Written by the generator and read back, as the command line would see it.
TriangleSoup environment_soup(Environment kind, std::uint64_t seed) {
  const auto path = test_folder(to_string(kind) + std::to_string(seed)) / "environment.ply";
  // The sizes keep each case's oracle fast.
  const std::uint64_t triangles = kind == Environment::tetras ? 400 : kind == Environment::terrain ? 800 : 3000;
  {
    MeshWriter writer(path);
    generate_environment(kind, triangles, seed, writer);
    writer.commit();
  }
  return read_mesh(path);
}

TriangleSoup generate_flying_object(std::uint64_t triangles, double size = 0.05) {
  ObjectOptions options;
  options.triangles = triangles;
  options.size = size;
  return generate_object(options, object_needs_meshes(triangles) ? &library() : nullptr).soup;
}

// The pose between `free` and `touching` (same rotation, translation moved along the
// segment) where contact begins, bisected until the two translations are adjacent doubles
// (or 200 halvings): returns {last free pose, first touching pose}, or nothing when the
// endpoints do not straddle contact under that rotation.
std::optional<std::pair<Pose, Pose>> bisect_contact(const ReferenceCollider& oracle, Pose free, Pose touching) {
  free.rotation = touching.rotation;
  if (oracle.query(free).collides || !oracle.query(touching).surfaces_touch) return std::nullopt;
  for (int i = 0; i < 200; ++i) {
    Pose middle = touching;
    for (int a = 0; a < 3; ++a)
      middle.translation[a] = free.translation[a] + 0.5 * (touching.translation[a] - free.translation[a]);
    if (middle.translation == free.translation || middle.translation == touching.translation) break;
    (oracle.query(middle).surfaces_touch ? touching : free) = middle;
  }
  return std::make_pair(free, touching);
}

using Exact = CGAL::Exact_predicates_exact_constructions_kernel;

Exact::Point_3 exact_point(const Vec3& v) { return {v[0], v[1], v[2]}; }

bool brute_force_touch(const TriangleSoup& environment, const TriangleSoup& object, const Pose& pose) {
  std::vector<Exact::Point_3> placed;
  for (const auto& v : object.vertices) placed.push_back(exact_point(apply_pose(pose, v)));
  for (std::size_t e = 0; e < environment.triangle_count(); ++e) {
    const auto c = environment.corners(e);
    const Exact::Triangle_3 obstacle(exact_point(c[0]), exact_point(c[1]), exact_point(c[2]));
    for (const auto& t : object.triangles)
      if (CGAL::do_intersect(obstacle, Exact::Triangle_3(placed[t[0]], placed[t[1]], placed[t[2]]))) return true;
  }
  return false;
}

// Pairs whose double boxes meet: rtcCollide must hand each of them over exactly once
// (they are exactly what EmbreeCollider::Answer::exact_tests counts), whatever its trees.
std::uint64_t brute_force_box_pairs(const TriangleSoup& environment, const TriangleSoup& object, const Pose& pose) {
  std::vector<Vec3> placed;
  for (const auto& v : object.vertices) placed.push_back(apply_pose(pose, v));
  const auto box = [](const Vec3& a, const Vec3& b, const Vec3& c) {
    return CGAL::Bbox_3(std::min({a[0], b[0], c[0]}), std::min({a[1], b[1], c[1]}), std::min({a[2], b[2], c[2]}),
                        std::max({a[0], b[0], c[0]}), std::max({a[1], b[1], c[1]}), std::max({a[2], b[2], c[2]}));
  };
  std::vector<CGAL::Bbox_3> object_boxes;
  for (const auto& t : object.triangles) object_boxes.push_back(box(placed[t[0]], placed[t[1]], placed[t[2]]));
  std::uint64_t pairs = 0;
  for (std::size_t e = 0; e < environment.triangle_count(); ++e) {
    const auto c = environment.corners(e);
    const CGAL::Bbox_3 obstacle = box(c[0], c[1], c[2]);
    for (const auto& b : object_boxes) pairs += CGAL::do_overlap(obstacle, b);
  }
  return pairs;
}

struct Case {
  Environment environment;
  std::uint64_t object_triangles;
  std::uint64_t seed;
};

void PrintTo(const Case& c, std::ostream* out) {
  *out << to_string(c.environment) << ", object " << c.object_triangles << " triangles, seed " << c.seed;
}

std::string case_name(const ::testing::TestParamInfo<Case>& info) {
  return to_string(info.param.environment) + "_object" + std::to_string(info.param.object_triangles) + "_seed" +
         std::to_string(info.param.seed);
}

class EmbreeAgainstOracle : public ::testing::TestWithParam<Case> {};

TEST_P(EmbreeAgainstOracle, SurfacesTouchAgreeOnFlightsAndOnGrazingPoses) {
  const Case c = GetParam();
  SCOPED_TRACE(case_name({c, 0}));
  const TriangleSoup environment = environment_soup(c.environment, c.seed);
  const TriangleSoup object = generate_flying_object(c.object_triangles);
  const ReferenceCollider oracle(environment, object);
  EmbreeCollider embree(environment, object);

  FlightOptions options;
  options.steps = 4000;
  options.seed = c.seed;
  const Flight flight = generate_billiard_flight(oracle, options);
  std::uint64_t touching = 0, grazing = 0, candidates = 0;
  for (std::size_t i = 0; i < flight.poses.size(); ++i) {
    const auto expected = oracle.query(flight.poses[i]);
    const auto answer = embree.query(flight.poses[i]);
    ASSERT_EQ(answer.surfaces_touch, expected.surfaces_touch) << "pose " << i;
    ASSERT_EQ(answer.surfaces_touch, bool(flight.collides[i])) << "pose " << i;
    ASSERT_LE(answer.exact_tests, answer.candidate_pairs) << "pose " << i;
    ASSERT_EQ(answer.surfaces_touch, answer.touching_pairs > 0) << "pose " << i;
    touching += answer.surfaces_touch;
    candidates += answer.candidate_pairs;
    const bool small = environment.triangle_count() * object.triangle_count() <= 100000;
    if (small && (i % 16 == 0 || answer.exact_tests > 0)) {
      ASSERT_EQ(answer.exact_tests, brute_force_box_pairs(environment, object, flight.poses[i])) << "pose " << i;
    }

    // Each bounce: the last free and the first touching pose along the move into contact,
    // a few ulps apart, where Embree's float boxes cannot tell the two apart.
    if (i == 0 || !flight.collides[i]) continue;
    const auto contact = bisect_contact(oracle, flight.poses[i - 1], flight.poses[i]);
    if (!contact) continue;
    const auto& [before, at] = *contact;
    for (int a = 0; a < 3; ++a) ASSERT_LT(std::abs(before.translation[a] - at.translation[a]), 1e-12);
    const auto free_answer = embree.query(before);
    const auto touch_answer = embree.query(at);
    ASSERT_FALSE(free_answer.surfaces_touch) << "grazing pose before bounce " << i;
    ASSERT_TRUE(touch_answer.surfaces_touch) << "grazing pose at bounce " << i;
    ASSERT_GT(free_answer.exact_tests, 0u) << "a pose this close must reach the exact test";
    if (small) {
      ASSERT_FALSE(brute_force_touch(environment, object, before)) << "bounce " << i;
      ASSERT_TRUE(brute_force_touch(environment, object, at)) << "bounce " << i;
      ASSERT_EQ(free_answer.exact_tests, brute_force_box_pairs(environment, object, before)) << "bounce " << i;
      ASSERT_EQ(touch_answer.exact_tests, brute_force_box_pairs(environment, object, at)) << "bounce " << i;
    }
    ++grazing;
  }
  RecordProperty("touching", std::to_string(touching));
  RecordProperty("grazing_pairs", std::to_string(grazing));
  EXPECT_GT(touching, 0u) << "the flight should bounce";
  EXPECT_GT(grazing, 0u) << "some bounces should give grazing poses";
  EXPECT_GT(candidates, 0u);
}

INSTANTIATE_TEST_SUITE_P(Generated, EmbreeAgainstOracle,
                         ::testing::Values(Case{Environment::tetras, 4, 1}, Case{Environment::tetras, 116, 2},
                                           Case{Environment::terrain, 4, 3}, Case{Environment::terrain, 116, 1},
                                           Case{Environment::scene, 116, 2}, Case{Environment::scene, 496, 1}),
                         case_name);

// Vertex on vertex: the identity rotation places x at exactly x + t, so choosing t = e - x
// puts the object's vertex x on the environment's vertex e whenever x + (e - x) rounds to e.
// A single shared point; both boxes meet in one corner at most.
TEST(EmbreeCollider, VertexOnVertexContactsAreSeen) {
  const TriangleSoup environment = environment_soup(Environment::tetras, 4);
  const TriangleSoup object = generate_flying_object(4, 0.02);
  const ReferenceCollider oracle(environment, object);
  EmbreeCollider embree(environment, object);
  int exact_contacts = 0;
  for (std::size_t v = 0; v < environment.vertices.size(); v += 7) {
    const Vec3& e = environment.vertices[v];
    for (const Vec3& x : object.vertices) {
      Pose pose;
      for (int a = 0; a < 3; ++a) pose.translation[a] = e[a] - x[a];
      if (apply_pose(pose, x) != e) continue;
      ++exact_contacts;
      ASSERT_TRUE(brute_force_touch(environment, object, pose)) << "vertex " << v;
      ASSERT_TRUE(oracle.query(pose).surfaces_touch) << "vertex " << v;
      ASSERT_TRUE(embree.query(pose).surfaces_touch) << "vertex " << v;
    }
  }
  EXPECT_GT(exact_contacts, 20);
}

// Face on face at coordinates no float holds: a cube pressed exactly against a box face
// (the cube's face and the box's face lie in the same plane x = c, c not a float), and the
// same cube one ulp of translation away. Every touching pair's boxes meet only in that
// plane, so Embree sees the contact only if the float boxes are rounded outward.
TEST(EmbreeCollider, FaceContactsAtCoordinatesNoFloatHolds) {
  const std::uint64_t seed = 8;
  SCOPED_TRACE("seed " + std::to_string(seed));
  Random random(seed);
  TriangleSoup environment;
  for (int i = 0; i < 6; ++i) {
    Vec3 lo, hi;
    for (int a = 0; a < 3; ++a) {
      lo[a] = 0.25 * i + random.uniform(0.01, 0.05);
      hi[a] = lo[a] + random.uniform(0.08, 0.15);
    }
    test::add_box(environment, lo, hi);
  }
  TriangleSoup object;
  test::add_box(object, {-0.01, -0.01, -0.01}, {0.01, 0.01, 0.01});
  const ReferenceCollider oracle(environment, object);
  EmbreeCollider embree(environment, object);
  int contacts = 0, misses = 0;
  for (std::size_t box = 0; box < environment.part_names.size(); ++box) {
    const Vec3& lo = environment.vertices[8 * box];
    const Vec3& hi = environment.vertices[8 * box + 7];
    for (int axis = 0; axis < 3; ++axis)
      for (const double side : {-1.0, 1.0}) {
        const double plane = side < 0 ? lo[axis] : hi[axis];
        if (double(float(plane)) == plane) continue;
        // The cube's face at -side * 0.01 lands on the plane: translation plane + side * 0.01.
        Pose pose;
        for (int a = 0; a < 3; ++a) pose.translation[a] = 0.5 * (lo[a] + hi[a]);
        pose.translation[axis] = plane + side * 0.01;
        Vec3 probe{0, 0, 0};
        probe[axis] = -side * 0.01;
        if (apply_pose(pose, probe)[axis] != plane) continue;
        ++contacts;
        ASSERT_TRUE(brute_force_touch(environment, object, pose)) << "box " << box << " axis " << axis;
        ASSERT_TRUE(oracle.query(pose).surfaces_touch) << "box " << box << " axis " << axis;
        ASSERT_TRUE(embree.query(pose).surfaces_touch) << "box " << box << " axis " << axis;
        Pose apart = pose;
        apart.translation[axis] = std::nextafter(pose.translation[axis], pose.translation[axis] + side);
        if (side * (apply_pose(apart, probe)[axis] - plane) <= 0) continue;
        ++misses;
        ASSERT_FALSE(brute_force_touch(environment, object, apart)) << "box " << box << " axis " << axis;
        ASSERT_FALSE(oracle.query(apart).surfaces_touch) << "box " << box << " axis " << axis;
        const auto answer = embree.query(apart);
        ASSERT_FALSE(answer.surfaces_touch) << "box " << box << " axis " << axis;
        ASSERT_GT(answer.candidate_pairs, 0u) << "one ulp apart, no float box can separate them";
      }
  }
  EXPECT_GE(contacts, 12);
  EXPECT_GE(misses, 12);
}

// Random poses of a small object: some land wholly inside a tetrahedron, where the oracle's
// parity says "collides" and no surfaces meet. Those (and obstacles wholly inside the
// object, if any), and only those, are where the two references' collides answers differ.
TEST(EmbreeCollider, DiffersFromTheOracleExactlyWhereOneBodyIsInsideTheOther) {
  const std::uint64_t seed = 5;
  SCOPED_TRACE("seed " + std::to_string(seed));
  const TriangleSoup environment = environment_soup(Environment::tetras, seed);
  const TriangleSoup object = generate_flying_object(116, 0.01);
  const ReferenceCollider oracle(environment, object);
  EmbreeCollider embree(environment, object);
  Random random(seed);
  int inside = 0, touching = 0, differ = 0;
  for (int i = 0; i < 4000; ++i) {
    Pose pose;
    for (auto& t : pose.translation) t = random.uniform(0.0, 1.0);
    std::array<double, 4> q{random.normal(), random.normal(), random.normal(), random.normal()};
    const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (auto& x : q) x /= n;
    pose.rotation = q;
    const auto expected = oracle.query(pose);
    const auto answer = embree.query(pose);
    ASSERT_EQ(answer.surfaces_touch, expected.surfaces_touch) << "pose " << i;
    differ += answer.surfaces_touch != expected.collides;
    inside += expected.object_inside || expected.obstacle_inside;
    touching += expected.surfaces_touch;
  }
  RecordProperty("inside", std::to_string(inside));
  EXPECT_EQ(differ, inside);
  EXPECT_GT(inside, 0) << "some random poses should fall inside a tetrahedron";
  EXPECT_GT(touching, 0);
}

// The trees may take another shape with another thread count (so may candidate_pairs), but
// the pairs whose double boxes meet, and those that touch, are the same.
TEST(EmbreeCollider, AnswersDoNotDependOnEmbreesThreads) {
  const TriangleSoup environment = environment_soup(Environment::scene, 3);
  const TriangleSoup object = generate_flying_object(116);
  const ReferenceCollider oracle(environment, object);
  EmbreeCollider one(environment, object, 1), all(environment, object);
  FlightOptions options;
  options.steps = 300;
  options.seed = 3;
  const Flight flight = generate_billiard_flight(oracle, options);
  for (std::size_t i = 0; i < flight.poses.size(); ++i) {
    const auto a = one.query(flight.poses[i]), b = all.query(flight.poses[i]);
    ASSERT_EQ(a.surfaces_touch, b.surfaces_touch) << "pose " << i;
    ASSERT_EQ(a.exact_tests, b.exact_tests) << "pose " << i;
    ASSERT_EQ(a.touching_pairs, b.touching_pairs) << "pose " << i;
  }
}

TEST(EmbreeCollider, RejectsEmptyInputAndCoordinatesBeyondEmbreesRange) {
  const TriangleSoup object = generate_flying_object(4);
  EXPECT_THROW(EmbreeCollider(TriangleSoup{}, object), InputError);
  EXPECT_THROW(EmbreeCollider(object, TriangleSoup{}), InputError);
  TriangleSoup far = object;
  far.vertices[0][2] = 2e18;
  EXPECT_THROW(EmbreeCollider(far, object), InputError);
  EmbreeCollider embree(object, object);
  Pose pose;
  pose.translation = {0, -3e18, 0};
  try {
    embree.query(pose);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("1e18"), std::string::npos) << e.what();
  }
  pose.translation = {0, 0, 0};
  EXPECT_TRUE(embree.query(pose).surfaces_touch) << "the object meets its own copy";
}

struct CommandResult {
  int status = -1;
  std::string stderr_text;
};

CommandResult run_command(const std::string& arguments, const std::filesystem::path& folder) {
  const auto err = folder / "stderr.txt";
  const std::string command =
      std::string("'") + TETRAPAGE_CLI + "' " + arguments + " > /dev/null 2> '" + err.string() + "'";
  CommandResult result;
  result.status = std::system(command.c_str());
  std::ifstream in(err);
  std::ostringstream text;
  text << in.rdbuf();
  result.stderr_text = text.str();
  return result;
}

// `replay --reference embree --check` passes on the oracle's answers, and fails, naming the
// steps, on the same flight shifted by one pose (each bounce then lands a step off).
TEST(EmbreeCollider, ReplayChecksAnswersAndCatchesAShiftedFlight) {
  const auto folder = test_folder("replay");
  const TriangleSoup environment = environment_soup(Environment::tetras, 6);
  const TriangleSoup object = generate_flying_object(116);
  write_mesh(folder / "environment.ply", environment);
  write_mesh(folder / "object.ply", object);
  const ReferenceCollider oracle(environment, object);
  FlightOptions options;
  options.steps = 400;
  options.seed = 6;
  const Flight flight = generate_billiard_flight(oracle, options);
  ASSERT_GT(flight.collisions, 0u);
  write_poses(folder / "flight.csv", flight.poses);
  write_answers(folder / "answers.csv", flight.collides);
  std::vector<Pose> shifted(flight.poses.begin() + 1, flight.poses.end());
  shifted.push_back(flight.poses.back());
  write_poses(folder / "shifted.csv", shifted);
  std::uint64_t expected_disagreements = 0;
  for (std::size_t i = 0; i < shifted.size(); ++i)
    expected_disagreements += oracle.query(shifted[i]).collides != bool(flight.collides[i]);
  ASSERT_GT(expected_disagreements, 0u);

  const std::string common = "replay '" + (folder / "environment.ply").string() + "' --object '" +
                             (folder / "object.ply").string() + "' --reference embree --check '" +
                             (folder / "answers.csv").string() + "' --report '" + (folder / "r.json").string() +
                             "' --path ";
  const auto same = run_command(common + "'" + (folder / "flight.csv").string() + "'", folder);
  EXPECT_EQ(same.status, 0) << same.stderr_text;
  EXPECT_EQ(nlohmann::json::parse(std::ifstream(folder / "r.json"))["disagreements"], 0);

  const auto off = run_command(common + "'" + (folder / "shifted.csv").string() + "'", folder);
  EXPECT_NE(off.status, 0);
  EXPECT_NE(off.stderr_text.find("step "), std::string::npos) << off.stderr_text;
  EXPECT_EQ(nlohmann::json::parse(std::ifstream(folder / "r.json"))["disagreements"], expected_disagreements);
}

}  // namespace
}  // namespace tetrapage
