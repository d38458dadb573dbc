// The object's shapes (mesh, hull, box) and motions (discrete, swept) of QueryOptions against
// independent brute-force oracles written here with CGAL (its exact-predicates kernel, its
// convex_hull_3 of every placed vertex, Side_of_triangle_mesh), on grazing flights (poses
// bisected to within 1e-6..1e-9 of contact); the orderings that must hold under the exact
// accuracy (mesh => hull => box; discrete => swept); and a touching contact on a floor.

#include <gtest/gtest.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>
#include <CGAL/intersections.h>

#include <cstdio>
#include <filesystem>

#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/preprocess/Preprocess.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/tools/FlightGenerator.h"
#include "tetrapage/tools/MeshLibrary.h"
#include "tetrapage/tools/ObjectGenerator.h"
#include "tetrapage/tools/ReferenceCollider.h"
#include "tetrapage/tools/TetrasGenerator.h"

namespace tetrapage {
namespace {

namespace fs = std::filesystem;
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Mesh = CGAL::Surface_mesh<K::Point_3>;

K::Point_3 cgal(const Vec3& p) {
  return {p[0], p[1], p[2]};
}
K::Triangle_3 cgal(const std::array<Vec3, 3>& t) {
  return {cgal(t[0]), cgal(t[1]), cgal(t[2])};
}

// The environment's triangles as CGAL sees them, with their boxes.
struct Environment {
  std::vector<K::Triangle_3> triangles;
  std::vector<CGAL::Bbox_3> boxes;
  explicit Environment(const TriangleSoup& soup) {
    for (std::size_t t = 0; t < soup.triangle_count(); ++t) {
      triangles.push_back(cgal(soup.corners(t)));
      boxes.push_back(triangles.back().bbox());
    }
  }
};

// Brute force: does some environment triangle meet the closed box?
bool box_oracle(const Environment& env, const BoundingBox& box) {
  const K::Iso_cuboid_3 cuboid(cgal(box.lo), cgal(box.hi));
  const CGAL::Bbox_3 bbox(box.lo[0], box.lo[1], box.lo[2], box.hi[0], box.hi[1], box.hi[2]);
  for (std::size_t t = 0; t < env.triangles.size(); ++t)
    if (CGAL::do_overlap(bbox, env.boxes[t]) && CGAL::do_intersect(env.triangles[t], cuboid))
      return true;
  return false;
}

// Brute force: does some environment triangle meet the convex hull of `points` (a solid)?
bool hull_oracle(const Environment& env, const std::vector<K::Point_3>& points) {
  Mesh hull;
  CGAL::convex_hull_3(points.begin(), points.end(), hull);
  std::vector<K::Triangle_3> faces;
  for (const auto f : hull.faces()) {
    std::vector<K::Point_3> corners;
    for (const auto v : CGAL::vertices_around_face(hull.halfedge(f), hull))
      corners.push_back(hull.point(v));
    faces.emplace_back(corners[0], corners[1], corners[2]);
  }
  const CGAL::Bbox_3 bbox = CGAL::bbox_3(points.begin(), points.end());
  const CGAL::Side_of_triangle_mesh<Mesh, K> side(hull);
  for (std::size_t t = 0; t < env.triangles.size(); ++t) {
    if (!CGAL::do_overlap(bbox, env.boxes[t])) continue;
    for (const auto& f : faces)
      if (CGAL::do_overlap(f.bbox(), env.boxes[t]) && CGAL::do_intersect(f, env.triangles[t]))
        return true;
    if (side(env.triangles[t].vertex(0)) != CGAL::ON_UNBOUNDED_SIDE) return true;
  }
  return false;
}

void add_placed(const TriangleSoup& object, const Pose& pose, std::vector<K::Point_3>& points) {
  for (const auto& v : object.vertices) points.push_back(cgal(apply_pose(pose, v)));
}

const MeshLibrary& library() {
  static const MeshLibrary instance = MeshLibrary::load_default();
  return instance;
}

fs::path folder_for(const std::string& name) {
  const fs::path folder = fs::path(TETRAPAGE_TEST_TMP) / "shapes" / name;
  fs::remove_all(folder);
  fs::create_directories(folder);
  return folder;
}

fs::path preprocess_double(const fs::path& input) {
  PreprocessOptions options;
  options.region_triangles = 200;
  options.precision = StoredPrecision::float64;
  options.threads = 1;
  const fs::path output = input.parent_path() / "index.tpi";
  preprocess({input}, output, options);
  return output;
}

struct Setting {
  ObjectShape shape;
  Motion motion;
  const char* name;
};
const Setting kSettings[] = {{ObjectShape::mesh, Motion::discrete, "mesh"},
                             {ObjectShape::hull, Motion::discrete, "hull"},
                             {ObjectShape::box, Motion::discrete, "box"},
                             {ObjectShape::mesh, Motion::swept, "mesh swept"},
                             {ObjectShape::hull, Motion::swept, "hull swept"},
                             {ObjectShape::box, Motion::swept, "box swept"}};

TEST(ObjectShapes, ShapesAndMotionsEqualBruteForceOnAGrazingFlight) {
  const fs::path folder = folder_for("grazing");
  const fs::path scene_path = folder / "tetras.ply";
  {
    MeshWriter writer(scene_path);
    // Tetras: dense, so that a billiard flight collides often.
    TetrasOptions options;
    options.triangles = 20000;
    options.seed = 11;
    generate_tetras(options, writer);
    writer.commit();
  }
  const TriangleSoup scene = read_mesh(scene_path);
  ObjectOptions object_options;
  object_options.triangles = 300;
  object_options.seed = 2;  // a real (concave) mesh: the hull differs from it
  const TriangleSoup object = generate_object(object_options, &library()).soup;
  const ReferenceCollider oracle(scene, object);
  FlightOptions flight_options;
  flight_options.steps = 1500;
  flight_options.seed = 5;
  const Flight billiard = generate_billiard_flight(oracle, flight_options);
  GrazingOptions grazing_options;
  grazing_options.distances = {1e-6, 1e-9};
  const Flight grazing = generate_grazing_flight(oracle, billiard, grazing_options);
  ASSERT_GT(grazing.collisions, 5u) << "the billiard flight must collide";
  const auto index = std::make_shared<const CollisionIndex>(preprocess_double(scene_path));
  const Environment env(scene);

  std::vector<FlyingObject> flying;
  for (std::size_t s = 0; s < std::size(kSettings); ++s) flying.emplace_back(index, object);
  FlyingObject boxes(index, object);
  std::size_t differences[std::size(kSettings)] = {};
  std::size_t hull_only = 0, box_only = 0, swept_only = 0;
  BoundingBox previous_box;
  for (std::size_t i = 0; i < grazing.poses.size(); ++i) {
    const Pose& pose = grazing.poses[i];
    const bool first = i == 0;
    // The independent answers of each question.
    const BoundingBox box = boxes.world_box(pose);
    BoundingBox swept_box = box;
    if (!first) swept_box.extend(previous_box);
    std::vector<K::Point_3> points;
    add_placed(object, pose, points);
    const bool hull = hull_oracle(env, points);
    if (!first) add_placed(object, grazing.poses[i - 1], points);
    const bool swept_hull = first ? hull : hull_oracle(env, points);
    const bool expected[] = {bool(grazing.collides[i]),
                             hull,
                             box_oracle(env, box),
                             first ? bool(grazing.collides[i]) : swept_hull,
                             swept_hull,
                             box_oracle(env, swept_box)};
    previous_box = box;
    bool got[std::size(kSettings)];
    for (std::size_t s = 0; s < std::size(kSettings); ++s) {
      QueryOptions options;
      options.shape = kSettings[s].shape;
      options.motion = kSettings[s].motion;
      got[s] = flying[s].query(pose, options).collides;
      if (got[s] != expected[s] && ++differences[s] <= 3)
        ADD_FAILURE() << kSettings[s].name << ": pose " << i << " runtime " << got[s] << " oracle "
                      << expected[s];
    }
    // The orderings of the exact answers: mesh => hull => box, discrete => swept.
    EXPECT_TRUE(!got[0] || got[1]) << "pose " << i;
    EXPECT_TRUE(!got[1] || got[2]) << "pose " << i;
    EXPECT_TRUE(!got[3] || got[4]) << "pose " << i;
    EXPECT_TRUE(!got[4] || got[5]) << "pose " << i;
    for (int s = 0; s < 3; ++s)
      EXPECT_TRUE(!got[s] || got[s + 3]) << kSettings[s].name << " pose " << i;
    hull_only += got[1] && !got[0];
    box_only += got[2] && !got[1];
    swept_only += got[4] && !got[1];
  }
  std::printf("%zu grazing poses (%llu colliding): hull only %zu, box only %zu, swept only %zu\n",
              grazing.poses.size(), static_cast<unsigned long long>(grazing.collisions), hull_only,
              box_only, swept_only);
  for (std::size_t s = 0; s < std::size(kSettings); ++s)
    EXPECT_EQ(differences[s], 0u) << kSettings[s].name;
  // The coarser questions really are coarser on this flight (else the test checks little).
  EXPECT_GT(hull_only, 0u);
  EXPECT_GT(box_only, 0u);
  EXPECT_GT(swept_only, 0u);
}

TEST(ObjectShapes, ATouchingVertexCountsForEveryShapeAndAGapForNone) {
  const fs::path folder = folder_for("touching");
  const fs::path scene_path = folder / "floor.ply";
  // A floor z = 0 and, far from it, a few triangles so that the model has some extent.
  {
    MeshWriter writer(scene_path);
    const std::vector<Vec3> floor{{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
    const std::vector<TriangleIndices> floor_triangles{{0, 1, 2}, {0, 2, 3}};
    writer.add_part(floor, floor_triangles);
    const std::vector<Vec3> roof{{-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1}};
    writer.add_part(roof, floor_triangles);
    writer.commit();
  }
  const auto index = std::make_shared<const CollisionIndex>(preprocess_double(scene_path));
  // An octahedron whose lowest vertex is (0, 0, -0.0625).
  TriangleSoup object;
  object.vertices = {{0.0625, 0, 0},  {-0.0625, 0, 0}, {0, 0.0625, 0},
                     {0, -0.0625, 0}, {0, 0, 0.0625},  {0, 0, -0.0625}};
  object.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                      {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  object.part_of.assign(object.triangles.size(), 0);
  object.part_names = {"octahedron"};
  Pose touching;  // the identity rotation places exactly: the vertex lands on z = 0
  touching.translation = {0.25, 0.125, 0.0625};
  Pose apart = touching;
  apart.translation[2] += 1e-9;
  for (const auto& setting : kSettings) {
    QueryOptions options;
    options.shape = setting.shape;
    options.motion = setting.motion;
    FlyingObject flying(index, object);
    EXPECT_FALSE(flying.query(apart, options).collides) << setting.name << " apart (first query)";
    EXPECT_TRUE(flying.query(touching, options).collides) << setting.name << " touching";
    // Swept from the touching pose to the free one still touches; discrete does not.
    EXPECT_EQ(flying.query(apart, options).collides, setting.motion == Motion::swept)
        << setting.name << " after";
    const QueryResult result = flying.query(touching, options);
    ASSERT_TRUE(result.collides);
    EXPECT_EQ(result.contacts.front().object_triangle == Contact::kNoObjectTriangle,
              setting.shape != ObjectShape::mesh || setting.motion == Motion::swept)
        << setting.name;
  }
}

}  // namespace
}  // namespace tetrapage
