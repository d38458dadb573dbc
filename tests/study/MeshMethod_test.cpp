// The study's mesh method against brute force (every object triangle against every obstacle
// triangle, exact): random poses and touching contacts in generated tetras, terrains and
// scenes, and in a deliberately bad input (crossing, duplicated and zero-area triangles).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/runtime/geometry/Box.h"
#include "tetrapage/runtime/geometry/TriangleTriangle.h"
#include "tetrapage/study/MeshMethod.h"
#include "tetrapage/study/PlacedObject.h"
#include "tetrapage/tools/MeshLibrary.h"
#include "tetrapage/tools/ObjectGenerator.h"
#include "tetrapage/tools/Random.h"
#include "tetrapage/tools/StudyEnvironment.h"

namespace tetrapage::study {
namespace {

using geometry::Point;
using geometry::Triangle;

using Environment = EnvironmentKind;

// Written by the generator and read back, as the command line would see it; under the
// running test's name, since ctest runs test cases in parallel processes.
std::vector<Triangle> environment_triangles(Environment kind, std::uint64_t triangles, std::uint64_t seed) {
  const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
  const auto folder = std::filesystem::path(TETRAPAGE_TEST_TMP) / "mesh_method" /
                      (std::string(test->test_suite_name()) + "." + test->name());
  std::filesystem::create_directories(folder);
  const auto path = folder / (to_string(kind) + std::to_string(triangles) + "_" + std::to_string(seed) + ".ply");
  {
    MeshWriter writer(path);
    generate_environment(kind, triangles, seed, writer);
    writer.commit();
  }
  return read_mesh(path).all_corners();
}

TriangleSoup flying_object(std::uint64_t triangles, double size) {
  ObjectOptions options;
  options.triangles = triangles;
  options.size = size;
  return generate_object(options).soup;
}

// The oracle: some object triangle meets some obstacle triangle (all pairs).
bool brute_force(const PlacedObject& object, const std::vector<Triangle>& obstacles) {
  const auto triangles = object.triangles();
  const auto boxes = object.triangle_boxes();
  for (const auto& o : obstacles) {
    const auto box = geometry::box_of(o);
    if (!geometry::boxes_overlap(box, object.box())) continue;
    for (std::size_t i = 0; i < triangles.size(); ++i)
      if (geometry::boxes_overlap(box, boxes[i]) && geometry::triangles_intersect(triangles[i], o)) return true;
  }
  return false;
}

std::array<double, 4> random_rotation(Random& random) {
  std::array<double, 4> q{random.normal(), random.normal(), random.normal(), random.normal()};
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (auto& c : q) c /= n;
  return q;
}

struct FlightTally {
  int poses = 0;
  int collisions = 0;
};

// Random poses near obstacle vertices (many hits), anywhere in the box around them (mostly
// misses), and exact vertex-on-vertex contacts: a mesh method answer must equal the oracle's.
FlightTally fly(StudyMethod& method, const std::vector<Triangle>& obstacles, const TriangleSoup& soup,
                std::uint64_t seed, int poses) {
  PlacedObject object(soup);
  Random random(seed);
  geometry::Box bounds;
  for (const auto& t : obstacles) bounds.extend(geometry::box_of(t));
  StudyCounters counters;
  FlightTally tally;
  for (int i = 0; i < poses; ++i) {
    Pose pose;
    const Triangle& near = obstacles[random.below(obstacles.size())];
    const Point& v = near[random.below(3)];
    switch (i % 4) {
      case 0:  // near an obstacle vertex, rotated
        pose.rotation = random_rotation(random);
        for (int a = 0; a < 3; ++a) pose.translation[a] = v[a] + random.uniform(-0.03, 0.03);
        break;
      case 1:  // anywhere around the obstacles, a little beyond their box
        pose.rotation = random_rotation(random);
        for (int a = 0; a < 3; ++a) {
          const double pad = 0.2 * (bounds.hi[a] - bounds.lo[a]);
          pose.translation[a] = random.uniform(bounds.lo[a] - pad, bounds.hi[a] + pad);
        }
        break;
      case 2:  // touching: the object's vertex 0 exactly on an obstacle vertex (no rotation)
        for (int a = 0; a < 3; ++a) pose.translation[a] = v[a] - soup.vertices[0][a];
        break;
      case 3: {  // the same, one ulp away along a random axis
        for (int a = 0; a < 3; ++a) pose.translation[a] = v[a] - soup.vertices[0][a];
        const auto axis = random.below(3);
        pose.translation[axis] = std::nextafter(pose.translation[axis], random.below(2) ? 1e300 : -1e300);
        break;
      }
    }
    object.place(pose);
    const bool expected = brute_force(object, obstacles);
    const bool answer = method.collides(object, counters);
    EXPECT_EQ(answer, expected) << "seed " << seed << ", pose " << i << ": translation (" << pose.translation[0]
                                << ", " << pose.translation[1] << ", " << pose.translation[2] << ")";
    if (answer != expected) return tally;
    ++tally.poses;
    tally.collisions += expected;
  }
  EXPECT_EQ(counters.queries, std::uint64_t(poses));
  EXPECT_EQ(counters.collisions, std::uint64_t(tally.collisions));
  EXPECT_GE(counters.full_checks, counters.collisions);
  return tally;
}

void print_figures(const std::string& what, const StudyMethod& method) {
  const auto s = method.statistics();
  std::printf("%s: %s, build %.3f s, stored %llu, details %s\n", what.c_str(), method.parameters().c_str(),
              s.build_seconds, static_cast<unsigned long long>(s.stored_triangles), s.details.dump().c_str());
}

struct FlightCase {
  Environment environment;
  std::uint64_t triangles;
  std::uint64_t seed;
  std::uint64_t object_triangles;
};

class MeshMethodFlight : public ::testing::TestWithParam<FlightCase> {};

TEST_P(MeshMethodFlight, AnswersEqualBruteForce) {
  const auto c = GetParam();
  const auto obstacles = environment_triangles(c.environment, c.triangles, c.seed);
  const auto method = make_mesh_method(obstacles);
  print_figures(to_string(c.environment) + " " + std::to_string(obstacles.size()), *method);
  const auto stats = method->statistics();
  EXPECT_EQ(method->name(), "mesh");
  EXPECT_EQ(stats.obstacle_triangles, obstacles.size());
  // Every obstacle triangle meets at least one tet.
  EXPECT_GE(stats.stored_triangles, obstacles.size());
  const auto tally = fly(*method, obstacles, flying_object(c.object_triangles, 0.05), c.seed, 400);
  // The flight exercised both answers.
  EXPECT_GT(tally.collisions, 40);
  EXPECT_LT(tally.collisions, tally.poses - 40);
}

INSTANTIATE_TEST_SUITE_P(Environments, MeshMethodFlight,
                         ::testing::Values(FlightCase{Environment::tetras, 400, 1, 4},
                                           FlightCase{Environment::tetras, 1000, 2, 116},
                                           FlightCase{Environment::terrain, 800, 3, 4},
                                           FlightCase{Environment::scene, 2000, 4, 116}),
                         [](const auto& test) {
                           return to_string(test.param.environment) + std::to_string(test.param.triangles) +
                                  "_object" + std::to_string(test.param.object_triangles);
                         });

// A vertex exactly on an obstacle triangle's face (not on its edges): contact, and one ulp
// above it: none; the same for a vertex exactly on an edge.
TEST(MeshMethod, TouchingContactsAreExact) {
  std::vector<Triangle> obstacles = {
      {Point{0, 0, 0.5}, Point{1, 0, 0.5}, Point{0, 1, 0.5}},
      {Point{0.2, 0.2, 0.1}, Point{0.6, 0.3, 0.2}, Point{0.3, 0.7, 0.15}},
  };
  const auto method = make_mesh_method(obstacles);
  // A small tetrahedron standing on its vertex 0 at its local origin.
  TriangleSoup soup;
  soup.vertices = {{0, 0, 0}, {0.01, 0, 0.02}, {0, 0.01, 0.02}, {-0.01, -0.01, 0.02}};
  soup.triangles = {{0, 1, 2}, {0, 2, 3}, {0, 3, 1}, {1, 3, 2}};
  soup.part_of = {0, 0, 0, 0};
  soup.part_names = {"probe"};
  PlacedObject object(soup);
  StudyCounters counters;
  const Point on_face{0.25, 0.25, 0.5}, on_edge{0.5, 0.0, 0.5}, at_vertex{1, 0, 0.5};
  for (const Point& p : {on_face, on_edge, at_vertex}) {
    Pose pose;
    pose.translation = p;
    object.place(pose);
    EXPECT_TRUE(brute_force(object, obstacles));
    EXPECT_TRUE(method->collides(object, counters)) << p[0] << " " << p[1] << " " << p[2];
    pose.translation[2] = std::nextafter(0.5, 1.0);
    object.place(pose);
    EXPECT_FALSE(brute_force(object, obstacles));
    EXPECT_FALSE(method->collides(object, counters)) << p[0] << " " << p[1] << " " << p[2];
  }
  // Far outside the hull, and straddling its boundary.
  Pose far;
  far.translation = {50, -3, 7};
  object.place(far);
  EXPECT_FALSE(method->collides(object, counters));
  Pose edge_of_hull;
  edge_of_hull.translation = {1.095, 0.3, 0.45};  // the hull ends at x = 1.1
  object.place(edge_of_hull);
  EXPECT_EQ(method->collides(object, counters), brute_force(object, obstacles));
}

// Disjoint tetrahedra: the Steiner rounds reach a conforming mesh, with a finite growth.
TEST(MeshMethod, DisjointTetrahedraConform) {
  for (std::uint64_t triangles : {100, 400}) {
    const auto obstacles = environment_triangles(Environment::tetras, triangles, 7);
    const auto method = make_mesh_method(obstacles);
    print_figures("tetras " + std::to_string(triangles), *method);
    const auto details = method->statistics().details;
    EXPECT_EQ(details["non_conforming_triangles"].get<std::uint64_t>(), 0u);
    EXPECT_TRUE(details["conforming"].get<bool>());
    EXPECT_EQ(details["stopped"].get<std::string>(), "conforming");
    const double growth = details["growth_factor"].get<double>();
    EXPECT_TRUE(std::isfinite(growth));
    EXPECT_GE(growth, 1.0);
    EXPECT_LE(growth, 10.0);
    EXPECT_EQ(details["original_vertices"].get<std::uint64_t>(), triangles);  // 4 per tetrahedron
    EXPECT_GT(details["average_stabbing_number"].get<double>(), 0.0);
  }
}

// Bad data (section 2.2): two triangles crossing each other, a duplicated triangle, a
// zero-area one and one shrunk to a point. The build ends (conformity may be given up) and
// the answers stay exact.
TEST(MeshMethod, SelfIntersectingInputBuildsAndAnswersExactly) {
  const std::vector<Triangle> obstacles = {
      {Point{0, 0, 0}, Point{1, 0, 0}, Point{0, 1, 0}},
      {Point{0.2, 0.2, -0.5}, Point{0.3, 0.2, 0.5}, Point{0.2, 0.4, 0.4}},  // crosses the first
      {Point{0.5, 0.5, 0.2}, Point{0.9, 0.6, 0.3}, Point{0.6, 0.9, 0.1}},
      {Point{0.5, 0.5, 0.2}, Point{0.9, 0.6, 0.3}, Point{0.6, 0.9, 0.1}},  // duplicate
      {Point{0.1, 0.8, 0.6}, Point{0.4, 0.8, 0.6}, Point{0.7, 0.8, 0.6}},  // zero area
      {Point{0.8, 0.1, 0.7}, Point{0.8, 0.1, 0.7}, Point{0.8, 0.1, 0.7}},  // a point
      {Point{0.05, 0.05, 0.3}, Point{0.95, 0.1, -0.2}, Point{0.5, 0.9, 0.25}},  // crosses the first
  };
  MeshMethodOptions options;
  options.max_rounds = 20;
  const auto method = make_mesh_method(obstacles, options);
  print_figures("bad data", *method);
  const auto details = method->statistics().details;
  EXPECT_EQ(details["degenerate_triangles"].get<std::uint64_t>(), 2u);
  EXPECT_LE(details["rounds"].get<std::uint64_t>(), 20u);
  fly(*method, obstacles, flying_object(4, 0.05), 11, 400);
  // The object on the zero-area triangle's middle vertex and on the point.
  TriangleSoup soup = flying_object(4, 0.02);
  PlacedObject object(soup);
  StudyCounters counters;
  for (const Point& p : {Point{0.4, 0.8, 0.6}, Point{0.8, 0.1, 0.7}}) {
    Pose pose;
    for (int a = 0; a < 3; ++a) pose.translation[a] = p[a] - soup.vertices[1][a];
    object.place(pose);
    EXPECT_TRUE(brute_force(object, obstacles));
    EXPECT_TRUE(method->collides(object, counters));
  }
}

TEST(MeshMethod, GridPointsAndLimitsAreHonoured) {
  const auto obstacles = environment_triangles(Environment::terrain, 200, 5);
  MeshMethodOptions options;
  options.grid_points = 5;
  options.max_rounds = 3;
  const auto method = make_mesh_method(obstacles, options);
  print_figures("terrain 200, grid 5, 3 rounds", *method);
  const auto details = method->statistics().details;
  EXPECT_LE(details["rounds"].get<std::uint64_t>(), 3u);
  EXPECT_EQ(details["bounding_vertices"].get<std::uint64_t>(), 8u + 125u);
  EXPECT_EQ(method->parameters(), "Delaunay + Steiner points, max rounds 3, grid 5");
  fly(*method, obstacles, flying_object(4, 0.05), 5, 200);
}

TEST(MeshMethod, RejectsBadInput) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_THROW(make_mesh_method({}), InputError);
  const std::vector<Triangle> with_nan = {{Point{0, 0, 0}, Point{1, 0, 0}, Point{0, nan, 0}}};
  EXPECT_THROW(make_mesh_method(with_nan), InputError);
  const std::vector<Triangle> with_inf = {{Point{0, 0, 0}, Point{inf, 0, 0}, Point{0, 1, 0}}};
  EXPECT_THROW(make_mesh_method(with_inf), InputError);
  const std::vector<Triangle> fine = {{Point{0, 0, 0}, Point{1, 0, 0}, Point{0, 1, 0}}};
  MeshMethodOptions options;
  options.max_growth = nan;
  EXPECT_THROW(make_mesh_method(fine, options), InputError);
  EXPECT_NO_THROW(make_mesh_method(fine));
}

}  // namespace
}  // namespace tetrapage::study
