// ObjectGroup against an independent brute force written here with CGAL (its exact-predicates
// kernel's triangle/triangle test over every pair of placed triangles, and its
// Side_of_triangle_mesh for one object inside another), placed by apply_pose (the canonical
// placement) and nothing else of the runtime: cubes touching at a vertex, an edge and a face,
// or missing by one ulp; a cube and a sphere nested; 2, 8 and 64 objects at random poses at
// scales 1e-9, 1 and 1e9, near and far from the origin. Each object's environment answer is a
// lone FlyingObject's; the C API answers what the C++ API answers.

#include <gtest/gtest.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/intersections.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/preprocess/Preprocess.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/runtime/query/ObjectGroup.h"
#include "tetrapage/tetrapage.h"
#include "tetrapage/tools/MeshLibrary.h"
#include "tetrapage/tools/ObjectGenerator.h"
#include "tetrapage/tools/StudyEnvironment.h"

namespace tetrapage {
namespace {

namespace fs = std::filesystem;
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Mesh = CGAL::Surface_mesh<K::Point_3>;
using ModelPtr = std::shared_ptr<const ObjectModel>;

// ---- Objects ----------------------------------------------------------------------------

// The closed cube [-h, h]^3, faces outwards.
TriangleSoup cube(double h) {
  TriangleSoup soup;
  for (int c = 0; c < 8; ++c)
    soup.vertices.push_back({c & 1 ? h : -h, c & 2 ? h : -h, c & 4 ? h : -h});
  soup.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                    {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  soup.part_of.assign(soup.triangles.size(), 0);
  soup.part_names = {"cube"};
  return soup;
}

TriangleSoup scaled(TriangleSoup soup, double s) {
  for (auto& v : soup.vertices)
    for (auto& x : v) x *= s;
  return soup;
}

TriangleSoup sphere() {
  ObjectOptions options;
  options.triangles = 116;
  return generate_object(options).soup;
}

// A real, non-convex mesh of about 300 triangles (generated once: it simplifies a library mesh).
const TriangleSoup& real_mesh() {
  static const TriangleSoup mesh = [] {
    const MeshLibrary library = MeshLibrary::load_default();
    ObjectOptions options;
    options.triangles = 300;
    return generate_object(options, &library).soup;
  }();
  return mesh;
}

ModelPtr model_of(TriangleSoup soup) {
  return std::make_shared<const ObjectModel>(std::move(soup));
}

Pose at(double x, double y, double z, std::array<double, 4> q = {1, 0, 0, 0}) {
  Pose pose;
  pose.translation = {x, y, z};
  pose.rotation = q;
  return pose;
}

std::array<double, 4> random_rotation(std::mt19937_64& random) {
  std::normal_distribution<double> normal;
  std::array<double, 4> q{};
  double n = 0;
  for (auto& c : q) c = normal(random), n += c * c;
  for (auto& c : q) c /= std::sqrt(n);
  return q;
}

// ---- The oracle: CGAL on the placed triangles -------------------------------------------

struct Placed {
  const TriangleSoup* soup = nullptr;
  std::vector<K::Point_3> points;
  std::vector<K::Triangle_3> triangles;
  std::vector<CGAL::Bbox_3> boxes;
  CGAL::Bbox_3 box;
  std::unique_ptr<Mesh> mesh;  // built when a containment question needs it
  std::unique_ptr<CGAL::Side_of_triangle_mesh<Mesh, K>> side;
};

Placed place(const TriangleSoup& soup, const Pose& pose) {
  Placed placed;
  placed.soup = &soup;
  for (const auto& v : soup.vertices) {
    const Vec3 w = apply_pose(pose, v);
    placed.points.emplace_back(w[0], w[1], w[2]);
    placed.box += placed.points.back().bbox();
  }
  for (const auto& t : soup.triangles) {
    placed.triangles.emplace_back(placed.points[t[0]], placed.points[t[1]], placed.points[t[2]]);
    placed.boxes.push_back(placed.triangles.back().bbox());
  }
  return placed;
}

// Closed triangles meet; a degenerate one (collinear corners, possible after rounding) is the
// union of its edges.
bool meet(const K::Triangle_3& a, const K::Triangle_3& b) {
  const auto edges = [](const K::Triangle_3& t) {
    return std::array<K::Segment_3, 3>{K::Segment_3(t[0], t[1]), K::Segment_3(t[1], t[2]),
                                       K::Segment_3(t[2], t[0])};
  };
  if (!a.is_degenerate() && !b.is_degenerate()) return CGAL::do_intersect(a, b);
  if (a.is_degenerate() && b.is_degenerate()) {
    for (const auto& e : edges(a))
      for (const auto& f : edges(b))
        if (CGAL::do_intersect(e, f)) return true;
    return false;
  }
  const K::Triangle_3& whole = a.is_degenerate() ? b : a;
  for (const auto& e : edges(a.is_degenerate() ? a : b))
    if (CGAL::do_intersect(e, whole)) return true;
  return false;
}

std::vector<TrianglePair> oracle_triangle_pairs(const Placed& a, const Placed& b) {
  std::vector<TrianglePair> pairs;
  for (std::uint32_t i = 0; i < a.triangles.size(); ++i) {
    if (!CGAL::do_overlap(a.boxes[i], b.box)) continue;
    for (std::uint32_t j = 0; j < b.triangles.size(); ++j)
      if (CGAL::do_overlap(a.boxes[i], b.boxes[j]) && meet(a.triangles[i], b.triangles[j]))
        pairs.push_back({i, j});
  }
  return pairs;
}

// Is p strictly inside the closed placed object? (The test's objects are one closed,
// connected surface each.)
bool oracle_inside(Placed& outer, const K::Point_3& p) {
  if (!CGAL::do_overlap(outer.box, p.bbox())) return false;
  if (!outer.side) {
    outer.mesh = std::make_unique<Mesh>();
    std::vector<Mesh::Vertex_index> vertices;
    for (const auto& q : outer.points) vertices.push_back(outer.mesh->add_vertex(q));
    for (const auto& t : outer.soup->triangles)
      outer.mesh->add_face(vertices[t[0]], vertices[t[1]], vertices[t[2]]);
    outer.side = std::make_unique<CGAL::Side_of_triangle_mesh<Mesh, K>>(*outer.mesh);
  }
  return (*outer.side)(p) == CGAL::ON_BOUNDED_SIDE;
}

struct OraclePair {
  std::uint32_t first, second;
  PairContainment containment;
  std::vector<TrianglePair> triangles;
};

// Every pair of objects: their triangle pairs; with none, one object's vertex inside the other
// (with no surface contact, one vertex decides for a connected object).
std::vector<OraclePair> oracle_step(std::vector<Placed>& placed) {
  std::vector<OraclePair> pairs;
  for (std::uint32_t i = 0; i < placed.size(); ++i)
    for (std::uint32_t j = i + 1; j < placed.size(); ++j) {
      if (!CGAL::do_overlap(placed[i].box, placed[j].box)) continue;
      OraclePair pair{i, j, PairContainment::none, oracle_triangle_pairs(placed[i], placed[j])};
      if (pair.triangles.empty()) {
        if (oracle_inside(placed[j], placed[i].points[0]))
          pair.containment = PairContainment::first_inside_second;
        else if (oracle_inside(placed[i], placed[j].points[0]))
          pair.containment = PairContainment::second_inside_first;
        else
          continue;
      }
      pairs.push_back(std::move(pair));
    }
  return pairs;
}

std::vector<OraclePair> oracle_for(const std::vector<const TriangleSoup*>& soups,
                                   std::span<const Pose> poses) {
  std::vector<Placed> placed;
  for (std::size_t i = 0; i < soups.size(); ++i) placed.push_back(place(*soups[i], poses[i]));
  return oracle_step(placed);
}

// What the test saw, so that it can insist on having checked something.
struct Seen {
  std::size_t touching = 0, containment = 0, apart_boxes_overlap = 0;
};

void expect_oracle(const GroupResult& result, const std::vector<OraclePair>& oracle, QueryMode mode,
                   const std::string& where, Seen* seen = nullptr) {
  ASSERT_EQ(result.pairs.size(), oracle.size()) << where;
  for (std::size_t k = 0; k < oracle.size(); ++k) {
    const CollidingPair& got = result.pairs[k];
    const OraclePair& want = oracle[k];
    ASSERT_EQ(got.first, want.first) << where << " pair " << k;
    ASSERT_EQ(got.second, want.second) << where << " pair " << k;
    EXPECT_EQ(got.containment, want.containment)
        << where << " pair " << want.first << "," << want.second;
    const auto triangles = result.triangles_of(got);
    if (mode == QueryMode::all_contacts) {
      EXPECT_TRUE(std::equal(triangles.begin(), triangles.end(), want.triangles.begin(),
                             want.triangles.end()))
          << where << " pair " << want.first << "," << want.second << ": " << triangles.size()
          << " triangle pairs, " << want.triangles.size() << " by brute force";
    } else if (want.triangles.empty()) {
      EXPECT_TRUE(triangles.empty()) << where;
    } else {
      ASSERT_EQ(triangles.size(), 1u) << where;
      EXPECT_TRUE(std::binary_search(want.triangles.begin(), want.triangles.end(), triangles[0]))
          << where;
    }
    if (seen) ++(want.triangles.empty() ? seen->containment : seen->touching);
  }
  if (seen) seen->apart_boxes_overlap += result.counters.box_pairs - oracle.size();
}

// ---- Contacts made on purpose -----------------------------------------------------------

struct Case {
  const char* name;
  Vec3 offset;  // of the second cube, in cube sides
  bool collides;
  int nudged_axis = -1;  // the translation moved one ulp away from contact along this axis
};

// Two cubes of side s, the first at c (c, c, c), the second beside it. Powers of two keep every
// placed coordinate exact, so the expected answers are known, and the brute force agrees.
TEST(ObjectGroup, CubesTouchAtVertexEdgeFaceAndMissByOneUlp) {
  const std::vector<Case> cases{
      {"face", {1, 0, 0}, true},         {"edge", {1, 1, 0}, true},
      {"vertex", {1, 1, 1}, true},       {"face gap", {1, 0, 0}, false, 0},
      {"edge gap", {1, 1, 0}, false, 1}, {"vertex gap", {1, 1, 1}, false, 2},
      {"overlap", {0.5, 0.25, 0}, true}, {"half face", {1, 0.5, 0.5}, true},
      {"far", {10, 3, 0}, false},
  };
  for (const double s : {0x1p-30, 1.0, 0x1p30})
    for (const double c : {0.0, 0x1p20 * s, 1e6}) {
      const TriangleSoup soup = cube(s / 2);
      ObjectGroup group(nullptr, {model_of(soup), model_of(soup)});
      for (const Case& k : cases) {
        for (const QueryMode mode : {QueryMode::first_hit, QueryMode::all_contacts}) {
          std::array<Pose, 2> poses{
              at(c, c, c), at(c + k.offset[0] * s, c + k.offset[1] * s, c + k.offset[2] * s)};
          if (k.nudged_axis >= 0) {
            double& t = poses[1].translation[k.nudged_axis];
            t = std::nextafter(t, std::numeric_limits<double>::infinity());
          }
          GroupQueryOptions options;
          options.pair_mode = mode;
          const GroupResult result = group.step(poses, options);
          const std::string where = std::string(k.name) + " at scale " + std::to_string(s) +
                                    " offset " + std::to_string(c);
          expect_oracle(result, oracle_for({&soup, &soup}, poses), mode, where);
          // At 1e6 a 2^-30 cube rounds into another shape: the brute force alone decides there.
          if (c != 1e6 || s >= 1) {
            EXPECT_EQ(!result.pairs.empty(), k.collides) << where;
          }
        }
      }
    }
}

// A cube rotated at random, and a second cube whose corner is put on one of the first's placed
// corners (within the rounding of the subtraction): grazing contacts in general position.
TEST(ObjectGroup, RotatedCubesGrazingAtACorner) {
  std::mt19937_64 random(11);
  const TriangleSoup soup = cube(0.5);
  ObjectGroup group(nullptr, {model_of(soup), model_of(soup)});
  Seen seen;
  for (int trial = 0; trial < 200; ++trial) {
    const Pose first = at(3, -2, 1, random_rotation(random));
    const Vec3 corner = apply_pose(first, soup.vertices[trial % 8]);
    const double d = trial % 3 == 0 ? 0 : (trial % 3 == 1 ? 1e-15 : -1e-15);
    const std::array<Pose, 2> poses{
        first, at(corner[0] + 0.5 + d, corner[1] + 0.5 + d, corner[2] + 0.5 + d)};
    GroupQueryOptions options;
    options.pair_mode = QueryMode::all_contacts;
    expect_oracle(group.step(poses, options), oracle_for({&soup, &soup}, poses), options.pair_mode,
                  "trial " + std::to_string(trial), &seen);
  }
  EXPECT_GT(seen.touching, 20u);
}

// ---- One object inside another ----------------------------------------------------------

TEST(ObjectGroup, ContainmentWithoutTouchingSurfaces) {
  const TriangleSoup ball = scaled(sphere(), 20);  // fits a cube of side 1
  const TriangleSoup small = cube(0.05), big = cube(2), tiny = cube(0.005);
  ObjectGroup group(nullptr, {model_of(small), model_of(ball), model_of(small), model_of(small),
                              model_of(big), model_of(tiny)});
  const std::vector<const TriangleSoup*> soups{&small, &ball, &small, &small, &big, &tiny};
  // 0: inside the ball (and the big cube); 2: in the ball's box corner, outside it; 3: across
  // the ball's surface; 4: the big cube around everything, touching nothing; 5: inside the
  // ball, just under its surface (where the interior grid cannot tell: a crossing parity).
  const std::array<Pose, 6> poses{at(0.01, 0.02, -0.03), at(0, 0, 0),   at(0.44, 0.44, 0.44),
                                  at(0.5, 0, 0),         at(0, 0, 0.1), at(0.47, 0.003, 0.002)};
  for (const bool containment : {true, false}) {
    GroupQueryOptions options;
    options.pair_containment = containment;
    options.pair_mode = QueryMode::all_contacts;
    const GroupResult result = group.step(poses, options);
    auto oracle = oracle_for(soups, poses);
    if (!containment)
      std::erase_if(oracle,
                    [](const OraclePair& p) { return p.containment != PairContainment::none; });
    expect_oracle(result, oracle, options.pair_mode,
                  containment ? "with containment" : "surfaces only");
    const auto find = [&](std::uint32_t i, std::uint32_t j) -> const CollidingPair* {
      for (const auto& p : result.pairs)
        if (p.first == i && p.second == j) return &p;
      return nullptr;
    };
    if (containment) {
      ASSERT_TRUE(find(0, 1));
      EXPECT_EQ(find(0, 1)->containment, PairContainment::first_inside_second);
      ASSERT_TRUE(find(1, 4));
      EXPECT_EQ(find(1, 4)->containment, PairContainment::first_inside_second);
      ASSERT_TRUE(find(1, 5));
      EXPECT_EQ(find(1, 5)->containment, PairContainment::second_inside_first);
    } else {
      EXPECT_FALSE(find(0, 1));
    }
    EXPECT_FALSE(find(1, 2));
    ASSERT_TRUE(find(1, 3));
    EXPECT_EQ(find(1, 3)->containment, PairContainment::none);
  }
}

// ---- Random poses ------------------------------------------------------------------------

// n objects (cubes, spheres and a real mesh, in turn) at random poses in a box about as wide
// as cbrt(n) objects, so that some pairs touch and most do not.
void check_random(std::size_t n, std::size_t steps, double scale, double offset, std::uint64_t seed,
                  Seen& seen) {
  static const TriangleSoup sphere_soup = sphere();
  const std::array<TriangleSoup, 3> kinds{scaled(cube(0.02), scale), scaled(sphere_soup, scale),
                                          scaled(real_mesh(), scale)};
  std::array<ModelPtr, 3> models;
  for (int k = 0; k < 3; ++k) models[k] = model_of(kinds[k]);
  std::vector<ModelPtr> group_models;
  std::vector<const TriangleSoup*> soups;
  for (std::size_t i = 0; i < n; ++i)
    group_models.push_back(models[i % 3]), soups.push_back(&kinds[i % 3]);
  ObjectGroup group(nullptr, group_models);
  std::mt19937_64 random(seed);
  const double side = 0.04 * std::cbrt(double(n)) * scale;
  std::uniform_real_distribution<double> within(offset, offset + side);
  std::vector<Pose> poses(n);
  GroupResult result;
  for (std::size_t step = 0; step < steps; ++step) {
    for (auto& pose : poses)
      pose = at(within(random), within(random), within(random), random_rotation(random));
    const auto oracle = oracle_for(soups, poses);
    for (const QueryMode mode : {QueryMode::first_hit, QueryMode::all_contacts}) {
      GroupQueryOptions options;
      options.pair_mode = mode;
      group.step(poses, options, result);
      expect_oracle(result, oracle, mode,
                    std::to_string(n) + " objects, scale " + std::to_string(scale) + ", offset " +
                        std::to_string(offset) + ", step " + std::to_string(step),
                    mode == QueryMode::all_contacts ? &seen : nullptr);
      if (::testing::Test::HasFatalFailure()) return;
    }
  }
}

TEST(ObjectGroup, RandomPosesMatchBruteForce) {
  for (const double scale : {1e-9, 1.0, 1e9})
    for (const double offset : {0.0, 1e6 * scale}) {
      Seen seen;
      check_random(2, 150, scale, offset, 1, seen);
      check_random(8, 30, scale, offset, 2, seen);
      check_random(64, 5, scale, offset, 3, seen);
      // The poses made contacts, and boxes that overlap without one.
      EXPECT_GT(seen.touching, 100u) << scale << " " << offset;
      EXPECT_GT(seen.apart_boxes_overlap, 100u) << scale << " " << offset;
    }
}

TEST(ObjectGroup, RejectsBadInput) {
  EXPECT_THROW(ObjectGroup(nullptr, {}), InputError);
  EXPECT_THROW(ObjectGroup(nullptr, {model_of(cube(1)), nullptr}), InputError);
  ObjectGroup group(nullptr, {model_of(cube(1)), model_of(cube(1))});
  const std::array<Pose, 1> one{at(0, 0, 0)};
  EXPECT_THROW(group.step(one), InputError);
  const std::array<Pose, 2> bad{at(0, 0, 0), at(0, 0, 0, {1, 1, 0, 0})};
  try {
    group.step(bad);
    ADD_FAILURE() << "a non-unit quaternion was taken";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("object 1"), std::string::npos) << e.what();
  }
}

// ---- The environment, and the C API -----------------------------------------------------

struct Environment {
  fs::path index_path;
  std::shared_ptr<const CollisionIndex> index;
  BoundingBox bounds;
};

const Environment& environment() {
  static const Environment env = [] {
    const fs::path folder = fs::path(TETRAPAGE_TEST_TMP) / "group";
    fs::remove_all(folder);
    fs::create_directories(folder);
    {
      MeshWriter writer(folder / "tetras.ply");
      generate_environment(EnvironmentKind::tetras, 4000, 5, writer);
      writer.commit();
    }
    PreprocessOptions options;
    options.interiors = true;
    options.threads = 1;
    preprocess({folder / "tetras.ply"}, folder / "tetras.tpi", options);
    Environment e;
    e.index_path = folder / "tetras.tpi";
    e.index = std::make_shared<const CollisionIndex>(e.index_path, CollisionIndexOptions{});
    e.bounds = e.index->header().bounds;
    return e;
  }();
  return env;
}

// Poses of n objects random-walking through the environment's box.
std::vector<std::vector<Pose>> walk(std::size_t n, std::size_t steps, const BoundingBox& box,
                                    std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> unit(0, 1), jitter(-0.02, 0.02);
  std::vector<Pose> poses(n);
  for (auto& pose : poses)
    for (int a = 0; a < 3; ++a)
      pose.translation[a] = box.lo[a] + unit(random) * (box.hi[a] - box.lo[a]);
  std::vector<std::vector<Pose>> flight;
  for (std::size_t step = 0; step < steps; ++step) {
    for (auto& pose : poses) {
      for (int a = 0; a < 3; ++a)
        pose.translation[a] =
            std::clamp(pose.translation[a] + jitter(random), box.lo[a], box.hi[a]);
      pose.rotation = random_rotation(random);
    }
    flight.push_back(poses);
  }
  return flight;
}

void sort_contacts(std::vector<Contact>& contacts) {
  std::sort(contacts.begin(), contacts.end(), [](const Contact& a, const Contact& b) {
    return std::tie(a.environment_triangle, a.object_triangle) <
           std::tie(b.environment_triangle, b.object_triangle);
  });
}

TEST(ObjectGroup, EnvironmentAnswersAreLoneFlyingObjects) {
  const Environment& env = environment();
  const TriangleSoup ball = scaled(sphere(), 2), box = cube(0.04);
  const std::vector<ModelPtr> models{model_of(ball), model_of(box), model_of(real_mesh()),
                                     model_of(ball), model_of(box), model_of(real_mesh()),
                                     model_of(ball), model_of(box)};
  const std::vector<const TriangleSoup*> soups{&ball, &box,         &real_mesh(), &ball,
                                               &box,  &real_mesh(), &ball,        &box};
  // In a box a few objects wide, so that they also meet each other.
  BoundingBox middle = env.bounds;
  for (int a = 0; a < 3; ++a) {
    const double c = (middle.lo[a] + middle.hi[a]) / 2;
    middle.lo[a] = c - 0.08, middle.hi[a] = c + 0.08;
  }
  const auto flight = walk(models.size(), 40, middle, 9);
  std::size_t collisions = 0, pairs = 0;
  for (const bool parallel : {false, true}) {
    ObjectGroup group(env.index, models);
    std::vector<FlyingObject> lone;
    for (const auto& model : models) lone.emplace_back(env.index, model);
    GroupQueryOptions options;
    options.parallel = parallel;
    options.environment.mode = QueryMode::all_contacts;
    options.pair_mode = QueryMode::all_contacts;
    GroupResult result;
    for (std::size_t step = 0; step < flight.size(); ++step) {
      group.step(flight[step], options, result);
      ASSERT_EQ(result.environment.size(), models.size());
      for (std::size_t i = 0; i < models.size(); ++i) {
        QueryResult alone = lone[i].query(flight[step][i], options.environment);
        QueryResult got = result.environment[i];
        const std::string where = "step " + std::to_string(step) + " object " + std::to_string(i);
        EXPECT_EQ(got.collides, alone.collides) << where;
        EXPECT_EQ(got.containment, alone.containment) << where;
        sort_contacts(got.contacts);
        sort_contacts(alone.contacts);
        EXPECT_EQ(got.contacts, alone.contacts) << where;
        collisions += got.collides;
      }
      expect_oracle(result, oracle_for(soups, flight[step]), options.pair_mode,
                    "step " + std::to_string(step));
      pairs += result.pairs.size();
    }
  }
  EXPECT_GT(collisions, 10u);
  EXPECT_GT(pairs, 0u);
}

TEST(ObjectGroup, CApiAgreesWithCpp) {
  const Environment& env = environment();
  tetrapage_index* index = nullptr;
  ASSERT_EQ(tetrapage_open(env.index_path.c_str(), TETRAPAGE_DEFAULT_BUDGET_BYTES, &index),
            TETRAPAGE_OK)
      << tetrapage_last_error();
  const std::vector<TriangleSoup> soups{scaled(sphere(), 2), cube(0.04), real_mesh(),
                                        scaled(sphere(), 3)};
  std::vector<tetrapage_object*> objects;
  std::vector<ModelPtr> models;
  for (const auto& soup : soups) {
    std::vector<double> vertices;
    for (const auto& v : soup.vertices) vertices.insert(vertices.end(), v.begin(), v.end());
    std::vector<std::uint32_t> triangles;
    for (const auto& t : soup.triangles) triangles.insert(triangles.end(), t.begin(), t.end());
    tetrapage_object* object = nullptr;
    ASSERT_EQ(tetrapage_object_create(index, vertices.data(), soup.vertices.size(),
                                      triangles.data(), soup.triangles.size(), &object),
              TETRAPAGE_OK);
    objects.push_back(object);
    models.push_back(model_of(soup));
  }
  tetrapage_group* group = nullptr;
  ASSERT_EQ(tetrapage_group_create(index, objects.data(), objects.size(), &group), TETRAPAGE_OK)
      << tetrapage_last_error();
  // The group keeps its objects' models: the handles may go.
  for (auto* object : objects) ASSERT_EQ(tetrapage_object_destroy(object), TETRAPAGE_OK);
  ObjectGroup cpp(env.index, models);
  // Objects close together, so that they also meet each other.
  BoundingBox middle = env.bounds;
  for (int a = 0; a < 3; ++a) {
    const double c = (middle.lo[a] + middle.hi[a]) / 2;
    middle.lo[a] = c - 0.05, middle.hi[a] = c + 0.05;
  }
  std::size_t pairs_seen = 0;
  for (const auto& poses : walk(soups.size(), 30, middle, 4)) {
    for (const int all : {0, 1}) {
      std::vector<double> flat;
      for (const auto& p : poses) {
        flat.insert(flat.end(), p.translation.begin(), p.translation.end());
        flat.insert(flat.end(), p.rotation.begin(), p.rotation.end());
      }
      size_t count = 0;
      ASSERT_EQ(tetrapage_group_step(group, flat.data(), all, &count), TETRAPAGE_OK)
          << tetrapage_last_error();
      GroupQueryOptions options;
      options.environment.mode = options.pair_mode =
          all ? QueryMode::all_contacts : QueryMode::first_hit;
      const GroupResult want = cpp.step(poses, options);
      ASSERT_EQ(count, want.pairs.size());
      pairs_seen += count;
      std::vector<std::uint32_t> pairs(2 * count + 2);
      size_t written = 0;
      ASSERT_EQ(tetrapage_group_pairs(group, pairs.data(), count + 1, &written), TETRAPAGE_OK);
      ASSERT_EQ(written, count);
      for (std::size_t k = 0; k < count; ++k) {
        EXPECT_EQ(pairs[2 * k], want.pairs[k].first);
        EXPECT_EQ(pairs[2 * k + 1], want.pairs[k].second);
        const auto triangles = want.triangles_of(want.pairs[k]);
        std::vector<std::uint32_t> got(2 * triangles.size());
        int containment = -1;
        ASSERT_EQ(tetrapage_group_pair_triangles(group, k, got.data(), triangles.size(), &written,
                                                 &containment),
                  TETRAPAGE_OK);
        ASSERT_EQ(written, triangles.size());
        EXPECT_EQ(containment, int(want.pairs[k].containment));
        for (std::size_t t = 0; t < triangles.size(); ++t) {
          EXPECT_EQ(got[2 * t], triangles[t].first_triangle);
          EXPECT_EQ(got[2 * t + 1], triangles[t].second_triangle);
        }
      }
      std::vector<int> collides(soups.size(), -1);
      ASSERT_EQ(tetrapage_group_environment(group, collides.data(), collides.size(), &written),
                TETRAPAGE_OK);
      ASSERT_EQ(written, soups.size());
      for (std::size_t i = 0; i < soups.size(); ++i)
        EXPECT_EQ(collides[i], want.environment[i].collides ? 1 : 0);
    }
  }
  EXPECT_GT(pairs_seen, 0u);

  // Errors, in the C API's conventions.
  size_t count = 7, written = 7;
  const std::vector<double> bad(7 * soups.size(), 0.0);  // zero quaternions
  EXPECT_EQ(tetrapage_group_step(group, bad.data(), 0, &count), TETRAPAGE_ERROR_INPUT);
  EXPECT_NE(std::string(tetrapage_last_error()).find("object 0"), std::string::npos)
      << tetrapage_last_error();
  EXPECT_EQ(count, 0u);
  EXPECT_EQ(tetrapage_group_pairs(group, nullptr, 0, &written), TETRAPAGE_OK);
  EXPECT_EQ(written, 0u);  // a failed step leaves no answer
  EXPECT_EQ(tetrapage_group_pair_triangles(group, 0, nullptr, 0, &written, nullptr),
            TETRAPAGE_ERROR_INPUT);
  EXPECT_EQ(tetrapage_group_step(group, nullptr, 0, &count), TETRAPAGE_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(tetrapage_group_pairs(group, nullptr, 1, &written), TETRAPAGE_ERROR_INVALID_ARGUMENT);
  tetrapage_group* none = nullptr;
  EXPECT_EQ(tetrapage_group_create(index, objects.data(), 0, &none), TETRAPAGE_ERROR_INPUT);
  EXPECT_EQ(tetrapage_group_create(index, objects.data(), objects.size(), &none),
            TETRAPAGE_ERROR_STALE_HANDLE);
  tetrapage_object* null_object = nullptr;
  EXPECT_EQ(tetrapage_group_create(index, &null_object, 1, &none),
            TETRAPAGE_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(tetrapage_last_error()).find("objects[0]"), std::string::npos)
      << tetrapage_last_error();
  EXPECT_EQ(none, nullptr);
  EXPECT_EQ(tetrapage_group_destroy(group), TETRAPAGE_OK);
  EXPECT_EQ(tetrapage_group_destroy(group), TETRAPAGE_ERROR_STALE_HANDLE);
  EXPECT_EQ(tetrapage_group_step(group, bad.data(), 0, &count), TETRAPAGE_ERROR_STALE_HANDLE);
  EXPECT_EQ(tetrapage_group_destroy(nullptr), TETRAPAGE_OK);
  EXPECT_EQ(tetrapage_close(index), TETRAPAGE_OK);
}

}  // namespace
}  // namespace tetrapage
