// The reference oracle on multi-solid soups, component by component: its component counts and
// closedness against the scene as the test built it, and its answers against a brute force
// that knows each component by construction (every triangle pair in CGAL's exact-construction
// kernel; insideness by the majority of five ray parities over one component's triangles).

#include <gtest/gtest.h>

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/tools/Random.h"
#include "tetrapage/tools/ReferenceCollider.h"

namespace tetrapage {
namespace {

using Exact = CGAL::Exact_predicates_exact_constructions_kernel;
using Corners = std::array<Vec3, 3>;

// One component as the test built it: its triangles and whether it is a closed surface.
struct Body {
  std::vector<Corners> triangles;
  bool closed = false;
};

// How a piece's triangles reach the soup: sharing vertex entries, or STL-style (three entries
// per triangle, every other triangle writing its zero coordinates as -0.0).
enum class Indexing { shared, separate };

// A soup built body by body, in one part (or none), remembering the bodies.
struct Scene {
  TriangleSoup soup;
  std::vector<Body> bodies;
  bool parts = true;

  // A body made of pieces; each piece gets its own vertex entries, so pieces of one body meet
  // only through identical coordinates.
  void add(const std::vector<std::vector<Corners>>& pieces, bool closed,
           Indexing indexing = Indexing::shared) {
    Body body{{}, closed};
    for (const auto& piece : pieces) {
      add_piece(piece, indexing);
      body.triangles.insert(body.triangles.end(), piece.begin(), piece.end());
    }
    bodies.push_back(body);
  }

  void add_piece(const std::vector<Corners>& piece, Indexing indexing) {
    if (parts && soup.part_names.empty()) soup.part_names.push_back("scene");
    std::map<Vec3, std::uint32_t> index;
    for (std::size_t t = 0; t < piece.size(); ++t) {
      TriangleIndices tri{};
      for (int k = 0; k < 3; ++k) {
        Vec3 v = piece[t][k];
        if (indexing == Indexing::separate) {
          if (t % 2 == 1)
            for (auto& x : v) x = x == 0.0 ? -0.0 : x;
          tri[k] = std::uint32_t(soup.vertices.size());
          soup.vertices.push_back(v);
          continue;
        }
        const auto [it, added] = index.emplace(v, std::uint32_t(soup.vertices.size()));
        if (added) soup.vertices.push_back(v);
        tri[k] = it->second;
      }
      soup.triangles.push_back(tri);
      if (parts) soup.part_of.push_back(0);
    }
  }
};

Vec3 plus(const Vec3& a, const Vec3& b) {
  return {a[0] + b[0], a[1] + b[1], a[2] + b[2]};
}

// The parallelepiped o + [0,1] u + [0,1] v + [0,1] w as 12 triangles (outward when u, v, w are
// right-handed), without its face at w = 1 when `open_top`.
std::vector<Corners> parallelepiped(const Vec3& o, const Vec3& u, const Vec3& v, const Vec3& w,
                                    bool open_top = false) {
  std::array<Vec3, 8> corner;
  for (int i = 0; i < 8; ++i) {
    corner[i] = o;
    if (i & 1) corner[i] = plus(corner[i], u);
    if (i & 2) corner[i] = plus(corner[i], v);
    if (i & 4) corner[i] = plus(corner[i], w);
  }
  const int faces[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                            {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  std::vector<Corners> out;
  for (int f = 0; f < 12; ++f) {
    if (open_top && (f == 2 || f == 3)) continue;  // the face at w = 1
    out.push_back({corner[faces[f][0]], corner[faces[f][1]], corner[faces[f][2]]});
  }
  return out;
}

std::vector<Corners> cube(const Vec3& lo, double side, bool open_top = false) {
  return parallelepiped(lo, {side, 0, 0}, {0, side, 0}, {0, 0, side}, open_top);
}

std::vector<Corners> quad(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return {{a, b, c}, {a, c, d}};
}

std::vector<Corners> tetrahedron(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return {{a, c, b}, {a, b, d}, {a, d, c}, {b, c, d}};
}

// The environment, in one part: a big cube with a small cube and a tetrahedron nested in it
// (neither connected to it), a tetrahedron, a
// box without its top, a lone quad, a self-intersecting closed component (a cube and a
// parallelepiped sharing one corner position, each with its own vertex entries), an STL-style
// cube, and three small solids for the objects to swallow.
Scene environment_scene() {
  Scene scene;
  scene.add({cube({0, 0, 0}, 10)}, true);
  scene.add({cube({4, 4, 4}, 2)}, true);
  scene.add({tetrahedron({1, 1, 6}, {3, 1, 6}, {1, 3, 6}, {1, 1, 8})}, true);  // nested too
  scene.add({tetrahedron({20, 0, 0}, {26, 0, 0}, {20, 6, 0}, {20, 0, 6})}, true);
  scene.add({cube({30, 0, 0}, 10, true)}, false);
  scene.add({quad({44, 20, 20}, {46, 20, 20}, {46, 22, 20}, {44, 22, 20})}, false);
  // The cube [50, 56]^3 and, from its corner (56, 56, 56), a parallelepiped reaching to
  // (42, 42, 42): they cross each other's faces and share only that corner.
  scene.add(
      {cube({50, 50, 50}, 6), parallelepiped({56, 56, 56}, {-8, -8, 2}, {-8, 2, -8}, {2, -8, -8})},
      true);
  scene.add({cube({60, -2, 0}, 2)}, true, Indexing::separate);
  scene.add({tetrahedron({79.5, 4.5, 4.5}, {80.5, 4.5, 4.5}, {79.5, 5.5, 4.5}, {79.5, 4.5, 5.5})},
            true);
  scene.add({cube({99.5, 4.5, 4.5}, 1)}, true);
  scene.add(
      {tetrahedron({119.8, 4.8, 4.8}, {120.2, 4.8, 4.8}, {119.8, 5.2, 4.8}, {119.8, 4.8, 5.2})},
      true);
  return scene;
}

Scene tetra_object(double s) {
  Scene scene;
  scene.add({tetrahedron({s, s, s}, {s, -s, -s}, {-s, s, -s}, {-s, -s, s})}, true);
  return scene;
}

// Two disjoint closed cubes as one object, with no part_of (one part).
Scene two_cubes_object() {
  Scene scene;
  scene.parts = false;
  scene.add({cube({-2, -2, -2}, 4)}, true);
  scene.add({cube({6, -0.5, -0.5}, 1)}, true);
  return scene;
}

// A box without its top and a closed cube as one object (the closed one second).
Scene closed_and_open_object() {
  Scene scene;
  scene.add({cube({6, -1.5, -1.5}, 3, true)}, false);
  scene.add({cube({-2, -2, -2}, 4)}, true);
  return scene;
}

Exact::Point_3 exact(const Vec3& v) {
  return {v[0], v[1], v[2]};
}

// A body in exact arithmetic, with the vertex that stands for it (the last triangle's second
// corner: the oracle may pick any, with no contact all agree).
struct ExactBody {
  std::vector<Exact::Triangle_3> triangles;
  bool closed = false;
  Vec3 vertex{};
};

// The bodies, each placed by apply_pose (no pose: as they are).
std::vector<ExactBody> exact_bodies(const Scene& scene, const Pose* pose = nullptr) {
  std::vector<ExactBody> out;
  for (const auto& body : scene.bodies) {
    ExactBody e{{}, body.closed, {}};
    for (const auto& t : body.triangles) {
      Corners c = t;
      if (pose)
        for (auto& v : c) v = apply_pose(*pose, v);
      e.triangles.emplace_back(exact(c[0]), exact(c[1]), exact(c[2]));
      e.vertex = c[1];
    }
    out.push_back(std::move(e));
  }
  return out;
}

// Odd parity along the majority of five fixed directions, over one body's triangles only.
bool brute_force_inside(const ExactBody& body, const Vec3& p) {
  static const std::array<Exact::Vector_3, 5> directions{
      Exact::Vector_3(0.3141592653, -0.2718281828, -1.0),
      Exact::Vector_3(0.5772156649, 0.7071067812, 0.1234567891),
      Exact::Vector_3(-0.8660254038, 0.1414213562, 0.4142135624),
      Exact::Vector_3(0.1732050808, -0.9, 0.2236067977), Exact::Vector_3(-0.3, -0.4, 0.8660254038)};
  int odd = 0;
  for (const auto& direction : directions) {
    const Exact::Ray_3 ray(exact(p), direction);
    int crossings = 0;
    for (const auto& t : body.triangles) crossings += CGAL::do_intersect(ray, t);
    odd += crossings % 2;
  }
  return odd >= 3;
}

bool brute_force_touch(const std::vector<ExactBody>& environment,
                       const std::vector<ExactBody>& object) {
  for (const auto& moving : object)
    for (const auto& m : moving.triangles)
      for (const auto& obstacle : environment)
        for (const auto& e : obstacle.triangles)
          if (CGAL::do_overlap(m.bbox(), e.bbox()) && CGAL::do_intersect(m, e)) return true;
  return false;
}

// The definition, spelled out over every pair of triangles and every pair of components.
ReferenceCollider::Answer brute_force(const std::vector<ExactBody>& environment,
                                      const Scene& object, const Pose& pose) {
  const std::vector<ExactBody> placed = exact_bodies(object, &pose);
  ReferenceCollider::Answer answer;
  answer.surfaces_touch = brute_force_touch(environment, placed);
  if (!answer.surfaces_touch)
    for (const auto& moving : placed)
      for (const auto& obstacle : environment)
        if (obstacle.closed && brute_force_inside(obstacle, moving.vertex))
          answer.object_inside = true;
  if (!answer.surfaces_touch && !answer.object_inside)
    for (const auto& obstacle : environment)
      for (const auto& moving : placed)
        if (moving.closed && brute_force_inside(moving, obstacle.vertex))
          answer.obstacle_inside = true;
  answer.collides = answer.surfaces_touch || answer.object_inside || answer.obstacle_inside;
  return answer;
}

Pose random_rotation(Random& random, const Vec3& translation) {
  Pose pose;
  pose.translation = translation;
  std::array<double, 4> q{random.normal(), random.normal(), random.normal(), random.normal()};
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (auto& c : q) c /= n;
  pose.rotation = q;
  return pose;
}

std::string describe(const ReferenceCollider::Answer& a) {
  return "touch " + std::to_string(a.surfaces_touch) + " object_inside " +
         std::to_string(a.object_inside) + " obstacle_inside " + std::to_string(a.obstacle_inside);
}

struct Tally {
  int poses = 0, disagreements = 0, touch = 0, object_inside = 0, obstacle_inside = 0, apart = 0;
};

// Every pose at its translation with the identity and three random rotations, plus jittered
// copies; each answer against brute force.
void compare(const ReferenceCollider& oracle, const Scene& environment, const Scene& object,
             const std::vector<Vec3>& spots, double jitter, Tally& tally) {
  const std::vector<ExactBody> exact_environment = exact_bodies(environment);
  Random random(17);
  for (const auto& spot : spots)
    for (int i = 0; i < 12; ++i) {
      Vec3 t = spot;
      if (i >= 4)
        for (auto& x : t) x += random.uniform(-jitter, jitter);
      const Pose pose = i == 0 ? Pose{t, {1, 0, 0, 0}} : random_rotation(random, t);
      const auto answer = oracle.query(pose);
      const auto expected = brute_force(exact_environment, object, pose);
      ++tally.poses;
      const bool same = answer.collides == expected.collides &&
                        answer.surfaces_touch == expected.surfaces_touch &&
                        answer.object_inside == expected.object_inside &&
                        answer.obstacle_inside == expected.obstacle_inside;
      if (!same && ++tally.disagreements <= 10)
        ADD_FAILURE() << "at (" << t[0] << ", " << t[1] << ", " << t[2] << ") pose " << i
                      << ": oracle " << describe(answer) << ", brute force " << describe(expected);
      tally.touch += answer.surfaces_touch;
      tally.object_inside += answer.object_inside;
      tally.obstacle_inside += answer.obstacle_inside;
      tally.apart += !answer.collides;
    }
}

TEST(ReferenceColliderComponents, CountsComponentsAndClosedness) {
  const Scene environment = environment_scene();
  const ReferenceCollider oracle(environment.soup, two_cubes_object().soup);
  // Eleven bodies: the self-intersecting pair is one component, the STL-style cube one.
  EXPECT_EQ(oracle.environment_components(), 11u);
  EXPECT_EQ(oracle.environment_closed_components(), 9u);
  EXPECT_EQ(oracle.object_components(), 2u);
  EXPECT_EQ(oracle.object_closed_components(), 2u);
  const ReferenceCollider mixed(environment.soup, closed_and_open_object().soup);
  EXPECT_EQ(mixed.object_components(), 2u);
  EXPECT_EQ(mixed.object_closed_components(), 1u);
}

TEST(ReferenceColliderComponents, PartsSplitComponents) {
  // One cube's faces split over two parts: two open components, though the positions match.
  TriangleSoup environment;
  environment.part_names = {"half", "other half"};
  const auto faces = cube({0, 0, 0}, 1);
  for (std::size_t f = 0; f < faces.size(); ++f) {
    for (const auto& v : faces[f]) environment.vertices.push_back(v);
    const auto base = std::uint32_t(environment.vertices.size() - 3);
    environment.triangles.push_back({base, base + 1, base + 2});
    environment.part_of.push_back(f < 6 ? 0 : 1);
  }
  const ReferenceCollider oracle(environment, tetra_object(0.1).soup);
  EXPECT_EQ(oracle.environment_components(), 2u);
  EXPECT_EQ(oracle.environment_closed_components(), 0u);
  EXPECT_FALSE(oracle.inside_environment({0.5, 0.5, 0.5}));
  environment.part_of.assign(environment.triangles.size(), 0);  // one part: one closed cube
  const ReferenceCollider whole(environment, tetra_object(0.1).soup);
  EXPECT_EQ(whole.environment_components(), 1u);
  EXPECT_EQ(whole.environment_closed_components(), 1u);
  EXPECT_TRUE(whole.inside_environment({0.5, 0.5, 0.5}));
}

TEST(ReferenceColliderComponents, InsideIsPerComponentParity) {
  const ReferenceCollider oracle(environment_scene().soup, tetra_object(0.1).soup);
  EXPECT_TRUE(oracle.inside_environment({2, 2, 2}));  // the big cube's cavity
  EXPECT_TRUE(oracle.inside_environment({5, 5, 5}));  // the nested cube, inside both
  EXPECT_TRUE(
      oracle.inside_environment({2.6, 2.6, 7.6}));  // the big cube; the nested tetrahedron's box
  EXPECT_TRUE(oracle.inside_environment({21.5, 1.5, 1.5}));    // the tetrahedron
  EXPECT_FALSE(oracle.inside_environment({35, 5, 5}));         // the open box
  EXPECT_TRUE(oracle.inside_environment({51, 55, 55}));        // the cube lobe only
  EXPECT_TRUE(oracle.inside_environment({43.4, 43.4, 43.4}));  // the parallelepiped lobe only
  EXPECT_FALSE(oracle.inside_environment({53, 53, 53}));       // both lobes: even parity
  EXPECT_TRUE(oracle.inside_environment({61, -1, 1}));         // the STL-style cube
  EXPECT_FALSE(oracle.inside_environment({70, 5, 5}));
}

TEST(ReferenceColliderComponents, AgreesWithBruteForce) {
  const Scene environment = environment_scene();
  Tally tally;
  {
    const Scene object = tetra_object(0.3);
    const ReferenceCollider oracle(environment.soup, object.soup);
    const std::vector<Vec3> spots{{2, 2, 2},   {5, 5, 5},    {2.6, 2.6, 7.6}, {21.5, 1.5, 1.5},
                                  {35, 5, 5},  {51, 55, 55}, {53, 53, 53},    {43.4, 43.4, 43.4},
                                  {61, -1, 1}, {10, 5, 5},   {4, 5, 5},       {45, 21, 20},
                                  {56, 56, 56}};
    compare(oracle, environment, object, spots, 1.0, tally);
    // The explicit cases: nested, cavity, open box, the self-intersecting lobes and overlap.
    EXPECT_TRUE(oracle.query(Pose{{2.6, 2.6, 7.6}, {1, 0, 0, 0}}).object_inside);
    EXPECT_TRUE(oracle.query(Pose{{5, 5, 5}, {1, 0, 0, 0}}).object_inside);
    EXPECT_TRUE(oracle.query(Pose{{2, 2, 2}, {1, 0, 0, 0}}).object_inside);
    EXPECT_FALSE(oracle.query(Pose{{35, 5, 5}, {1, 0, 0, 0}}).collides);
    EXPECT_TRUE(oracle.query(Pose{{43.4, 43.4, 43.4}, {1, 0, 0, 0}}).object_inside);
    EXPECT_FALSE(oracle.query(Pose{{53, 53, 53}, {1, 0, 0, 0}}).collides);
    EXPECT_TRUE(oracle.query(Pose{{10, 5, 5}, {1, 0, 0, 0}}).surfaces_touch);
  }
  {
    const Scene object = two_cubes_object();
    const ReferenceCollider oracle(environment.soup, object.soup);
    // The big cube around a small tetrahedron, around the lone quad; the small cube around the
    // smallest tetrahedron; the small cube in the big environment cube with the big one outside
    // it; and elsewhere.
    const std::vector<Vec3> spots{{80, 5, 5}, {45, 21, 20}, {113.5, 5, 5}, {2.5, 5, 12.5},
                                  {5, 5, 5},  {35, 5, 5},   {61, -1, 1}};
    compare(oracle, environment, object, spots, 0.5, tally);
    const auto around = oracle.query(Pose{{80, 5, 5}, {1, 0, 0, 0}});
    EXPECT_TRUE(around.obstacle_inside) << describe(around);
    // An open obstacle inside the big cube; a closed one inside the second cube.
    EXPECT_TRUE(oracle.query(Pose{{45, 21, 20}, {1, 0, 0, 0}}).obstacle_inside);
    EXPECT_TRUE(oracle.query(Pose{{113.5, 5, 5}, {1, 0, 0, 0}}).obstacle_inside);
    // A quarter turn about y takes the small cube below the big one, into the big environment
    // cube, while the big one stays above it: the object's second component is inside.
    const double half = std::sqrt(0.5);
    const auto second = oracle.query(Pose{{2.5, 5, 12.5}, {half, 0, half, 0}});
    EXPECT_TRUE(second.object_inside) << describe(second);
  }
  {
    const Scene object = closed_and_open_object();
    const ReferenceCollider oracle(environment.soup, object.soup);
    // The closed cube around the small cube; the open box around it instead.
    const std::vector<Vec3> spots{{100, 5, 5}, {92.5, 5, 5}, {5, 5, 5}, {80, 5, 5}};
    compare(oracle, environment, object, spots, 0.3, tally);
    EXPECT_TRUE(oracle.query(Pose{{100, 5, 5}, {1, 0, 0, 0}}).obstacle_inside);
    EXPECT_FALSE(oracle.query(Pose{{92.5, 5, 5}, {1, 0, 0, 0}}).collides);
  }
  EXPECT_EQ(tally.disagreements, 0) << "of " << tally.poses << " poses";
  // Every kind of answer occurred, so the agreement is not vacuous.
  EXPECT_GT(tally.touch, 0);
  EXPECT_GT(tally.object_inside, 0);
  EXPECT_GT(tally.obstacle_inside, 0);
  EXPECT_GT(tally.apart, 0);
}

TEST(ReferenceColliderComponents, ConcurrentQueriesMatchSerialOnes) {
  const Scene environment = environment_scene();
  const ReferenceCollider oracle(environment.soup, two_cubes_object().soup);
  Random random(5);
  std::vector<Pose> poses;
  for (int i = 0; i < 400; ++i)
    poses.push_back(random_rotation(
        random, {random.uniform(-5, 105), random.uniform(-5, 60), random.uniform(-5, 60)}));
  std::vector<ReferenceCollider::Answer> serial;
  for (const auto& pose : poses) serial.push_back(oracle.query(pose));
  std::vector<ReferenceCollider::Answer> parallel(poses.size());
  std::vector<std::thread> threads;
  for (int k = 0; k < 2; ++k)
    threads.emplace_back([&, k] {
      for (std::size_t i = std::size_t(k); i < poses.size(); i += 2)
        parallel[i] = oracle.query(poses[i]);
    });
  for (auto& thread : threads) thread.join();
  for (std::size_t i = 0; i < poses.size(); ++i)
    ASSERT_EQ(describe(parallel[i]), describe(serial[i])) << "pose " << i;
}

}  // namespace
}  // namespace tetrapage
