// The study's grid, 3d-tree and R-tree against brute force (every object triangle against
// every obstacle triangle, the kernel's exact test): random poses through generated tetras,
// scenes and terrains, touching contacts on voxel and cut boundaries, and bad input.

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/runtime/geometry/TriangleTriangle.h"
#include "tetrapage/study/BoxMethods.h"
#include "tetrapage/tools/MeshLibrary.h"
#include "tetrapage/tools/ObjectGenerator.h"
#include "tetrapage/tools/Random.h"
#include "tetrapage/tools/StudyEnvironment.h"

namespace tetrapage::study {
namespace {

namespace fs = std::filesystem;

// A generated environment written to a file and read back, as the benchmark does.
std::vector<geometry::Triangle> generated(EnvironmentKind kind, std::uint64_t triangles, std::uint64_t seed) {
  const fs::path folder = fs::path(TETRAPAGE_TEST_TMP) / ("study-" + std::to_string(::getpid()));
  fs::create_directories(folder);
  const fs::path path = folder / (to_string(kind) + ".ply");
  {
    MeshWriter writer(path);
    generate_environment(kind, triangles, seed, writer);
    writer.commit();
  }
  auto triangles_read = read_mesh(path).all_corners();
  fs::remove_all(folder);
  return triangles_read;
}

std::vector<geometry::Triangle> tetras(std::uint64_t triangles) { return generated(EnvironmentKind::tetras, triangles, 3); }
std::vector<geometry::Triangle> scene(std::uint64_t triangles) { return generated(EnvironmentKind::scene, triangles, 4); }
std::vector<geometry::Triangle> terrain(std::uint64_t triangles) { return generated(EnvironmentKind::terrain, triangles, 5); }

bool brute_force(const PlacedObject& object, std::span<const geometry::Triangle> obstacles) {
  for (const auto& t : object.triangles())
    for (const auto& o : obstacles)
      if (geometry::triangles_intersect(t, o)) return true;
  return false;
}

std::vector<std::unique_ptr<StudyMethod>> all_box_methods(std::span<const geometry::Triangle> obstacles) {
  std::vector<std::unique_ptr<StudyMethod>> methods;
  methods.push_back(make_grid_method(obstacles));
  methods.push_back(make_grid_method(obstacles, GridOptions{7}));
  for (const auto rule : {KdAxisRule::min_max_count, KdAxisRule::min_count_gap, KdAxisRule::min_count_product,
                          KdAxisRule::longest_side}) {
    KdTreeOptions o;
    o.axis_rule = rule;
    methods.push_back(make_kd_tree_method(obstacles, o));
  }
  methods.push_back(make_r_tree_method(obstacles));
  methods.push_back(make_r_tree_method(obstacles, RTreeOptions{4, RTreeSplitRule::min_volume_sum}));
  return methods;
}

Pose random_pose(Random& random, double lo, double hi) {
  Pose pose;
  for (auto& c : pose.translation) c = random.uniform(lo, hi);
  std::array<double, 4> q{random.normal(), random.normal(), random.normal(), random.normal()};
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (auto& c : q) c /= n;
  pose.rotation = q;
  return pose;
}

// Every method answers every pose as brute force does; returns the collisions seen.
int expect_methods_agree(std::span<const geometry::Triangle> obstacles, const TriangleSoup& object_soup,
                         int poses, std::uint64_t seed) {
  auto methods = all_box_methods(obstacles);
  PlacedObject object(object_soup);
  Random random(seed);
  int hits = 0;
  std::vector<StudyCounters> counters(methods.size());
  for (int i = 0; i < poses; ++i) {
    object.place(random_pose(random, -0.02, 1.02));
    const bool expected = brute_force(object, obstacles);
    hits += expected;
    for (std::size_t m = 0; m < methods.size(); ++m)
      EXPECT_EQ(methods[m]->collides(object, counters[m]), expected)
          << methods[m]->name() << " " << methods[m]->parameters() << ", pose " << i;
  }
  for (std::size_t m = 0; m < methods.size(); ++m) {
    EXPECT_EQ(counters[m].queries, std::uint64_t(poses));
    EXPECT_EQ(counters[m].collisions, std::uint64_t(hits)) << methods[m]->name();
    EXPECT_GE(counters[m].full_checks, counters[m].collisions) << methods[m]->name();
    EXPECT_GT(counters[m].cells_visited + counters[m].nodes_visited, 0u) << methods[m]->name();
  }
  return hits;
}

TriangleSoup object_of(std::uint64_t triangles) {
  ObjectOptions o;
  o.triangles = triangles;
  o.size = 0.08;
  static const MeshLibrary library = MeshLibrary::load_default();
  return generate_object(o, &library).soup;
}

TEST(BoxMethods, AgreeWithBruteForceOnTetras) {
  const auto obstacles = tetras(1000);
  EXPECT_GT(expect_methods_agree(obstacles, object_of(116), 400, 1), 20);
}

TEST(BoxMethods, AgreeWithBruteForceOnAScene) {
  const auto obstacles = scene(3000);
  EXPECT_GT(expect_methods_agree(obstacles, object_of(4), 400, 2), 10);
}

TEST(BoxMethods, AgreeWithBruteForceOnATerrain) {
  const auto obstacles = terrain(2000);
  EXPECT_GT(expect_methods_agree(obstacles, object_of(496), 300, 3), 15);
}

// An axis-aligned square on the plane x = 0.5, which with N = 2 is the cut between the two
// voxel columns and the 3d-tree's first cut; a tetrahedron that only touches it, by a vertex,
// along an edge, by a face, or misses it by one ulp.
TEST(BoxMethods, TouchingContactsOnCellAndCutBoundaries) {
  std::vector<geometry::Triangle> obstacles = {
      {{{0.5, 0, 0}, {0.5, 1, 0}, {0.5, 1, 1}}},
      {{{0.5, 0, 0}, {0.5, 1, 1}, {0.5, 0, 1}}},
      // Two far triangles so that the workspace is [0,1]^3 and the cut sits at 0.5.
      {{{0, 0, 0}, {0.01, 0, 0}, {0, 0.01, 0}}},
      {{{1, 1, 1}, {0.99, 1, 1}, {1, 0.99, 1}}},
  };
  std::vector<std::unique_ptr<StudyMethod>> methods;
  methods.push_back(make_grid_method(obstacles, GridOptions{2}));
  methods.push_back(make_grid_method(obstacles, GridOptions{40}));
  methods.push_back(make_kd_tree_method(obstacles, KdTreeOptions{1}));
  methods.push_back(make_r_tree_method(obstacles));
  // Tetrahedra whose largest x is 0 at a vertex, or on a face: placed with the identity
  // rotation, that x becomes the translation's exactly.
  auto tetrahedron = [](std::vector<Vec3> vertices) {
    TriangleSoup soup;
    soup.vertices = std::move(vertices);
    soup.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    return soup;
  };
  const TriangleSoup by_vertex = tetrahedron({{0, 0, 0}, {-0.1, 0, 0}, {-0.1, 0.1, 0}, {-0.1, 0, 0.1}});
  const TriangleSoup by_face = tetrahedron({{0, 0, 0}, {0, 0.1, 0}, {0, 0, 0.1}, {-0.1, 0, 0}});
  const double below = std::nextafter(0.5, 0.0);
  struct Case {
    const char* what;
    const TriangleSoup* soup;
    Vec3 translation;
    bool collides;
  };
  const std::vector<Case> cases = {
      {"vertex on the square", &by_vertex, {0.5, 0.3, 0.4}, true},
      {"vertex one ulp short", &by_vertex, {below, 0.3, 0.4}, false},
      {"face lying on it", &by_face, {0.5, 0.3, 0.4}, true},
      {"face one ulp short", &by_face, {below, 0.3, 0.4}, false},
      {"vertex on the square's corner", &by_vertex, {0.5, 1.0, 1.0}, true},
  };
  for (const auto& c : cases) {
    PlacedObject object(*c.soup);
    object.place(Pose{c.translation, {1, 0, 0, 0}});
    EXPECT_EQ(brute_force(object, obstacles), c.collides) << c.what << " (the oracle itself)";
    for (auto& m : methods) {
      StudyCounters counters;
      EXPECT_EQ(m->collides(object, counters), c.collides) << m->name() << " " << m->parameters() << ": " << c.what;
    }
  }
}

TEST(BoxMethods, StatisticsDescribeTheStructures) {
  const auto obstacles = tetras(400);
  const auto grid = make_grid_method(obstacles)->statistics();
  EXPECT_EQ(grid.obstacle_triangles, obstacles.size());
  EXPECT_GE(grid.stored_triangles, obstacles.size()) << "every triangle meets at least one voxel";
  EXPECT_EQ(grid.details["cells"], 40u * 40u * 40u);
  const auto kd = make_kd_tree_method(obstacles)->statistics();
  EXPECT_GE(kd.stored_triangles, obstacles.size());
  EXPECT_GT(kd.height, 3u);
  const auto r = make_r_tree_method(obstacles)->statistics();
  EXPECT_EQ(r.stored_triangles, obstacles.size()) << "K = 1: each triangle once";
  // A balanced binary tree of 400 leaves: height ceil(log2(400)) = 9.
  EXPECT_EQ(r.height, 9u);
  EXPECT_EQ(r.details["nodes"], 2 * obstacles.size() - 1);
}

TEST(BoxMethods, BadInputIsAClearError) {
  std::vector<geometry::Triangle> none;
  EXPECT_THROW(make_grid_method(none), InputError);
  EXPECT_THROW(make_kd_tree_method(none), InputError);
  EXPECT_THROW(make_r_tree_method(none), InputError);
  std::vector<geometry::Triangle> nan = {{{{0, 0, 0}, {1, 0, 0}, {0, std::nan(""), 0}}}};
  EXPECT_THROW(make_grid_method(nan), InputError);
  EXPECT_THROW(make_kd_tree_method(nan), InputError);
  EXPECT_THROW(make_r_tree_method(nan), InputError);
  std::vector<geometry::Triangle> one = {{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}}};
  EXPECT_THROW(make_grid_method(one, GridOptions{0}), InputError);
  EXPECT_THROW(make_kd_tree_method(one, KdTreeOptions{0}), InputError);
  EXPECT_THROW(make_r_tree_method(one, RTreeOptions{0}), InputError);
  // A flat environment (every z equal) and a single triangle still answer.
  for (auto& m : all_box_methods(one)) {
    TriangleSoup soup;
    soup.vertices = {{0.2, 0.2, -0.1}, {0.3, 0.2, 0.1}, {0.2, 0.3, 0.1}};
    soup.triangles = {{0, 1, 2}};
    PlacedObject object(soup);
    StudyCounters counters;
    EXPECT_TRUE(m->collides(object, counters)) << m->name();
  }
}

}  // namespace
}  // namespace tetrapage::study
