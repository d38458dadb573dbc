// Every query just inside the accepted coordinate range (kMaxCoordinateMagnitude) and the
// refusals just outside it. Inside, the scene and the object sit on dyadic coordinates near
// the limit, so that translating them back near the origin and dividing by the scale is
// exact: there CGAL's exact kernel (distance, triangle pairs) and the tools' ReferenceCollider
// (touching, containment) give the answers the far copy must give, times the scale.
#include <gtest/gtest.h>

#include <unistd.h>

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/squared_distance_3.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <memory>
#include <set>
#include <string>
#include <utility>

#include "GeometryTestSupport.h"
#include "TestSolids.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/preprocess/Preprocess.h"
#include "tetrapage/runtime/geometry/TriangleDistance.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/runtime/query/ObjectModel.h"
#include "tetrapage/tools/Random.h"
#include "tetrapage/tools/ReferenceCollider.h"

namespace tetrapage {
namespace {

namespace fs = std::filesystem;
using namespace test_solids;
using Exact = CGAL::Exact_predicates_exact_constructions_kernel;

// The largest power of two within the limit: the far copies lie just below it.
int limit_exponent() {
  const int e = std::ilogb(kMaxCoordinateMagnitude);
  return std::ldexp(1.0, e) <= kMaxCoordinateMagnitude ? e : e - 1;
}

// Closed boxes (one nested in another, one small and apart), a topless box and a slanted
// sheet, on multiples of 1/64 in [0, 1].
TriangleSoup unit_scene() {
  TriangleSoup soup;
  add_box(soup, {0.125, 0.125, 0.125}, {0.5, 0.5, 0.5});
  add_box(soup, {0.25, 0.25, 0.25}, {0.3125, 0.3125, 0.3125});
  add_box(soup, {0.6875, 0.6875, 0.6875}, {0.75, 0.75, 0.75});
  add_box(soup, {0.625, 0.625, 0.125}, {0.8125, 0.8125, 0.3125}, true);
  add_quad(soup, {0.625, 0.125, 0.75}, {0.9375, 0.125, 0.625}, {0.9375, 0.4375, 0.8125},
           {0.625, 0.4375, 0.875});
  return soup;
}

// A closed cube of side 1/16 and an open sheet beside it, on multiples of 1/64.
TriangleSoup unit_object() {
  TriangleSoup soup;
  add_box(soup, {-0.03125, -0.03125, -0.03125}, {0.03125, 0.03125, 0.03125});
  add_quad(soup, {0.046875, -0.03125, -0.03125}, {0.046875, 0.03125, -0.03125},
           {0.0625, 0.03125, 0.03125}, {0.046875, -0.03125, 0.03125});
  return soup;
}

// A closed cube of side 1/4: placed around the small box, it holds it.
TriangleSoup unit_big_cube() {
  TriangleSoup soup;
  add_box(soup, {-0.125, -0.125, -0.125}, {0.125, 0.125, 0.125});
  return soup;
}

Exact::Triangle_3 exact_triangle(const TriangleSoup& soup, std::size_t t, const Pose& pose) {
  std::array<Exact::Point_3, 3> corners;
  for (int k = 0; k < 3; ++k) {
    const Vec3 v = apply_pose(pose, soup.vertices[soup.triangles[t][k]]);
    corners[k] = {v[0], v[1], v[2]};
  }
  return {corners[0], corners[1], corners[2]};
}

std::vector<Exact::Triangle_3> exact_triangles(const TriangleSoup& soup, const Pose& pose = {}) {
  std::vector<Exact::Triangle_3> out;
  for (std::size_t t = 0; t < soup.triangles.size(); ++t)
    out.push_back(exact_triangle(soup, t, pose));
  return out;
}

// The scene and its objects at offset + scale x (exact: dyadic), against their unit copies.
class NearTheLimit : public ::testing::Test {
 protected:
  void SetUp() override {
    const int e = limit_exponent();
    scale_ = std::ldexp(1.0, e - 20);
    // Below 2^e on every axis, on both signs: every coordinate is a multiple of scale / 64,
    // which the doubles near 2^e hold exactly.
    const double corner = std::ldexp(1.0, e) - 2 * scale_;
    offset_ = {corner, -corner, corner};
    folder_ = fs::path(TETRAPAGE_TEST_TMP) / ("coordinate-limits-" + std::to_string(::getpid()));
    fs::remove_all(folder_);
    fs::create_directories(folder_);
    const fs::path input = folder_ / "scene.ply";
    {
      MeshWriter writer(input);
      const TriangleSoup far = placed(unit_scene(), scale_, offset_);
      writer.add_part(far.vertices, far.triangles);
      writer.commit();
    }
    const TriangleSoup stored = read_mesh(input);
    // The file holds the far scene exactly; its unit copy is the reference's environment.
    unit_environment_ = placed(stored, 1.0, {0, 0, 0});
    for (Vec3& v : unit_environment_.vertices)
      for (int a = 0; a < 3; ++a) v[a] = (v[a] - offset_[a]) / scale_;
    PreprocessOptions options;
    options.region_triangles = 8;
    options.interiors = true;
    preprocess({input}, folder_ / "scene.tpi", options);
    index_ = std::make_shared<const CollisionIndex>(folder_ / "scene.tpi");
    exact_environment_ = exact_triangles(unit_environment_);
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(folder_, ignored);
  }

  // The far pose of a unit pose (exact: multiples of 1/64 and quaternions of permutations).
  Pose far_pose(const Pose& unit) const {
    Pose pose = unit;
    for (int a = 0; a < 3; ++a) pose.translation[a] = offset_[a] + scale_ * unit.translation[a];
    return pose;
  }
  // A far point back in unit coordinates (exact for points near the scene).
  Vec3 to_unit(const Vec3& p) const {
    Vec3 out;
    for (int a = 0; a < 3; ++a) out[a] = (p[a] - offset_[a]) / scale_;
    return out;
  }

  double scale_ = 1;
  Vec3 offset_{};
  fs::path folder_;
  TriangleSoup unit_environment_;
  std::vector<Exact::Triangle_3> exact_environment_;
  std::shared_ptr<const CollisionIndex> index_;
};

// Random unit poses on multiples of 1/64 in [lo, lo + steps / 64), with the rotations that
// permute axes.
std::vector<Pose> unit_poses(std::uint64_t seed, int count, double lo = -10.0 / 64,
                             int steps = 84) {
  const std::array<std::array<double, 4>, 3> rotations{
      {{1, 0, 0, 0}, {0.5, 0.5, 0.5, 0.5}, {0.5, -0.5, -0.5, -0.5}}};
  Random random(seed);
  std::vector<Pose> poses;
  for (int i = 0; i < count; ++i) {
    Pose pose;
    for (int a = 0; a < 3; ++a) pose.translation[a] = lo + double(random.below(steps)) / 64;
    pose.rotation = rotations[random.below(3)];
    poses.push_back(pose);
  }
  return poses;
}

TEST_F(NearTheLimit, ThePosesAndTheSceneAreExactCopies) {
  // The premise of every test here: the far copies translate back exactly.
  const TriangleSoup unit = unit_scene();
  ASSERT_EQ(unit.vertices.size(), unit_environment_.vertices.size());
  for (std::size_t v = 0; v < unit.vertices.size(); ++v)
    ASSERT_EQ(unit_environment_.vertices[v], unit.vertices[v]);
  const TriangleSoup object = unit_object();
  for (const Pose& pose : unit_poses(3, 40))
    for (const Vec3& x : object.vertices) {
      const Vec3 far = apply_pose(far_pose(pose), {scale_ * x[0], scale_ * x[1], scale_ * x[2]});
      ASSERT_EQ(to_unit(far), apply_pose(pose, x));
      for (int a = 0; a < 3; ++a) ASSERT_LE(std::fabs(far[a]), kMaxCoordinateMagnitude);
    }
}

TEST_F(NearTheLimit, CollisionsContactsAndContainmentAreTheUnitCopys) {
  const TriangleSoup object = placed(unit_object(), scale_, {0, 0, 0});
  const ReferenceCollider oracle(unit_environment_, unit_object());
  FlyingObject flying(index_, object);
  int touching = 0, inside = 0;
  // Over the whole scene, then in and around the big box (walls, nested box, its inside).
  std::vector<Pose> poses = unit_poses(5, 40);
  for (const Pose& pose : unit_poses(6, 40, 0.0625, 32)) poses.push_back(pose);
  for (const Pose& unit : poses) {
    const ReferenceCollider::Answer expected = oracle.query(unit);
    QueryOptions options;
    options.mode = QueryMode::all_contacts;
    const QueryResult got = flying.query(far_pose(unit), options);
    ASSERT_EQ(got.collides, expected.collides) << unit.translation[0] << " " << unit.translation[1];
    EXPECT_EQ(got.containment == Containment::object_inside_obstacle, expected.object_inside);
    // Every touching pair, by brute force over the unit copies.
    std::set<std::pair<std::uint64_t, std::uint32_t>> pairs, want;
    for (const Contact& contact : got.contacts)
      pairs.insert({contact.environment_triangle, contact.object_triangle});
    const auto placed_object = exact_triangles(unit_object(), unit);
    for (std::size_t e = 0; e < exact_environment_.size(); ++e)
      for (std::uint32_t o = 0; o < placed_object.size(); ++o)
        if (CGAL::do_intersect(exact_environment_[e], placed_object[o])) want.insert({e, o});
    EXPECT_EQ(pairs, want);
    touching += expected.surfaces_touch;
    inside += expected.object_inside;
  }
  EXPECT_GT(touching, 5);
  EXPECT_GT(inside, 2);
  // The big cube around the small box holds it.
  FlyingObject big(index_, placed(unit_big_cube(), scale_, {0, 0, 0}));
  Pose around;
  around.translation = {0.71875, 0.71875, 0.71875};
  ASSERT_TRUE(ReferenceCollider(unit_environment_, unit_big_cube()).query(around).obstacle_inside);
  const QueryResult held = big.query(far_pose(around));
  EXPECT_TRUE(held.collides);
  EXPECT_EQ(held.containment, Containment::obstacle_inside_object);
}

TEST_F(NearTheLimit, DistancesAreTheUnitCopysTimesTheScale) {
  const ReferenceCollider oracle(unit_environment_, unit_object());
  FlyingObject flying(index_, placed(unit_object(), scale_, {0, 0, 0}));
  int apart = 0;
  // Doubles near 2^e are 2^(e - 52) apart: the closest points, each coordinate rounded once
  // in the sum with their triangle's far position, lie within that of the triangles.
  const double point_slack = 2 * std::ldexp(1.0, limit_exponent() - 52) / scale_;
  std::vector<Pose> poses = unit_poses(7, 40);
  for (const Pose& pose : unit_poses(8, 20, 0.0625, 32)) poses.push_back(pose);
  for (const Pose& unit : poses) {
    const DistanceResult got = flying.distance(far_pose(unit));
    if (oracle.query(unit).collides) {
      EXPECT_EQ(got.separation, Separation::touching);
      continue;
    }
    ++apart;
    ASSERT_EQ(got.separation, Separation::apart) << got.distance;
    const auto placed_object = exact_triangles(unit_object(), unit);
    Exact::FT exact = -1;
    for (const auto& e : exact_environment_)
      for (const auto& o : placed_object) {
        const Exact::FT d = CGAL::squared_distance(e, o);
        if (exact < 0 || d < exact) exact = d;
      }
    const double expected = std::sqrt(CGAL::to_double(exact));
    const double lower = got.lower_bound / scale_, upper = got.upper_bound / scale_;
    EXPECT_LE(Exact::FT(lower) * Exact::FT(lower), exact);
    EXPECT_GE(Exact::FT(upper) * Exact::FT(upper), exact);
    EXPECT_NEAR(got.distance / scale_, expected, 1e-9);
    // The closest points lie on the triangles named, as far apart as the distance says.
    ASSERT_LT(got.closest.environment_triangle, exact_environment_.size());
    ASSERT_LT(got.closest.object_triangle, placed_object.size());
    const Vec3 on_environment = to_unit(got.on_environment), on_object = to_unit(got.on_object);
    const Exact::Point_3 e{on_environment[0], on_environment[1], on_environment[2]};
    const Exact::Point_3 o{on_object[0], on_object[1], on_object[2]};
    EXPECT_LE(std::sqrt(CGAL::to_double(
                  CGAL::squared_distance(exact_environment_[got.closest.environment_triangle], e))),
              point_slack);
    EXPECT_LE(std::sqrt(CGAL::to_double(
                  CGAL::squared_distance(placed_object[got.closest.object_triangle], o))),
              point_slack);
    EXPECT_NEAR(std::sqrt(CGAL::to_double(CGAL::squared_distance(e, o))), expected,
                2 * point_slack);
  }
  EXPECT_GT(apart, 20);
}

TEST_F(NearTheLimit, TimeOfImpactBracketsTheFirstContact) {
  FlyingObject flying(index_, placed(unit_object(), scale_, {0, 0, 0}));
  // Along x at y = z = 0.3125 from 0 to 0.25: the sheet's far edge, x = 1/16, leads and meets
  // the big box's face x = 1/8 after 1/16 of travel, at time 1/4.
  Pose from, to;
  from.translation = {0, 0.3125, 0.3125};
  to.translation = {0.25, 0.3125, 0.3125};
  ImpactOptions options;
  options.tolerance = 1e-6;
  const ImpactResult hit = flying.time_of_impact(far_pose(from), far_pose(to), options);
  ASSERT_EQ(hit.impact, Impact::hit);
  EXPECT_LE(hit.free_until, 0.25);
  EXPECT_GE(hit.contact_at, 0.25 - 1e-9);
  EXPECT_LE(hit.contact_at - hit.free_until, options.tolerance);
  // Above every obstacle: nothing is met.
  from.translation = {0, 1.125, 1.125};
  to.translation = {1, 1.125, 1.125};
  EXPECT_EQ(flying.time_of_impact(far_pose(from), far_pose(to), options).impact, Impact::none);
}

// The triangle distance multiplies up to four lengths: far from 1 (lengths of 2^300 or
// 2^-400) it must still find the face and edge cases. Lattice pairs scaled by a power of two
// (exact) against CGAL's exact distance of the unscaled pair.
TEST(CoordinateLimits, TriangleDistanceHoldsAtEveryScale) {
  using namespace geometry::testing;
  Generator generator(11);
  Disagreements wrong("triangle distance scaled by 2^k");
  int cases = 0;
  for (const int exponent : {-400, -200, 0, 200, 300, 440}) {
    const double scale = std::ldexp(1.0, exponent);
    for (int i = 0; i < 300; ++i, ++cases) {
      const geometry::Triangle a = lattice_triangle(generator, 1000);
      geometry::Triangle b = lattice_triangle(generator, 1000);
      const double shift = double(generator.integer(-3000, 3000));
      for (auto& p : b) p[0] += shift;
      const Exact::FT exact = CGAL::squared_distance(to_epeck(a), to_epeck(b));
      geometry::Triangle far_a = a, far_b = b;
      for (auto* t : {&far_a, &far_b})
        for (auto& p : *t)
          for (double& x : p) x *= scale;
      const geometry::TriangleDistance got = geometry::triangle_distance(far_a, far_b);
      const double lower = got.lower_bound / scale, upper = got.upper_bound / scale;
      const double expected = std::sqrt(CGAL::to_double(exact));
      if (!(Exact::FT(lower) * Exact::FT(lower) <= exact &&
            Exact::FT(upper) * Exact::FT(upper) >= exact &&
            std::fabs(got.distance / scale - expected) <= 1e-9 * 4000))
        wrong.add(std::uint64_t(i), "scale 2^" + std::to_string(exponent) + ", " + hex(a) + " " +
                                        hex(b) + ": " + std::to_string(got.distance / scale) +
                                        " for " + std::to_string(expected));
    }
  }
  wrong.expect_none(std::uint64_t(cases));
}

// A small scene at the origin and the object at the limit itself: the distance is the
// placement's, measured exactly by CGAL on the placed coordinates.
TEST(CoordinateLimits, AnObjectAtTheLimitIsMeasuredFromASceneAtTheOrigin) {
  const fs::path folder =
      fs::path(TETRAPAGE_TEST_TMP) / ("coordinate-limits-origin-" + std::to_string(::getpid()));
  fs::remove_all(folder);
  fs::create_directories(folder);
  const TriangleSoup scene = unit_scene();
  {
    MeshWriter writer(folder / "scene.ply");
    writer.add_part(scene.vertices, scene.triangles);
    writer.commit();
  }
  preprocess({folder / "scene.ply"}, folder / "scene.tpi", PreprocessOptions{});
  const auto index = std::make_shared<const CollisionIndex>(folder / "scene.tpi");
  FlyingObject flying(index, unit_object());
  const double m = kMaxCoordinateMagnitude;
  for (const Vec3& translation : {Vec3{m, 0, 0}, Vec3{-m, m, -m}, Vec3{0.5, -m, 0.25}}) {
    Pose pose;
    pose.translation = translation;
    const DistanceResult got = flying.distance(pose);
    ASSERT_EQ(got.separation, Separation::apart) << got.distance;
    Exact::FT exact = -1;
    for (const auto& e : exact_triangles(scene))
      for (const auto& o : exact_triangles(unit_object(), pose)) {
        const Exact::FT d = CGAL::squared_distance(e, o);
        if (exact < 0 || d < exact) exact = d;
      }
    const double expected = std::sqrt(CGAL::to_double(exact));
    EXPECT_NEAR(got.distance, expected, 1e-12 * expected);
    EXPECT_LE(Exact::FT(got.lower_bound) * Exact::FT(got.lower_bound), exact);
    EXPECT_GE(Exact::FT(got.upper_bound) * Exact::FT(got.upper_bound), exact);
    EXPECT_NE(got.on_environment, got.on_object);
    EXPECT_FALSE(flying.query(pose).collides);
    Pose back;
    back.translation = {0.5, 0.5, 0.5};
    EXPECT_EQ(flying.time_of_impact(pose, back, {}).impact, Impact::hit);
  }
  std::error_code ignored;
  fs::remove_all(folder, ignored);
}

std::string message_of(const std::function<void()>& run) {
  try {
    run();
  } catch (const InputError& error) {
    return error.what();
  }
  return "accepted";
}

TEST(CoordinateLimits, BeyondTheLimitEveryInputIsRefusedNamingTheValueAndTheLimit) {
  const double beyond = std::nextafter(2 * kMaxCoordinateMagnitude, 0.0);
  char value[64], limit[64];
  std::snprintf(value, sizeof value, "%g", beyond);
  std::snprintf(limit, sizeof limit, "%g", kMaxCoordinateMagnitude);
  // An object's coordinate.
  TriangleSoup object = unit_object();
  object.vertices[3][1] = -beyond;
  const std::string object_message = message_of([&] { ObjectModel built(object); });
  EXPECT_NE(object_message.find(std::string("-") + value), std::string::npos) << object_message;
  EXPECT_NE(object_message.find(limit), std::string::npos) << object_message;
  // A model's coordinate, at preprocess.
  const fs::path folder =
      fs::path(TETRAPAGE_TEST_TMP) / ("coordinate-limits-beyond-" + std::to_string(::getpid()));
  fs::remove_all(folder);
  fs::create_directories(folder);
  TriangleSoup scene = unit_scene();
  scene.vertices[5][2] = beyond;
  {
    MeshWriter writer(folder / "scene.ply");
    writer.add_part(scene.vertices, scene.triangles);
    writer.commit();
  }
  const std::string model_message = message_of(
      [&] { preprocess({folder / "scene.ply"}, folder / "scene.tpi", PreprocessOptions{}); });
  EXPECT_NE(model_message.find(value), std::string::npos) << model_message;
  EXPECT_NE(model_message.find(limit), std::string::npos) << model_message;
  // A pose's translation, for every query.
  scene = unit_scene();
  {
    MeshWriter writer(folder / "scene.ply");
    writer.add_part(scene.vertices, scene.triangles);
    writer.commit();
  }
  preprocess({folder / "scene.ply"}, folder / "scene.tpi", PreprocessOptions{});
  FlyingObject flying(std::make_shared<const CollisionIndex>(folder / "scene.tpi"), unit_object());
  Pose far;
  far.translation = {0, beyond, 0};
  const Pose near;
  const std::vector<std::pair<const char*, std::function<void()>>> queries{
      {"collide", [&] { flying.query(far); }},
      {"contacts", [&] { flying.query(far, QueryOptions{.mode = QueryMode::all_contacts}); }},
      {"distance", [&] { flying.distance(far); }},
      {"time of impact from", [&] { flying.time_of_impact(far, near, {}); }},
      {"time of impact to", [&] { flying.time_of_impact(near, far, {}); }}};
  for (const auto& [name, run] : queries) {
    const std::string message = message_of(run);
    EXPECT_NE(message.find(value), std::string::npos) << name << ": " << message;
    EXPECT_NE(message.find(limit), std::string::npos) << name << ": " << message;
  }
  std::error_code ignored;
  fs::remove_all(folder, ignored);
}

}  // namespace
}  // namespace tetrapage
