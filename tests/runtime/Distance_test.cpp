// The distance and time-of-impact queries against independent references: the exact distance
// over every triangle pair by CGAL's exact-construction kernel (its own triangle/triangle
// distance), touching and containment by the tools' ReferenceCollider, and times of impact
// known in closed form. Scenes mix closed and open solids; near the origin, far from it, and
// at scales 1e-9 and 1e9; one foreign mesh from the library.
#include <gtest/gtest.h>

#include <unistd.h>

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/squared_distance_3.h>

#include <cmath>
#include <filesystem>
#include <memory>

#include "TestSolids.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/preprocess/Preprocess.h"
#include "tetrapage/runtime/geometry/Accuracy.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/runtime/query/PoseMotion.h"
#include "tetrapage/tools/MeshLibrary.h"
#include "tetrapage/tools/Random.h"
#include "tetrapage/tools/ReferenceCollider.h"

namespace tetrapage {
namespace {

namespace fs = std::filesystem;
using namespace test_solids;
using Exact = CGAL::Exact_predicates_exact_constructions_kernel;

// Closed boxes (one nested in another), a topless box and a slanted open sheet, in one part.
TriangleSoup mixed_scene() {
  TriangleSoup soup;
  add_box(soup, {0.125, 0.125, 0.125}, {0.5, 0.5, 0.5});
  add_box(soup, {0.25, 0.25, 0.25}, {0.3125, 0.3125, 0.3125});
  add_box(soup, {0.625, 0.625, 0.125}, {0.8125, 0.8125, 0.3125}, true);
  add_quad(soup, {0.625, 0.125, 0.75}, {0.9375, 0.125, 0.625}, {0.9375, 0.4375, 0.8125}, {0.625, 0.4375, 0.875});
  soup.part_of.assign(soup.triangles.size(), 0);
  soup.part_names = {"mixed"};
  return soup;
}

// A closed cube and an open sheet beside it: distances are taken from both.
TriangleSoup cube_and_sheet() {
  TriangleSoup soup;
  add_box(soup, {-0.02, -0.02, -0.02}, {0.02, 0.02, 0.02});
  add_quad(soup, {0.03, -0.02, -0.02}, {0.03, 0.02, -0.02}, {0.04, 0.02, 0.02}, {0.03, -0.02, 0.02});
  soup.part_of.assign(soup.triangles.size(), 0);
  soup.part_names = {"cube and sheet"};
  return soup;
}

Exact::Point_3 exact_point(const Vec3& p) { return {p[0], p[1], p[2]}; }

Exact::Triangle_3 exact_triangle(const TriangleSoup& soup, std::size_t t, const Pose* pose = nullptr) {
  std::array<Exact::Point_3, 3> corners;
  for (int k = 0; k < 3; ++k) {
    const Vec3& v = soup.vertices[soup.triangles[t][k]];
    corners[k] = exact_point(pose ? apply_pose(*pose, v) : v);
  }
  return {corners[0], corners[1], corners[2]};
}

// The exact squared distance between the environment and the placed object, by CGAL over
// every pair (triangles of zero area are segments or points to CGAL too).
Exact::FT exact_squared_distance(const std::vector<Exact::Triangle_3>& environment,
                                 const std::vector<Exact::Triangle_3>& object) {
  Exact::FT best = -1;
  for (const auto& e : environment)
    for (const auto& o : object) {
      const Exact::FT d = CGAL::squared_distance(e, o);
      if (best < 0 || d < best) best = d;
    }
  return best;
}

struct Variant {
  const char* name;
  double scale;
  Vec3 offset;
  const char* extension = "ply";  ///< stl: float input, one part
};
std::ostream& operator<<(std::ostream& out, const Variant& v) { return out << v.name; }

class Distance : public ::testing::TestWithParam<Variant> {
 protected:
  void SetUp() override {
    const Variant& v = GetParam();
    folder_ = fs::path(TETRAPAGE_TEST_TMP) / (std::string("distance-") + v.name + "-" + std::to_string(::getpid()));
    fs::remove_all(folder_);
    fs::create_directories(folder_);
    const fs::path input = folder_ / (std::string("scene.") + v.extension);
    {
      MeshWriter writer(input);
      const TriangleSoup soup = placed(mixed_scene(), v.scale, v.offset);
      writer.add_part(soup.vertices, soup.triangles);
      writer.commit();
    }
    environment_ = read_mesh(input);
    PreprocessOptions options;  // the defaults, with small regions and the interiors
    options.region_triangles = 8;
    options.interiors = true;
    preprocess({input}, folder_ / "scene.tpi", options);
    index_ = std::make_shared<const CollisionIndex>(folder_ / "scene.tpi");
    object_ = placed(cube_and_sheet(), v.scale, {0, 0, 0});
    for (std::size_t t = 0; t < environment_.triangles.size(); ++t)
      exact_environment_.push_back(exact_triangle(environment_, t));
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(folder_, ignored);
  }

  Pose pose_at(const Vec3& unit_position, const std::array<double, 4>& rotation) const {
    const Variant& v = GetParam();
    Pose pose;
    for (int a = 0; a < 3; ++a) pose.translation[a] = v.offset[a] + v.scale * unit_position[a];
    pose.rotation = unit_quaternion(rotation);
    return pose;
  }

  std::vector<Exact::Triangle_3> exact_object(const Pose& pose) const {
    std::vector<Exact::Triangle_3> out;
    for (std::size_t t = 0; t < object_.triangles.size(); ++t) out.push_back(exact_triangle(object_, t, &pose));
    return out;
  }

  // One distance answer against the references; counts what it saw.
  void check(FlyingObject& flying, const ReferenceCollider& oracle, const Pose& pose, int& touching, int& apart) {
    const DistanceResult got = flying.distance(pose);
    if (oracle.query(pose).collides) {
      ++touching;
      EXPECT_EQ(got.separation, Separation::touching);
      EXPECT_EQ(got.distance, 0.0);
      return;
    }
    ++apart;
    ASSERT_EQ(got.separation, Separation::apart);
    const auto object = exact_object(pose);
    const Exact::FT exact = exact_squared_distance(exact_environment_, object);
    // The true distance lies in the stated bracket, and the computed one too.
    EXPECT_LE(Exact::FT(got.lower_bound) * Exact::FT(got.lower_bound), exact);
    EXPECT_GE(Exact::FT(got.upper_bound) * Exact::FT(got.upper_bound), exact);
    EXPECT_LE(got.lower_bound, got.distance);
    EXPECT_LE(got.distance, got.upper_bound);
    // The bracket is tight: the double computation's error, not a search's slack.
    const double true_distance = std::sqrt(CGAL::to_double(exact));
    const double magnitude = GetParam().scale + std::fabs(GetParam().offset[0]) + std::fabs(GetParam().offset[1]);
    EXPECT_LE(got.upper_bound - got.lower_bound, 1e-12 * magnitude) << "distance " << true_distance;
    // The closest points lie on the triangles named, as far apart as the distance says.
    ASSERT_LT(got.closest.environment_triangle, environment_.triangles.size());
    ASSERT_LT(got.closest.object_triangle, object_.triangles.size());
    const double slack = 1e-12 * magnitude;
    EXPECT_LE(std::sqrt(CGAL::to_double(
                  CGAL::squared_distance(exact_environment_[got.closest.environment_triangle],
                                         exact_point(got.on_environment)))),
              slack);
    EXPECT_LE(std::sqrt(CGAL::to_double(CGAL::squared_distance(object[got.closest.object_triangle],
                                                               exact_point(got.on_object)))),
              slack);
    const double between = std::sqrt(CGAL::to_double(
        CGAL::squared_distance(exact_point(got.on_environment), exact_point(got.on_object))));
    EXPECT_NEAR(between, true_distance, slack);
    // max_distance on either side of it: "farther" exactly when it is below the distance.
    DistanceResult limited = flying.distance(pose, DistanceOptions{0.5 * true_distance});
    EXPECT_EQ(limited.separation, Separation::farther);
    EXPECT_GE(limited.lower_bound, 0.5 * true_distance);
    limited = flying.distance(pose, DistanceOptions{2 * true_distance});
    ASSERT_EQ(limited.separation, Separation::apart);
    EXPECT_NEAR(limited.distance, true_distance, slack);
  }

  fs::path folder_;
  TriangleSoup environment_, object_;
  std::vector<Exact::Triangle_3> exact_environment_;
  std::shared_ptr<const CollisionIndex> index_;
};

TEST_P(Distance, RandomPosesMatchTheExactDistance) {
  const ReferenceCollider oracle(environment_, object_);
  FlyingObject flying(index_, object_);
  Random random(27);
  int touching = 0, apart = 0;
  for (int i = 0; i < 60; ++i) {
    const Vec3 position{random.uniform(-0.2, 1.2), random.uniform(-0.2, 1.2), random.uniform(-0.2, 1.2)};
    check(flying, oracle, pose_at(position, {random.normal(), random.normal(), random.normal(), random.normal()}),
          touching, apart);
  }
  EXPECT_GT(touching, 3);
  EXPECT_GT(apart, 30);
}

TEST_P(Distance, CoherentFlightStartsFromTheLastPairAndStaysExact) {
  // A slow straight flight past the nested boxes, the topless box and the sheet: most steps
  // start from the last closest pair.
  const ReferenceCollider oracle(environment_, object_);
  FlyingObject flying(index_, object_);
  int touching = 0, apart = 0, from_last = 0;
  const std::array<double, 4> turn = {0.9, 0.1, 0.3, -0.2};
  for (int i = 0; i <= 40; ++i) {
    const double s = i / 40.0;
    const Pose pose = pose_at({0.05 + 0.85 * s, 0.56 - 0.1 * s, 0.6 - 0.2 * s}, turn);
    check(flying, oracle, pose, touching, apart);
    from_last += flying.distance(pose).from_last_pair;
  }
  EXPECT_GT(apart, 20);
  EXPECT_GT(from_last, 20);
}

TEST_P(Distance, InsideAClosedSolidIsTouchingWithContainment) {
  FlyingObject flying(index_, object_);
  // Between the big box's walls and the nested box: inside the closed big box.
  const DistanceResult got = flying.distance(pose_at({0.42, 0.42, 0.42}, {1, 0, 0, 0}));
  EXPECT_EQ(got.separation, Separation::touching);
  EXPECT_EQ(got.containment, Containment::object_inside_obstacle);
  EXPECT_EQ(got.distance, 0.0);
}

TEST_P(Distance, TouchingReportsAPointBothTrianglesShare) {
  FlyingObject flying(index_, object_);
  const ReferenceCollider oracle(environment_, object_);
  // The cube's face pressed on the big box's top, across its edge.
  const Pose pose = pose_at({0.5, 0.3, 0.52}, {1, 0, 0, 0});
  ASSERT_TRUE(oracle.query(pose).surfaces_touch);
  const DistanceResult got = flying.distance(pose);
  ASSERT_EQ(got.separation, Separation::touching);
  ASSERT_LT(got.closest.environment_triangle, environment_.triangles.size());
  const double slack = 1e-12 * (GetParam().scale + std::fabs(GetParam().offset[0]));
  EXPECT_LE(
      std::sqrt(CGAL::to_double(CGAL::squared_distance(
          exact_environment_[got.closest.environment_triangle], exact_point(got.on_environment)))),
      slack);
  EXPECT_LE(std::sqrt(CGAL::to_double(CGAL::squared_distance(
                exact_object(pose)[got.closest.object_triangle], exact_point(got.on_object)))),
            slack);
}

TEST_P(Distance, ObjectFarOutsideTheModelIsMeasured) {
  const ReferenceCollider oracle(environment_, object_);
  FlyingObject flying(index_, object_);
  int touching = 0, apart = 0;
  check(flying, oracle, pose_at({3.0, -2.0, 0.4}, {1, 0, 0, 0}), touching, apart);
  check(flying, oracle, pose_at({-40.0, 0.3, 0.3}, {0.5, 0.5, 0.5, 0.5}), touching, apart);
  EXPECT_EQ(apart, 2);
}

TEST_P(Distance, BadMaxDistanceIsRefused) {
  FlyingObject flying(index_, object_);
  EXPECT_THROW(flying.distance(pose_at({0, 0, 0}, {1, 0, 0, 0}), DistanceOptions{-1.0}), InputError);
  EXPECT_THROW(flying.distance(pose_at({0, 0, 0}, {1, 0, 0, 0}), DistanceOptions{std::nan("")}), InputError);
}

// Time of impact: a translation straight at the big box's face, whose first contact time is
// known in closed form, and motions checked against the reference along the way.
TEST_P(Distance, TimeOfImpactBracketsTheFirstContact) {
  FlyingObject flying(index_, object_);
  const ReferenceCollider oracle(environment_, object_);
  // The cube and its sheet move along x from 0.0 to 0.3 at y = z = 0.3: the sheet's far edge,
  // x = +0.04, leads and reaches the box's face x = 0.125 at travel 0.085, time 0.85 / 3.
  const Pose from = pose_at({0.0, 0.3, 0.3}, {1, 0, 0, 0});
  const Pose to = pose_at({0.3, 0.3, 0.3}, {1, 0, 0, 0});
  ImpactOptions options;
  options.tolerance = 1e-6;
  const ImpactResult hit = flying.time_of_impact(from, to, options);
  ASSERT_EQ(hit.impact, Impact::hit);
  EXPECT_LE(hit.free_until, 0.85 / 3);
  EXPECT_GE(hit.contact_at, 0.85 / 3 - 1e-12);
  EXPECT_LE(hit.contact_at - hit.free_until, options.tolerance);
  EXPECT_TRUE(hit.contact.has_triangle());
  const PoseMotion motion(from, to);
  EXPECT_TRUE(oracle.query(motion.at(hit.contact_at)).collides);
  EXPECT_FALSE(oracle.query(motion.at(hit.free_until)).collides);

  // A motion that turns and passes between obstacles: no contact at any of 400 samples when
  // the answer is "none"; when "hit", none before free_until and one at contact_at.
  Random random(5);
  int hits = 0, misses = 0;
  for (int m = 0; m < 12; ++m) {
    const Pose a = pose_at({random.uniform(-0.1, 1.1), random.uniform(-0.1, 1.1), random.uniform(0.55, 1.1)},
                           {random.normal(), random.normal(), random.normal(), random.normal()});
    const Pose b = pose_at({random.uniform(-0.1, 1.1), random.uniform(-0.1, 1.1), random.uniform(-0.1, 1.1)},
                           {random.normal(), random.normal(), random.normal(), random.normal()});
    if (oracle.query(a).collides) continue;
    const ImpactResult got = flying.time_of_impact(a, b, {});
    ASSERT_NE(got.impact, Impact::unresolved);
    const PoseMotion path(a, b);
    const double end = got.impact == Impact::hit ? got.free_until : 1.0;
    for (int s = 0; s < 400; ++s)
      ASSERT_FALSE(oracle.query(path.at(end * s / 400.0)).collides) << "motion " << m << " sample " << s;
    if (got.impact == Impact::hit) {
      ++hits;
      EXPECT_TRUE(oracle.query(path.at(got.contact_at)).collides);
      EXPECT_LE(got.contact_at - got.free_until, 1e-4);
    } else {
      ++misses;
      EXPECT_FALSE(oracle.query(b).collides);
    }
  }
  EXPECT_GT(hits, 2);
  EXPECT_GT(misses, 0);
}

INSTANTIATE_TEST_SUITE_P(Scales, Distance,
                         ::testing::Values(Variant{"unit", 1.0, {0, 0, 0}}, Variant{"tiny", 1e-9, {0, 0, 0}},
                                           Variant{"huge", 1e9, {0, 0, 0}},
                                           Variant{"far", 1.0, {1e6, -3e6, 2e6}},
                                           Variant{"float_stl", 1.0, {0.5, 0.5, 0.5}, "stl"}),
                         [](const auto& variant) { return std::string(variant.param.name); });

// A foreign mesh (CGAL's couplingdown, 3714 triangles) with the cube flown past it: the exact
// distance over the pairs whose double distance comes near the least (CGAL's double kernel
// picks them; its error is far below the 1 % margin), against the stated bracket.
TEST(DistanceOnLibraryMesh, CoherentFlightMatchesTheExactDistance) {
  using Double = CGAL::Exact_predicates_inexact_constructions_kernel;
  const fs::path folder = fs::path(TETRAPAGE_TEST_TMP) / ("distance-coupling-" + std::to_string(::getpid()));
  fs::remove_all(folder);
  fs::create_directories(folder);
  const fs::path input = MeshLibrary::default_folder() / "couplingdown.off";
  ASSERT_TRUE(fs::exists(input)) << input << " (CGAL's data meshes, libcgal-demo)";
  const TriangleSoup environment = read_mesh(input);
  preprocess({input}, folder / "coupling.tpi", PreprocessOptions{});
  const auto index = std::make_shared<const CollisionIndex>(folder / "coupling.tpi");
  const BoundingBox bounds = environment.bounds();
  const double size = geometry::extent(bounds);
  const TriangleSoup object = placed(cube_and_sheet(), size, {0, 0, 0});
  FlyingObject flying(index, object);
  std::vector<Exact::Triangle_3> exact_environment;
  std::vector<Double::Triangle_3> double_environment;
  for (std::size_t t = 0; t < environment.triangles.size(); ++t) {
    exact_environment.push_back(exact_triangle(environment, t));
    const auto& c = environment.triangles[t];
    const auto p = [&](int k) {
      const Vec3& v = environment.vertices[c[k]];
      return Double::Point_3(v[0], v[1], v[2]);
    };
    double_environment.emplace_back(p(0), p(1), p(2));
  }
  int apart = 0;
  for (int i = 0; i <= 8; ++i) {
    Pose pose;
    for (int a = 0; a < 3; ++a)
      pose.translation[a] = bounds.lo[a] + (bounds.hi[a] - bounds.lo[a]) * (a == 0 ? i / 8.0 : 0.5) +
                            (a == 2 ? 0.3 * size : 0.0);
    pose.rotation = unit_quaternion({1.0, 0.1 * i, 0.2, 0.0});
    const DistanceResult got = flying.distance(pose);
    if (got.separation != Separation::apart) continue;
    ++apart;
    std::vector<Double::FT> doubles;
    double least = std::numeric_limits<double>::infinity();
    std::vector<std::pair<std::size_t, std::size_t>> pairs;
    std::vector<Double::Triangle_3> placed_object;
    for (std::size_t o = 0; o < object.triangles.size(); ++o) {
      const auto& c = object.triangles[o];
      const auto p = [&](int k) {
        const Vec3 v = apply_pose(pose, object.vertices[c[k]]);
        return Double::Point_3(v[0], v[1], v[2]);
      };
      placed_object.emplace_back(p(0), p(1), p(2));
    }
    std::vector<double> d(environment.triangles.size() * object.triangles.size());
    for (std::size_t e = 0; e < environment.triangles.size(); ++e)
      for (std::size_t o = 0; o < object.triangles.size(); ++o) {
        d[e * object.triangles.size() + o] = CGAL::squared_distance(double_environment[e], placed_object[o]);
        least = std::min(least, d[e * object.triangles.size() + o]);
      }
    Exact::FT exact = -1;
    for (std::size_t e = 0; e < environment.triangles.size(); ++e)
      for (std::size_t o = 0; o < object.triangles.size(); ++o)
        if (d[e * object.triangles.size() + o] <= 1.01 * least) {
          const Exact::FT x = CGAL::squared_distance(exact_environment[e], exact_triangle(object, o, &pose));
          if (exact < 0 || x < exact) exact = x;
        }
    EXPECT_LE(Exact::FT(got.lower_bound) * Exact::FT(got.lower_bound), exact) << "pose " << i;
    EXPECT_GE(Exact::FT(got.upper_bound) * Exact::FT(got.upper_bound), exact) << "pose " << i;
    EXPECT_LE(got.upper_bound - got.lower_bound, 1e-12 * size);
  }
  EXPECT_GT(apart, 4);
  std::error_code ignored;
  fs::remove_all(folder, ignored);
}

}  // namespace
}  // namespace tetrapage
