// Exact by default on files that mix solids, as CAD exports do: one PLY, STL or OBJ file (one
// part) holding closed solids, a solid nested inside another, a self-intersecting closed solid
// and open shells; objects that are multi-solid too. Each file is preprocessed with the default
// options and flown with the default query; every answer must be the reference oracle's, which
// decides components, closedness and insides by its own means (ReferenceCollider: CGAL's
// polygon-soup orientation, is_closed and Side_of_triangle_mesh). Poses: wholly inside and
// outside solids, in the box of an open shell, straddling, random, and grazing poses bisected
// to 1e-6, 1e-9 and 1e-12 of the model's size from contact, on float and double input, near the
// origin, far from it, and at scales 1e-9 and 1e9.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <memory>

#include "TestSolids.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/preprocess/Preprocess.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/tools/Random.h"
#include "tetrapage/tools/ReferenceCollider.h"

namespace tetrapage {
namespace {

namespace fs = std::filesystem;
using namespace test_solids;

void finish(TriangleSoup& soup, const char* name) {
  soup.part_of.assign(soup.triangles.size(), 0);
  soup.part_names = {name};
}

// One part, coordinates on a grid of 2^-10 (floats exactly): a big closed box holding a smaller
// one (not connected: a nested solid), a closed box pierced by a tetrahedron that shares its
// corner (one self-intersecting closed component), a box without its top (open), an open sheet,
// and a small closed tetrahedron on its own.
TriangleSoup mixed_solids() {
  TriangleSoup soup;
  add_box(soup, {0.125, 0.125, 0.125}, {0.5, 0.5, 0.5});
  add_box(soup, {0.25, 0.25, 0.25}, {0.3125, 0.3125, 0.3125});
  add_box(soup, {0.625, 0.125, 0.125}, {0.8125, 0.3125, 0.3125});
  add_tetra(soup, {{{0.8125, 0.3125, 0.3125}, {0.6875, 0.1875, 0.375}, {0.9375, 0.25, 0.1875}, {0.75, 0.4375, 0.25}}});
  add_box(soup, {0.625, 0.625, 0.125}, {0.8125, 0.8125, 0.3125}, true);
  add_quad(soup, {0.125, 0.125, 0.75}, {0.4375, 0.125, 0.75}, {0.4375, 0.4375, 0.75}, {0.125, 0.4375, 0.75});
  add_tetra(soup, {{{0.84375, 0.84375, 0.84375}, {0.8671875, 0.84375, 0.84375}, {0.84375, 0.8671875, 0.84375},
                    {0.84375, 0.84375, 0.8671875}}});
  finish(soup, "mixed");
  return soup;
}

// Objects around their origin: a closed cube; two disjoint closed cubes and an open sheet in one
// soup; a large closed cube (that can swallow the small tetrahedron) with an open sheet.
TriangleSoup cube_object() {
  TriangleSoup soup;
  add_box(soup, {-0.02, -0.02, -0.02}, {0.02, 0.02, 0.02});
  finish(soup, "cube");
  return soup;
}

TriangleSoup multi_solid_object() {
  TriangleSoup soup;
  add_box(soup, {-0.045, -0.015, -0.015}, {-0.015, 0.015, 0.015});
  add_box(soup, {0.015, -0.015, -0.015}, {0.045, 0.015, 0.015});
  add_quad(soup, {-0.03, -0.03, 0.03}, {0.03, -0.03, 0.03}, {0.03, 0.03, 0.03}, {-0.03, 0.03, 0.03});
  finish(soup, "pair");
  return soup;
}

TriangleSoup swallowing_object() {
  TriangleSoup soup;
  add_box(soup, {-0.05, -0.05, -0.05}, {0.05, 0.05, 0.05});
  add_quad(soup, {-0.07, -0.07, 0.07}, {0.07, -0.07, 0.07}, {0.07, 0.07, 0.07}, {-0.07, 0.07, 0.07});
  finish(soup, "box and sheet");
  return soup;
}

struct Variant {
  const char* name;
  const char* extension;
  double scale;
  Vec3 offset;
};

std::ostream& operator<<(std::ostream& out, const Variant& v) { return out << v.name; }

class MultiSolid : public ::testing::TestWithParam<Variant> {
 protected:
  void SetUp() override {
    const Variant& v = GetParam();
    folder_ = fs::path(TETRAPAGE_TEST_TMP) / (std::string("multi-solid-") + v.name + "-" + std::to_string(::getpid()));
    fs::remove_all(folder_);
    fs::create_directories(folder_);
    const fs::path input = folder_ / (std::string("mixed.") + v.extension);
    {
      MeshWriter writer(input);
      const TriangleSoup soup = placed(mixed_solids(), v.scale, v.offset);
      writer.add_part(soup.vertices, soup.triangles);
      writer.commit();
    }
    environment_ = read_mesh(input);  // as the file holds it (an STL rounds to floats)
    PreprocessOptions options;        // the defaults, but for a small region size
    options.region_triangles = 8;
    options.interiors = true;
    summary_ = preprocess({input}, folder_ / "mixed.tpi", options);
    index_ = std::make_shared<const CollisionIndex>(folder_ / "mixed.tpi");
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(folder_, ignored);
  }

  // An object at the model's scale.
  TriangleSoup scaled(const TriangleSoup& object) const { return placed(object, GetParam().scale, {0, 0, 0}); }

  Pose pose_at(const Vec3& unit_position, const std::array<double, 4>& rotation) const {
    const Variant& v = GetParam();
    Pose pose;
    for (int a = 0; a < 3; ++a) pose.translation[a] = v.offset[a] + v.scale * unit_position[a];
    pose.rotation = unit_quaternion(rotation);
    return pose;
  }

  fs::path folder_;
  TriangleSoup environment_;
  PreprocessSummary summary_;
  std::shared_ptr<const CollisionIndex> index_;
};

struct Tally {
  int poses = 0, wrong = 0, touching = 0, object_inside = 0, obstacle_inside = 0, free = 0;
};

// Flies `poses` in order (the runtime reuses work between steps) against the oracle.
Tally fly(FlyingObject& flying, const ReferenceCollider& oracle, const std::vector<Pose>& poses) {
  Tally tally;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const auto expected = oracle.query(poses[i]);
    const QueryResult got = flying.query(poses[i]);
    ++tally.poses;
    tally.touching += expected.surfaces_touch;
    tally.object_inside += expected.object_inside;
    tally.obstacle_inside += expected.obstacle_inside;
    tally.free += !expected.collides;
    if (got.collides != expected.collides && ++tally.wrong <= 5)
      ADD_FAILURE() << "pose " << i << " at (" << poses[i].translation[0] << ", " << poses[i].translation[1]
                    << ", " << poses[i].translation[2] << "): runtime " << got.collides << ", oracle "
                    << expected.collides << " (touch " << expected.surfaces_touch << ", object inside "
                    << expected.object_inside << ", obstacle inside " << expected.obstacle_inside << ")";
  }
  return tally;
}

std::array<double, 4> random_rotation(Random& random) {
  return {random.normal(), random.normal(), random.normal(), random.normal()};
}

TEST_P(MultiSolid, ComponentsAreFoundAndClassified) {
  // Six components in one part: four closed (the big box, the box nested in it, the pierced
  // box with its tetrahedron, the small tetrahedron), two open (the topless box, the sheet).
  EXPECT_EQ(summary_.parts, 1u);
  EXPECT_EQ(summary_.components, 6u);
  EXPECT_EQ(summary_.closed_components, 4u);
  EXPECT_EQ(summary_.interior_undecided, 0u);
  const ReferenceCollider oracle(environment_, scaled(cube_object()));
  EXPECT_EQ(oracle.environment_components(), summary_.components);
  EXPECT_EQ(oracle.environment_closed_components(), summary_.closed_components);
  EXPECT_EQ(summary_.max_rounding_distance, 0.0) << "the default stores the coordinates read";
}

TEST_P(MultiSolid, PosesInsideOutsideAndStraddlingAgreeWithTheOracle) {
  Random random(7);
  // Wholly inside the big box's shell, inside the nested box, inside the pierced box, in the
  // topless box (open: nothing inside), under the sheet, far from everything, straddling walls;
  // the large object below the big box with only its sheet inside it (its second component).
  const std::vector<Vec3> centres{{0.18, 0.18, 0.4},  {0.28, 0.28, 0.28}, {0.66, 0.16, 0.16}, {0.72, 0.72, 0.2},
                                  {0.28, 0.28, 0.65}, {0.56, 0.56, 0.56}, {0.5, 0.3, 0.3},    {0.72, 0.72, 0.3125},
                                  {0.3125, 0.28, 0.28}, {0.855, 0.855, 0.855}, {0.78, 0.3, 0.3},
                                  {0.3, 0.4, 0.07}};
  int object_inside = 0, obstacle_inside = 0, free = 0;
  for (const TriangleSoup& object : {scaled(cube_object()), scaled(multi_solid_object()), scaled(swallowing_object())}) {
    const ReferenceCollider oracle(environment_, object);
    FlyingObject flying(index_, object);
    std::vector<Pose> poses;
    for (const Vec3& c : centres)
      for (int r = 0; r < 4; ++r) poses.push_back(pose_at(c, r == 0 ? std::array<double, 4>{1, 0, 0, 0} : random_rotation(random)));
    const Tally tally = fly(flying, oracle, poses);
    EXPECT_EQ(tally.wrong, 0) << object.part_names[0];
    object_inside += tally.object_inside;
    obstacle_inside += tally.obstacle_inside;
    free += tally.free;
  }
  EXPECT_GT(object_inside, 10) << "poses wholly inside closed components";
  EXPECT_GT(obstacle_inside, 0) << "the small tetrahedron inside the large object";
  EXPECT_GT(free, 10);
}

TEST_P(MultiSolid, RandomFlightsAgreeWithTheOracle) {
  Random random(11);
  for (const TriangleSoup& object : {scaled(cube_object()), scaled(multi_solid_object()), scaled(swallowing_object())}) {
    const ReferenceCollider oracle(environment_, object);
    FlyingObject flying(index_, object);
    // A random walk: coherent steps, as a flight, with jumps now and then.
    std::vector<Pose> poses;
    Vec3 at{0.5, 0.5, 0.5};
    for (int i = 0; i < 600; ++i) {
      for (int a = 0; a < 3; ++a)
        at[a] = i % 50 == 0 ? random.uniform(0.05, 0.95) : std::clamp(at[a] + random.uniform(-0.01, 0.01), 0.0, 1.0);
      poses.push_back(pose_at(at, random_rotation(random)));
    }
    const Tally tally = fly(flying, oracle, poses);
    EXPECT_EQ(tally.wrong, 0) << object.part_names[0];
    EXPECT_GT(tally.touching, 10) << object.part_names[0];
    EXPECT_GT(tally.free, 10) << object.part_names[0];
  }
}

// Pairs of poses on either side of first contact along a line, `gap` (of the model's size)
// apart: bisected against the oracle, so one pose just touches or overlaps and the other just
// misses. Rounded storage answers such pairs wrongly both ways; exact storage must not.
TEST_P(MultiSolid, GrazingPosesBisectedTo1e6To1e12FromContactAgreeWithTheOracle) {
  const Variant& v = GetParam();
  Random random(13);
  const TriangleSoup object = scaled(cube_object());
  const ReferenceCollider oracle(environment_, object);
  int pairs = 0;
  for (const double gap : {1e-6, 1e-9, 1e-12}) {
    FlyingObject flying(index_, object);
    std::vector<Pose> poses;
    for (int k = 0; k < 40; ++k) {
      const auto rotation = random_rotation(random);
      // From a free point towards a solid's centre: the segment crosses a surface.
      const Vec3 from{random.uniform(0.0, 1.0), random.uniform(0.0, 1.0), random.uniform(0.55, 1.0)};
      const Vec3 to = k % 2 == 0 ? Vec3{0.3, 0.3, 0.3} : Vec3{0.72, 0.22, 0.22};
      auto at = [&](double t) {
        Vec3 p;
        for (int a = 0; a < 3; ++a) p[a] = from[a] + t * (to[a] - from[a]);
        return pose_at(p, rotation);
      };
      if (oracle.query(at(0)).collides || !oracle.query(at(1)).collides) continue;
      double lo = 0, hi = 1;  // oracle: lo free, hi colliding
      while ((hi - lo) > gap && hi - lo > 0x1p-52) {
        const double mid = 0.5 * (lo + hi);
        (oracle.query(at(mid)).collides ? hi : lo) = mid;
      }
      poses.push_back(at(lo));
      poses.push_back(at(hi));
      ++pairs;
    }
    const Tally tally = fly(flying, oracle, poses);
    EXPECT_EQ(tally.wrong, 0) << v.name << ", gap " << gap;
    EXPECT_EQ(tally.free * 2, tally.poses) << "each pair holds one free pose";
  }
  EXPECT_GT(pairs, 40);
}

INSTANTIATE_TEST_SUITE_P(
    Files, MultiSolid,
    ::testing::Values(Variant{"stl_float", "stl", 1.0, {0, 0, 0}}, Variant{"obj", "obj", 1.0, {0, 0, 0}},
                      Variant{"ply_far", "ply", 1.0, {1000.0123456789, -2000.9876543211, 3000.5555555555}},
                      Variant{"ply_tiny", "ply", 1e-9, {1e-9 / 3, 0, 0}},
                      Variant{"ply_huge", "ply", 1e9, {0, 1e9 / 7, 0}}),
    [](const ::testing::TestParamInfo<Variant>& param) { return std::string(param.param.name); });

}  // namespace
}  // namespace tetrapage
