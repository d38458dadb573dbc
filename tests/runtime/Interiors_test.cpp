// Interiors of closed obstacles (issue 6, the study's footnote 3): preprocess classifies each
// tet's reference point by exact vertical ray parity (RayParity.h) and the runtime decides
// "inside" by crossings within one tet. Checked against Embree's ray parity for the reference
// points, and against the exact oracle (tools' ReferenceCollider: parity over the whole closed
// meshes with CGAL's exact predicates) for random points, for a flight that ends inside an
// obstacle, and for an obstacle that ends up inside a closed object.

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "tetrapage/formats/index/IndexReader.h"
#include "tetrapage/formats/mesh/Manifest.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/formats/mesh/SurfaceComponents.h"
#include "tetrapage/preprocess/Preprocess.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/runtime/query/ObstacleInterior.h"
#include "tetrapage/tools/EmbreeInteriorClassifier.h"
#include "tetrapage/tools/MeshLibrary.h"
#include "tetrapage/tools/ObjectGenerator.h"
#include "tetrapage/tools/Random.h"
#include "tetrapage/tools/ReferenceCollider.h"
#include "tetrapage/tools/SceneGenerator.h"

namespace tetrapage {
namespace {

namespace fs = std::filesystem;

void add_box(TriangleSoup& soup, const Vec3& lo, const Vec3& hi) {
  const auto base = std::uint32_t(soup.vertices.size());
  for (int i = 0; i < 8; ++i)
    soup.vertices.push_back(
        {(i & 1) ? hi[0] : lo[0], (i & 2) ? hi[1] : lo[1], (i & 4) ? hi[2] : lo[2]});
  const std::array<std::array<std::uint32_t, 4>, 6> faces{
      {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}}};
  for (const auto& f : faces) {
    soup.triangles.push_back({base + f[0], base + f[1], base + f[2]});
    soup.triangles.push_back({base + f[0], base + f[2], base + f[3]});
  }
  soup.part_of.resize(soup.triangles.size(), 0);
  if (soup.part_names.empty()) soup.part_names = {"boxes"};
}

void write(const TriangleSoup& soup, const fs::path& path) {
  MeshWriter writer(path);
  writer.add_part(soup.vertices, soup.triangles);
  writer.commit();
}

struct Model {
  TriangleSoup environment;  // all parts, in the order preprocess reads them
  fs::path folder, index;
  PreprocessSummary summary;
  Model() = default;
  Model(Model&&) = default;
  ~Model() {
    std::error_code ignored;
    if (!folder.empty()) fs::remove_all(folder, ignored);
  }
};

// Parts: a scene of real closed meshes (one part per copy, through a manifest); two nested
// boxes (inside = the shell between them) plus a small box far from the rest; an open sheet
// that has no inside. pairs_per_pass > 0 forces passes of so many (point, part) pairs.
Model make_model(const std::string& name, std::uint64_t pairs_per_pass = 0) {
  {
    Model m;
    // ctest runs each test in its own process, in parallel: one folder per process.
    const fs::path folder =
        fs::path(TETRAPAGE_TEST_TMP) / (name + "-" + std::to_string(::getpid()));
    m.folder = folder;
    fs::remove_all(folder);
    fs::create_directories(folder);
    std::vector<fs::path> inputs{folder / "scene.json", folder / "boxes.obj", folder / "sheet.obj"};
    {
      MeshWriter writer(inputs[0]);
      SceneOptions options;
      options.triangles = 6000;
      options.seed = 5;
      generate_scene(MeshLibrary::load_default(), options, writer);
      writer.commit();
    }
    TriangleSoup boxes;
    add_box(boxes, {0.1, 0.55, 0.1}, {0.45, 0.9, 0.45});
    add_box(boxes, {0.2, 0.65, 0.2}, {0.3, 0.75, 0.3});
    add_box(boxes, {1.2, 1.2, 1.2}, {1.22, 1.22, 1.22});
    write(boxes, inputs[1]);
    TriangleSoup sheet;
    sheet.vertices = {{0.5, 0.0, 0.55}, {1.0, 0.0, 0.55}, {1.0, 0.5, 0.55}, {0.5, 0.5, 0.55}};
    sheet.triangles = {{0, 1, 2}, {0, 2, 3}};
    write(sheet, inputs[2]);
    m.environment.append(load_assembly(read_manifest(inputs[0])));
    for (std::size_t i = 1; i < inputs.size(); ++i) m.environment.append(read_mesh(inputs[i]));
    m.index = folder / "model.tpi";
    PreprocessOptions options;
    options.region_triangles = 64;
    options.precision = StoredPrecision::float64;
    options.interiors = true;
    options.interior_pairs_per_pass = pairs_per_pass;
    m.summary = preprocess(inputs, m.index, options);
    return m;
  }
}

const Model& model() {
  static const Model instance = make_model("interiors");
  return instance;
}

TriangleSoup tetra_object(double size) {
  TriangleSoup soup;
  soup.vertices = {{0, 0, 0}, {size, 0, 0}, {0, size, 0}, {0, 0, size}};
  soup.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  soup.part_of.assign(4, 0);
  soup.part_names = {"tetra"};
  return soup;
}

TEST(Interiors, PreprocessClassifiesTheClosedComponents) {
  const Model& m = model();
  const auto parts = std::uint32_t(m.summary.parts);
  ASSERT_GT(parts, 5u) << "the scene's copies are parts";
  // Each copy is one component; boxes.obj is one part of three closed components.
  const auto components = std::uint32_t(m.summary.components);
  EXPECT_EQ(components, parts + 2);
  EXPECT_EQ(m.summary.closed_components, components - 1)
      << "the sheet is open, the copies and the boxes are closed";
  EXPECT_EQ(m.summary.interiors.rfind("stored (1 pass)", 0), 0u) << m.summary.interiors;
  // Undecided points are moved and classified again: none is left.
  EXPECT_EQ(m.summary.interior_undecided, 0u) << m.summary.interiors;
  EXPECT_GT(m.summary.interior_tets, 0u);
  const CollisionIndex index(m.index);
  ASSERT_TRUE(index.has_interiors());
  ASSERT_EQ(index.component_count(), components);
  for (std::uint32_t c = 0; c + 1 < components; ++c) EXPECT_TRUE(index.component_closed(c)) << c;
  EXPECT_FALSE(index.component_closed(components - 1));
  // The three boxes of boxes.obj are the part before the sheet's.
  for (std::uint32_t c = components - 4; c + 1 < components; ++c)
    EXPECT_EQ(index.component_part(c), parts - 2);
  EXPECT_EQ(index.component_part(components - 1), parts - 1);
}

void expect_points_agree(const Model& m) {
  const ReferenceCollider oracle(m.environment, tetra_object(0.01));
  const CollisionIndex index(m.index);
  Random random(11);
  std::uint32_t hint = 0;
  int inside = 0, unknown = 0, wrong = 0;
  const int points = 20000;
  const BoundingBox box = m.environment.bounds();
  for (int i = 0; i < points; ++i) {
    geometry::Point p;
    for (int a = 0; a < 3; ++a) p[a] = random.uniform(box.lo[a] - 0.05, box.hi[a] + 0.05);
    const ObstacleQuery answer = locate_in_obstacles(index, hint, p);
    if (answer.containment == ObstacleContainment::unknown ||
        answer.containment == ObstacleContainment::on_surface) {
      ++unknown;
      continue;
    }
    const bool runtime_inside = answer.containment == ObstacleContainment::inside;
    const bool oracle_inside = oracle.inside_environment(p);
    inside += oracle_inside;
    if (runtime_inside != oracle_inside && ++wrong <= 5)
      ADD_FAILURE() << "point (" << p[0] << ", " << p[1] << ", " << p[2] << "): runtime "
                    << runtime_inside << ", oracle " << oracle_inside;
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_GT(inside, points / 50) << "the points must test interiors, not only free space";
  // Undecided tets (Embree's rays disagreeing) are rare and never answer wrongly.
  EXPECT_LE(unknown, points / 500);
}

TEST(Interiors, RandomPointsAgreeWithParityOverWholeClosedMeshes) {
  expect_points_agree(model());
}

TEST(Interiors, AMovingPointDecidedFromItsLastAnswerAgreesWithTheOracle) {
  // A random walk of short steps: most points share their tet with the one before, and are
  // decided by parity along the step (ObstacleMemo) rather than from the reference point.
  const Model& m = model();
  const ReferenceCollider oracle(m.environment, tetra_object(0.01));
  const CollisionIndex index(m.index);
  Random random(23);
  const BoundingBox box = m.environment.bounds();
  geometry::Point p{};
  std::uint32_t hint = 0, plain_hint = 0, held_hint = 0;
  ObstacleMemo memo, held_memo;
  // The same walk again with every other shard pinned by the caller (a flying object's
  // region): the pinned ones are read from there.
  std::vector<ShardPin> held;
  for (std::uint32_t s = 0; s < index.shard_count(); s += 2)
    held.push_back(index.cache().acquire(s));
  int inside = 0, from_memo = 0, wrong = 0;
  const int steps = 20000;
  for (int i = 0; i < steps; ++i) {
    // Every 50 steps a jump to a random point of the box, then short steps from there.
    for (int a = 0; a < 3; ++a)
      p[a] = i % 50 == 0
                 ? random.uniform(box.lo[a], box.hi[a])
                 : std::clamp(p[a] + random.uniform(-0.002, 0.002) * (box.hi[a] - box.lo[a]),
                              box.lo[a], box.hi[a]);
    const bool same_tet = memo.valid;
    const std::uint32_t memo_tet = memo.tet;
    const ObstacleQuery answer = locate_in_obstacles(index, hint, p, memo);
    from_memo += same_tet && answer.tet == memo_tet;
    const ObstacleQuery plain = locate_in_obstacles(index, plain_hint, p);
    EXPECT_EQ(answer.containment, plain.containment) << "step " << i;
    const ObstacleQuery from_held = locate_in_obstacles(index, held_hint, p, held_memo, held);
    EXPECT_EQ(from_held.containment, answer.containment) << "step " << i;
    EXPECT_EQ(from_held.component, answer.component) << "step " << i;
    if (answer.containment != ObstacleContainment::inside &&
        answer.containment != ObstacleContainment::outside)
      continue;
    EXPECT_EQ(answer.component, plain.component) << "step " << i;
    const bool oracle_inside = oracle.inside_environment(p);
    inside += oracle_inside;
    if ((answer.containment == ObstacleContainment::inside) != oracle_inside && ++wrong <= 5)
      ADD_FAILURE() << "step " << i << ": point (" << p[0] << ", " << p[1] << ", " << p[2] << ")";
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_GT(inside, steps / 50) << "the walk must visit interiors";
  EXPECT_GT(from_memo, steps / 2) << "most steps must be decided from the last answer";
}

TEST(Interiors, ClassifiedInSeveralPassesTheTablesAreTheSame) {
  const Model& whole = model();
  const Model m = make_model("interiors-passes", 50);
  ASSERT_EQ(m.summary.interiors.rfind("stored (", 0), 0u) << m.summary.interiors;
  EXPECT_NE(m.summary.interiors.rfind("stored (1 pass)", 0), 0u) << m.summary.interiors;
  const IndexReader one(whole.index), several(m.index);
  EXPECT_EQ(one.read_table_uint64("interior_offsets"),
            several.read_table_uint64("interior_offsets"));
  EXPECT_EQ(one.read_table_uint32("interior_components"),
            several.read_table_uint32("interior_components"));
  EXPECT_EQ(one.read_table_double("reference_points"),
            several.read_table_double("reference_points"));
  EXPECT_EQ(one.read_table_uint8("component_closed"), several.read_table_uint8("component_closed"));
}

TEST(Interiors, StoredClassesAreEmbreeRayParityWhereverEmbreeDecides) {
  // An independent engine: Embree's float rays in three directions against the closed
  // components (the exact classification uses one vertical ray with a symbolic perturbation).
  const Model& m = model();
  const IndexReader reader(m.index);
  const auto closed = reader.read_table_uint8("component_closed");
  const auto references = reader.read_table_double("reference_points");
  const auto offsets = reader.read_table_uint64("interior_offsets");
  const auto parts = reader.read_table_uint32("interior_components");
  // The model's components numbered in input order, as the preprocess numbers them.
  const SurfaceComponents split = find_surface_components(m.environment);
  ASSERT_EQ(split.components.size(), closed.size());
  EmbreeInteriorClassifier embree;
  std::vector<std::array<Vec3, 3>> triangles;
  for (std::uint32_t p = 0; p < closed.size(); ++p) {
    if (closed[p] == 0) continue;
    triangles.clear();
    for (std::size_t t = 0; t < m.environment.triangle_count(); ++t)
      if (split.component_of[t] == p) triangles.push_back(m.environment.corners(t));
    embree.add_triangles(p, triangles);
  }
  std::vector<Vec3> points;
  std::vector<std::size_t> tets;
  for (std::size_t t = 0; t + 1 < offsets.size(); ++t) {
    if (std::isnan(references[3 * t])) continue;
    points.push_back({references[3 * t], references[3 * t + 1], references[3 * t + 2]});
    tets.push_back(t);
  }
  ASSERT_GT(points.size(), 100u);
  std::vector<PointInterior> answers;
  embree.classify(points, answers);
  std::size_t decided = 0, inside = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::size_t t = tets[i];
    const std::vector<std::uint32_t> stored(parts.begin() + std::ptrdiff_t(offsets[t]),
                                            parts.begin() + std::ptrdiff_t(offsets[t + 1]));
    ASSERT_TRUE(stored.empty() || stored[0] != 0xffffffffu) << "tet " << t << " undecided";
    if (!answers[i].decided) continue;
    ++decided;
    inside += !stored.empty();
    EXPECT_EQ(stored, answers[i].parts) << "tet " << t;
  }
  EXPECT_GT(decided, points.size() * 99 / 100);
  EXPECT_GT(inside, 10u) << "the reference points must test interiors";
}

// Poses along a line with fixed random rotations.
std::vector<Pose> line_poses(const Vec3& from, const Vec3& to, int steps, std::uint64_t seed) {
  Random random(seed);
  std::vector<Pose> poses;
  for (int i = 0; i <= steps; ++i) {
    Pose pose;
    for (int a = 0; a < 3; ++a) pose.translation[a] = from[a] + (to[a] - from[a]) * i / steps;
    std::array<double, 4> q{random.normal(), random.normal(), random.normal(), random.normal()};
    const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (auto& c : q) c /= n;
    pose.rotation = q;
    poses.push_back(pose);
  }
  return poses;
}

// Flies the poses; every collision answer must be the oracle's, and where the oracle sees the
// containment `kind`, the runtime must name it. Returns how many poses had it.
int fly_against_oracle(FlyingObject& flying, const ReferenceCollider& oracle,
                       const std::vector<Pose>& poses, Containment kind,
                       int* contained_in_free_box = nullptr) {
  int contained = 0, wrong = 0;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const auto expected = oracle.query(poses[i]);
    const QueryResult got = flying.query(poses[i]);
    if (contained_in_free_box && got.counters.found_free_box && got.containment == kind)
      ++*contained_in_free_box;
    const bool oracle_contained = kind == Containment::object_inside_obstacle
                                      ? expected.object_inside
                                      : expected.obstacle_inside;
    if (oracle_contained) {
      ++contained;
      EXPECT_EQ(got.containment, kind) << "pose " << i;
    }
    if (got.collides != expected.collides && ++wrong <= 5)
      ADD_FAILURE() << "pose " << i << ": runtime " << got.collides << ", oracle "
                    << expected.collides;
  }
  EXPECT_EQ(wrong, 0);
  return contained;
}

TEST(Interiors, AFlightEndingInsideAnObstacleCollidesAsTheOracleSays) {
  const Model& m = model();
  ObjectOptions object_options;
  object_options.triangles = 116;
  object_options.size = 0.02;
  const TriangleSoup object = generate_object(object_options).soup;
  const ReferenceCollider oracle(m.environment, object);
  auto index = std::make_shared<const CollisionIndex>(m.index);
  FlyingObject flying(index, object);
  // From outside the boxes, through the outer wall into the shell, through the inner box, and
  // on into the sheet's region (open: nothing inside) and the scene.
  std::vector<Pose> poses = line_poses({-0.1, 0.6, 0.15}, {0.4, 0.85, 0.4}, 600, 3);
  const auto more = line_poses({0.4, 0.85, 0.4}, {0.9, 0.2, 0.6}, 600, 4);
  poses.insert(poses.end(), more.begin(), more.end());
  int contained_in_free_box = 0;
  EXPECT_GT(fly_against_oracle(flying, oracle, poses, Containment::object_inside_obstacle,
                               &contained_in_free_box),
            100)
      << "the flight must end inside obstacles";
  // Deep inside, a box around the object holds no triangle: the walk still decides.
  EXPECT_GT(contained_in_free_box, 20);
}

TEST(Interiors, AnObstacleInsideAClosedObjectCollides) {
  const Model& m = model();
  TriangleSoup big;
  add_box(big, {-0.05, -0.05, -0.05}, {0.05, 0.05, 0.05});
  const ReferenceCollider oracle(m.environment, big);
  auto index = std::make_shared<const CollisionIndex>(m.index);
  FlyingObject flying(index, big);
  ASSERT_TRUE(flying.closed());
  // Over the small box at 1.2-1.22: the object swallows it whole for part of the way.
  const auto poses = line_poses({1.0, 1.21, 1.21}, {1.4, 1.21, 1.21}, 400, 5);
  EXPECT_GT(fly_against_oracle(flying, oracle, poses, Containment::obstacle_inside_object), 20);
}

TEST(Interiors, LeavesInsideAClosedObjectAreOnlyNotedAndTheAnswersStayTheOracles) {
  // A closed box larger than the scene's copies, flown through them over R-tree shards: leaves
  // deep inside it meet no object triangle, and phase I only notes their triangles for
  // containment (StepCounters::leaves_inside_object). The answers, and the copies the box
  // swallows whole, stay the oracle's.
  const Model& m = model();
  const fs::path rtree = m.folder / "rtree.tpi";
  PreprocessOptions options;
  options.region_triangles = 64;
  options.precision = StoredPrecision::float64;
  options.interiors = true;
  options.shard = ShardChoice::rtree;
  preprocess({m.folder / "scene.json", m.folder / "boxes.obj", m.folder / "sheet.obj"}, rtree,
             options);
  TriangleSoup big;
  add_box(big, {-0.15, -0.15, -0.15}, {0.15, 0.15, 0.15});
  const ReferenceCollider oracle(m.environment, big);
  auto index = std::make_shared<const CollisionIndex>(rtree);
  FlyingObject flying(index, big);
  std::uint64_t leaves_inside = 0;
  int wrong = 0, swallowed = 0;
  // Three lines through the scene's copies, and one over the small box at 1.2-1.22, which the
  // object swallows whole for part of the way.
  std::vector<Pose> poses;
  for (const double y : {0.3, 0.5, 0.7})
    for (const Pose& pose : line_poses({0.05, y, 0.5}, {0.95, y, 0.5}, 300, 11))
      poses.push_back(pose);
  for (const Pose& pose : line_poses({1.0, 1.21, 1.21}, {1.4, 1.21, 1.21}, 300, 13))
    poses.push_back(pose);
  for (const Pose& pose : poses) {
    const auto expected = oracle.query(pose);
    const QueryResult got = flying.query(pose);
    leaves_inside += got.counters.leaves_inside_object;
    if (expected.obstacle_inside && !expected.surfaces_touch) {
      ++swallowed;
      EXPECT_EQ(got.containment, Containment::obstacle_inside_object);
    }
    if (got.collides != expected.collides && ++wrong <= 5)
      ADD_FAILURE() << "pose " << pose.translation[0] << " " << pose.translation[1] << ": runtime "
                    << got.collides << ", oracle " << expected.collides;
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_GT(leaves_inside, 0u) << "no leaf lay inside the box: the test no longer reaches the path";
  EXPECT_GT(swallowed, 0) << "no copy lay wholly inside the box: containment is not reached";
  RecordProperty("leaves_inside_object", std::to_string(leaves_inside));
  RecordProperty("swallowed", swallowed);
}

TEST(Interiors, ABoxThatHoldsNoComponentIsToldSoAndNoFittingComponentIsMissed) {
  // A step whose box fits no component of a part skips the leaves inside the object: the
  // index's shortcut must never say "none" when some component's box lies in the box (checked
  // against every component's box, one by one), and must say it for boxes shorter than all.
  const Model& m = model();
  const CollisionIndex index(m.index);
  ASSERT_GT(index.component_count(), 2u);
  std::mt19937 random(7);
  std::uniform_real_distribution<double> centre(-0.2, 1.2), half(0.0, 0.4);
  int fitting = 0, told_none = 0;
  for (int i = 0; i < 4000; ++i) {
    geometry::Box box;
    for (int a = 0; a < 3; ++a) {
      const double c = centre(random), h = half(random);
      box.lo[a] = c - h, box.hi[a] = c + h;
    }
    bool fits = false;
    for (std::uint32_t c = 0; c < index.component_count() && !fits; ++c)
      fits = index.component_part(c) != CollisionIndex::kNoPart &&
             geometry::box_contains(box, index.component_bounds(c));
    const bool may = index.may_hold_a_component(box);
    if (fits) {
      ++fitting;
      EXPECT_TRUE(may) << "box " << i << " holds a component";
    }
    told_none += !may;
  }
  EXPECT_GT(fitting, 0);
  EXPECT_GT(told_none, 0);
  // A box exactly a component's own box holds it.
  for (std::uint32_t c = 0; c < index.component_count(); ++c) {
    if (index.component_part(c) != CollisionIndex::kNoPart) {
      EXPECT_TRUE(index.may_hold_a_component(index.component_bounds(c))) << "component " << c;
    }
  }
}

TEST(Interiors, AnIndexWithoutInteriorsAnswersUnknown) {
  const Model& m = model();
  const fs::path plain = m.index.parent_path() / "plain.tpi";
  PreprocessOptions options;
  options.region_triangles = 256;
  options.precision = StoredPrecision::float64;
  const fs::path boxes = m.folder / "boxes.obj";
  const auto summary = preprocess({boxes}, plain, options);
  EXPECT_EQ(summary.interiors, "off");
  const CollisionIndex index(plain);
  EXPECT_FALSE(index.has_interiors());
  std::uint32_t hint = 0;
  EXPECT_EQ(locate_in_obstacles(index, hint, {0.15, 0.6, 0.15}).containment,
            ObstacleContainment::unknown);
}

}  // namespace
}  // namespace tetrapage
