// Dynamic obstacles against an independent reference: tools' ReferenceCollider (CGAL) built on
// one TriangleSoup holding the index's visible parts plus the dynamic parts placed by
// apply_pose, each its own part. Every answer of a FlyingObject given the overlay (collides,
// surfaces touching, which body holds which) must be the reference's, over random poses and
// after sequences of insert, move, remove, hide and show; first_hit never names a hidden part;
// all_contacts names exactly the dynamic triangle pairs that CGAL's exact kernel finds; a part
// inserted into the free box is seen on the very next step; save and load give the same
// answers; damaged files fail with a FormatError naming the file; the C API answers as C++.

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>

#include <limits>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/preprocess/Preprocess.h"
#include "tetrapage/runtime/query/DynamicObstacles.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/runtime/query/ObjectGroup.h"
#include "tetrapage/tetrapage.h"
#include "tetrapage/tools/MeshLibrary.h"
#include "tetrapage/tools/ObjectGenerator.h"
#include "tetrapage/tools/Random.h"
#include "tetrapage/tools/ReferenceCollider.h"

namespace tetrapage {
namespace {

namespace fs = std::filesystem;
using K = CGAL::Exact_predicates_inexact_constructions_kernel;

const MeshLibrary& library() {
  static const MeshLibrary instance = MeshLibrary::load_default();
  return instance;
}

// A generated mesh (a sphere, or a real non-convex mesh when triangles > 200) fitted into a
// cube of side `size`.
TriangleSoup shape(std::uint64_t triangles, double size, std::uint64_t seed) {
  ObjectOptions options;
  options.triangles = triangles;
  options.size = size;
  options.seed = seed;
  return generate_object(options, &library()).soup;
}

TriangleSoup moved(TriangleSoup soup, const Vec3& by) {
  for (auto& v : soup.vertices)
    for (int a = 0; a < 3; ++a) v[a] += by[a];
  return soup;
}

Pose random_pose(Random& random, double lo, double hi) {
  Pose pose;
  pose.translation = {random.uniform(lo, hi), random.uniform(lo, hi), random.uniform(lo, hi)};
  pose.rotation =
      unit_quaternion({random.normal(), random.normal(), random.normal(), random.normal()});
  return pose;
}

// The static scene: parts in [0, 1]^3, closed solids (spheres and real meshes) and one open
// sheet, written as one PLY (one part each) and preprocessed with interiors.
struct Scene {
  TriangleSoup soup;  ///< as read back: part k is the index's part k
  std::shared_ptr<const CollisionIndex> index;
  fs::path folder;
  Scene() = default;
  Scene(Scene&& other) noexcept
      : soup(std::move(other.soup)), index(std::move(other.index)), folder(std::exchange(other.folder, {})) {}
  ~Scene() {
    std::error_code ignored;
    if (!folder.empty()) fs::remove_all(folder, ignored);
  }
};

const Scene& scene() {
  static const Scene built = [] {
    Scene s;
    // One folder per process: ctest runs each test in its own, two at a time.
    s.folder = fs::path(TETRAPAGE_TEST_TMP) / ("dynamic-" + std::to_string(::getpid()));
    fs::remove_all(s.folder);
    fs::create_directories(s.folder);
    const fs::path ply = s.folder / "scene.ply";
    {
      MeshWriter writer(ply);
      const std::vector<std::pair<Vec3, std::uint64_t>> placed = {
          {{0.2, 0.2, 0.2}, 116},  {{0.75, 0.25, 0.3}, 300}, {{0.3, 0.75, 0.7}, 116},
          {{0.7, 0.7, 0.75}, 300}, {{0.5, 0.5, 0.5}, 116},   {{0.2, 0.8, 0.2}, 300}};
      for (std::size_t k = 0; k < placed.size(); ++k) {
        const TriangleSoup part = moved(shape(placed[k].second, 0.28, k + 1), placed[k].first);
        writer.add_part(part.vertices, part.triangles, "solid" + std::to_string(k));
      }
      // An open sheet: two triangles across the scene's bottom.
      const std::vector<Vec3> sheet = {{0, 0, 0.05}, {1, 0, 0.1}, {1, 1, 0.05}, {0, 1, 0.1}};
      const std::vector<TriangleIndices> halves = {{0, 1, 2}, {0, 2, 3}};
      writer.add_part(sheet, halves, "sheet");
      writer.commit();
    }
    s.soup = read_mesh(ply);
    PreprocessOptions options;
    options.region_triangles = 200;
    options.interiors = true;
    preprocess({ply}, s.folder / "scene.tpi", options);
    s.index = std::make_shared<const CollisionIndex>(s.folder / "scene.tpi");
    return s;
  }();
  return built;
}

// The reference's environment: the visible parts of the scene and the dynamic parts, placed.
TriangleSoup reference_world(const DynamicObstacles& overlay) {
  const TriangleSoup& soup = scene().soup;
  TriangleSoup world;
  std::vector<std::uint32_t> new_part(soup.part_count(), 0xffffffffu);
  for (std::uint32_t p = 0; p < soup.part_count(); ++p)
    if (!overlay.hidden(p))
      new_part[p] = std::uint32_t(world.part_names.size()),
      world.part_names.push_back(soup.part_names[p]);
  std::vector<std::uint32_t> vertex_of(soup.vertices.size(), 0xffffffffu);
  for (std::size_t t = 0; t < soup.triangles.size(); ++t) {
    if (new_part[soup.part_of[t]] == 0xffffffffu) continue;
    TriangleIndices copy;
    for (int c = 0; c < 3; ++c) {
      std::uint32_t& v = vertex_of[soup.triangles[t][c]];
      if (v == 0xffffffffu)
        v = std::uint32_t(world.vertices.size()),
        world.vertices.push_back(soup.vertices[soup.triangles[t][c]]);
      copy[c] = v;
    }
    world.triangles.push_back(copy);
    world.part_of.push_back(new_part[soup.part_of[t]]);
  }
  for (const auto& part : overlay.parts()) {
    const auto base = std::uint32_t(world.vertices.size());
    const auto rotation = rotation_matrix(part.pose.rotation);
    for (const auto& v : part.model->mesh.vertices)
      world.vertices.push_back(apply_pose(rotation, part.pose.translation, v));
    for (const auto& t : part.model->mesh.triangles) {
      world.triangles.push_back({base + t[0], base + t[1], base + t[2]});
      world.part_of.push_back(std::uint32_t(world.part_names.size()));
    }
    world.part_names.push_back(part.name);
  }
  return world;
}

// Each dynamic triangle pair that meets, by CGAL's exact predicates on the placed triangles.
std::set<std::pair<std::uint64_t, std::uint32_t>> dynamic_pairs_by_cgal(
    const DynamicObstacles& overlay, DynamicPartId id, const TriangleSoup& object,
    const Pose& pose) {
  const auto* part = overlay.find(id);
  const auto placed = [](const TriangleSoup& soup, const Pose& p, const TriangleIndices& t) {
    const auto r = rotation_matrix(p.rotation);
    std::array<K::Point_3, 3> corners;
    for (int c = 0; c < 3; ++c) {
      const Vec3 x = apply_pose(r, p.translation, soup.vertices[t[c]]);
      corners[c] = K::Point_3(x[0], x[1], x[2]);
    }
    return K::Triangle_3(corners[0], corners[1], corners[2]);
  };
  std::set<std::pair<std::uint64_t, std::uint32_t>> pairs;
  for (std::uint32_t a = 0; a < part->model->mesh.triangles.size(); ++a) {
    const K::Triangle_3 ta = placed(part->model->mesh, part->pose, part->model->mesh.triangles[a]);
    for (std::uint32_t b = 0; b < object.triangles.size(); ++b)
      if (CGAL::do_intersect(ta, placed(object, pose, object.triangles[b]))) pairs.insert({a, b});
  }
  return pairs;
}

struct Tally {
  int poses = 0, touching = 0, inside = 0, wrong = 0;
};

// One pose against the reference, first_hit and all_contacts; `tally` counts.
void check_pose(FlyingObject& flying, const ReferenceCollider& reference,
                const DynamicObstacles& overlay, const Pose& pose, Tally& tally, bool check_pairs) {
  const ReferenceCollider::Answer expected = reference.query(pose);
  ++tally.poses;
  tally.touching += expected.surfaces_touch;
  tally.inside += expected.collides && !expected.surfaces_touch;
  for (const QueryMode mode : {QueryMode::first_hit, QueryMode::all_contacts}) {
    QueryOptions options;
    options.mode = mode;
    const QueryResult got = flying.query(pose, options);
    const bool agree =
        got.collides == expected.collides && !got.contacts.empty() == expected.surfaces_touch &&
        (got.containment == Containment::object_inside_obstacle) == expected.object_inside &&
        (got.containment == Containment::obstacle_inside_object) == expected.obstacle_inside;
    if (!agree && ++tally.wrong <= 5)
      ADD_FAILURE() << "mode " << int(mode) << " pose t=(" << pose.translation[0] << ", "
                    << pose.translation[1] << ", " << pose.translation[2] << "): runtime "
                    << got.collides << "/" << got.contacts.size() << "/" << int(got.containment)
                    << ", reference " << expected.collides << "/" << expected.surfaces_touch << "/"
                    << expected.object_inside << expected.obstacle_inside;
    for (const Contact& c : got.contacts) {
      if (c.dynamic_part == kNoDynamicPart) {
        EXPECT_FALSE(overlay.hidden(c.environment_part)) << "a hidden part's triangle was reported";
        EXPECT_EQ(c.environment_part, scene().soup.part_of[c.environment_triangle]);
      } else {
        EXPECT_EQ(c.environment_part, Contact::kDynamicPart);
        EXPECT_NE(overlay.find(c.dynamic_part), nullptr);
      }
    }
    if (mode != QueryMode::all_contacts || !check_pairs) continue;
    // Every dynamic pair CGAL finds, and no other.
    std::map<DynamicPartId, std::set<std::pair<std::uint64_t, std::uint32_t>>> got_pairs;
    for (const Contact& c : got.contacts)
      if (c.dynamic_part != kNoDynamicPart)
        got_pairs[c.dynamic_part].insert({c.environment_triangle, c.object_triangle});
    for (const auto& part : overlay.parts()) {
      const auto cgal = dynamic_pairs_by_cgal(overlay, part.id, flying.object(), pose);
      if (!cgal.empty() || got_pairs.count(part.id)) {
        EXPECT_EQ(got_pairs[part.id], cgal) << "dynamic part " << part.id;
      }
    }
  }
}

void check_poses(FlyingObject& flying, const DynamicObstacles& overlay, Random& random, int count,
                 Tally& tally, bool check_pairs = false) {
  const ReferenceCollider reference(reference_world(overlay), flying.object());
  for (int i = 0; i < count; ++i) {
    // Half the poses near a dynamic part, where contacts are.
    Pose pose = random_pose(random, 0.05, 0.95);
    if (i % 2 == 0 && overlay.size() > 0) {
      const auto& part = overlay.parts()[random.below(overlay.size())];
      for (int a = 0; a < 3; ++a)
        pose.translation[a] = part.pose.translation[a] + random.uniform(-0.12, 0.12);
    }
    check_pose(flying, reference, overlay, pose, tally, check_pairs);
  }
}

std::shared_ptr<const ObjectModel> part_model(std::uint64_t triangles, double size,
                                              std::uint64_t seed) {
  return std::make_shared<const ObjectModel>(shape(triangles, size, seed));
}

TEST(DynamicObstacles, AnswersEqualTheReferenceThroughInsertMoveRemoveHideShow) {
  auto overlay = std::make_shared<DynamicObstacles>(scene().index);
  FlyingObject flying(scene().index, shape(116, 0.12, 7));
  flying.set_obstacles(overlay);
  Random random(11);
  Tally tally;
  check_poses(flying, *overlay, random, 40, tally);  // no part: the static scene alone
  std::vector<DynamicPartId> ids;
  for (int k = 0; k < 6; ++k)
    ids.push_back(overlay->insert(part_model(k % 2 ? 300 : 116, 0.15, 20 + k),
                                  random_pose(random, 0.15, 0.85), "dynamic" + std::to_string(k)));
  check_poses(flying, *overlay, random, 60, tally, true);
  overlay->hide_part(1);
  overlay->hide_part(4);
  check_poses(flying, *overlay, random, 60, tally);
  for (int k = 0; k < 3; ++k) overlay->move(ids[k], random_pose(random, 0.15, 0.85));
  overlay->remove(ids[4]);
  check_poses(flying, *overlay, random, 60, tally, true);
  overlay->show_part(1);
  overlay->hide_part(6);  // the open sheet
  ids.push_back(overlay->insert(part_model(116, 0.4, 3), random_pose(random, 0.3, 0.7), "big"));
  // Beyond the index's mesh box (its top is the solids' top, z = 0.89), and straddling it.
  ids.push_back(
      overlay->insert(part_model(300, 0.15, 4), Pose{{0.5, 0.5, 1.02}, {1, 0, 0, 0}}, "above"));
  ids.push_back(overlay->insert(part_model(116, 0.15, 5), Pose{{0.45, 0.2, 0.9}, {1, 0, 0, 0}},
                                "straddling"));
  check_poses(flying, *overlay, random, 80, tally, true);
  {
    // Rising through the mesh box's top into the part above it: the step's box straddles the
    // mesh box, whose free boxes stop at its top (a free box once missed the part there).
    const ReferenceCollider reference(reference_world(*overlay), flying.object());
    for (double z = 0.8; z < 1.0; z += 0.004)
      check_pose(flying, reference, *overlay, Pose{{0.47, 0.52, z}, {1, 0, 0, 0}}, tally, false);
  }
  EXPECT_EQ(tally.wrong, 0);
  EXPECT_GT(tally.touching, 40);
  EXPECT_GT(tally.poses - tally.touching, 40);
  // Ids are never reused.
  EXPECT_EQ(ids.back(), 9u);
  EXPECT_THROW(overlay->move(ids[4], Pose{}), InputError);
  EXPECT_THROW(overlay->hide_part(7), InputError);
}

// The distance query sees the dynamic parts and not the hidden ones: against CGAL's distance
// over every triangle pair of the visible world (reference_world), on a coherent flight
// through inserts, moves and hides.
TEST(DynamicObstacles, DistancesAreTheVisibleWorldsExactDistance) {
  using Exact = CGAL::Exact_predicates_exact_constructions_kernel;
  auto overlay = std::make_shared<DynamicObstacles>(scene().index);
  const TriangleSoup object = shape(116, 0.06, 7);
  FlyingObject flying(scene().index, object);
  flying.set_obstacles(overlay);
  Random random(29);
  const auto exact = [](const std::array<Vec3, 3>& t) {
    return Exact::Triangle_3({t[0][0], t[0][1], t[0][2]}, {t[1][0], t[1][1], t[1][2]}, {t[2][0], t[2][1], t[2][2]});
  };
  int apart = 0, on_dynamic = 0;
  std::vector<DynamicPartId> ids;
  for (int round = 0; round < 4; ++round) {
    if (round == 1)
      for (int k = 0; k < 4; ++k) ids.push_back(overlay->insert(part_model(116, 0.15, 40 + k), random_pose(random, 0.15, 0.85)));
    if (round == 2) overlay->hide_part(0), overlay->hide_part(4), overlay->move(ids[0], random_pose(random, 0.15, 0.85));
    if (round == 3) overlay->remove(ids[1]), overlay->show_part(0);
    const TriangleSoup world = reference_world(*overlay);
    std::vector<Exact::Triangle_3> environment;
    for (std::size_t t = 0; t < world.triangle_count(); ++t) environment.push_back(exact(world.corners(t)));
    // Beside the first dynamic part once there is one (its closest triangles are then often
    // the part's), else anywhere.
    Pose start = random_pose(random, 0.1, 0.9);
    if (!ids.empty()) {
      start.translation = overlay->find(ids[0])->pose.translation;
      start.translation[1] += 0.13;
    }
    for (int i = 0; i < 6; ++i) {
      Pose pose = start;
      pose.translation[0] += 0.01 * i;
      const DistanceResult got = flying.distance(pose);
      if (got.separation != Separation::apart) continue;
      ++apart;
      on_dynamic += got.closest.dynamic_part != 0;
      // CGAL's double kernel picks the pairs near the least distance (its error is far below the
      // 1 % margin); the exact kernel measures those.
      std::vector<std::array<Vec3, 3>> placed(object.triangle_count());
      std::vector<double> inexact(environment.size() * placed.size());
      double least_inexact = std::numeric_limits<double>::infinity();
      for (std::size_t o = 0; o < placed.size(); ++o) {
        placed[o] = object.corners(o);
        for (Vec3& v : placed[o]) v = apply_pose(pose, v);
        const auto& q = placed[o];
        const K::Triangle_3 moved({q[0][0], q[0][1], q[0][2]}, {q[1][0], q[1][1], q[1][2]}, {q[2][0], q[2][1], q[2][2]});
        for (std::size_t e = 0; e < environment.size(); ++e) {
          const auto& w = world.corners(e);
          const K::Triangle_3 fixed({w[0][0], w[0][1], w[0][2]}, {w[1][0], w[1][1], w[1][2]}, {w[2][0], w[2][1], w[2][2]});
          inexact[o * environment.size() + e] = CGAL::squared_distance(fixed, moved);
          least_inexact = std::min(least_inexact, inexact[o * environment.size() + e]);
        }
      }
      Exact::FT least = -1;
      for (std::size_t o = 0; o < placed.size(); ++o)
        for (std::size_t e = 0; e < environment.size(); ++e)
          if (inexact[o * environment.size() + e] <= 1.01 * least_inexact) {
            const Exact::FT d = CGAL::squared_distance(environment[e], exact(placed[o]));
            if (least < 0 || d < least) least = d;
          }
      EXPECT_LE(Exact::FT(got.lower_bound) * Exact::FT(got.lower_bound), least) << "round " << round << " pose " << i;
      EXPECT_GE(Exact::FT(got.upper_bound) * Exact::FT(got.upper_bound), least) << "round " << round << " pose " << i;
      if (got.closest.dynamic_part != 0) {
        EXPECT_EQ(got.closest.environment_part, Contact::kDynamicPart);
        EXPECT_NE(overlay->find(got.closest.dynamic_part), nullptr);
      } else {
        EXPECT_FALSE(overlay->hidden(got.closest.environment_part));
      }
    }
  }
  EXPECT_GT(apart, 10);
  EXPECT_GT(on_dynamic, 0);  // some closest pairs lie on the dynamic parts
}

TEST(DynamicObstacles, ContainmentBothWaysAndHiddenSolids) {
  auto overlay = std::make_shared<DynamicObstacles>(scene().index);
  FlyingObject small(scene().index, shape(116, 0.04, 1));
  FlyingObject large(scene().index, shape(116, 0.3, 1));
  small.set_obstacles(overlay);
  large.set_obstacles(overlay);
  // A big closed dynamic sphere around the small object, a small one inside the large object.
  const DynamicPartId big =
      overlay->insert(part_model(116, 0.2, 1), Pose{{0.5, 0.25, 0.75}, {1, 0, 0, 0}}, "big");
  const DynamicPartId tiny =
      overlay->insert(part_model(116, 0.03, 1), Pose{{0.5, 0.75, 0.3}, {1, 0, 0, 0}}, "tiny");
  QueryResult in = small.query(Pose{{0.5, 0.25, 0.75}, {1, 0, 0, 0}});
  EXPECT_EQ(in.containment, Containment::object_inside_obstacle);
  EXPECT_EQ(in.containing_dynamic_part, big);
  QueryResult holds = large.query(Pose{{0.5, 0.75, 0.3}, {1, 0, 0, 0}});
  EXPECT_EQ(holds.containment, Containment::obstacle_inside_object);
  EXPECT_EQ(holds.containing_dynamic_part, tiny);
  // Inside the static solid 4 (centred at 0.5, 0.5, 0.5): collides until it is hidden.
  const Pose centre{{0.5, 0.5, 0.5}, {1, 0, 0, 0}};
  EXPECT_TRUE(small.query(centre).collides);
  overlay->hide_part(4);
  EXPECT_FALSE(small.query(centre).collides);
  overlay->show_part(4);
  EXPECT_TRUE(small.query(centre).collides);
  Random random(5);
  Tally tally;
  check_poses(small, *overlay, random, 30, tally);
  check_poses(large, *overlay, random, 30, tally);
  EXPECT_EQ(tally.wrong, 0);
}

TEST(DynamicObstacles, APartInsertedIntoTheFreeBoxIsSeenOnTheNextStep) {
  auto overlay = std::make_shared<DynamicObstacles>(scene().index);
  FlyingObject flying(scene().index, shape(116, 0.05, 1));
  flying.set_obstacles(overlay);
  // Free space between the solids: small steps until the object sits in a free box.
  Pose pose{{0.47, 0.2, 0.72}, {1, 0, 0, 0}};
  QueryResult result;
  bool in_free_box = false;
  for (int i = 0; i < 40 && !in_free_box; ++i) {
    pose.translation[0] += 0.001;
    flying.query(pose, {}, result);
    ASSERT_FALSE(result.collides);
    in_free_box = result.counters.in_free_box;
  }
  ASSERT_TRUE(in_free_box);
  overlay->insert(
      part_model(116, 0.05, 2),
      Pose{{pose.translation[0] + 0.02, pose.translation[1], pose.translation[2]}, {1, 0, 0, 0}});
  flying.query(pose, {}, result);
  EXPECT_TRUE(result.collides);
  EXPECT_FALSE(result.counters.in_free_box);
  ASSERT_FALSE(result.contacts.empty());
  EXPECT_NE(result.contacts[0].dynamic_part, kNoDynamicPart);
  // The contact's geometry is the dynamic triangle's.
  EXPECT_NE(flying.contact_geometry(result.contacts[0]).shape, geometry::ContactShape::none);
  // The distance query decides touching with the overlay: 0, at the dynamic contact.
  const DistanceResult touching = flying.distance(pose);
  EXPECT_EQ(touching.distance, 0.0);
  EXPECT_EQ(touching.closest.environment_part, Contact::kDynamicPart);
}

// Steps of 0.001 along x from `pose` until the object sits in a free box; false if it never does.
bool settle_in_free_box(FlyingObject& flying, Pose& pose) {
  QueryResult result;
  for (int i = 0; i < 40; ++i) {
    pose.translation[0] += 0.001;
    flying.query(pose, {}, result);
    if (result.collides) return false;
    if (result.counters.in_free_box) return true;
  }
  return false;
}

TEST(DynamicObstacles, TheFreeBoxSurvivesFarChangesOnly) {
  auto overlay = std::make_shared<DynamicObstacles>(scene().index);
  FlyingObject flying(scene().index, shape(116, 0.05, 1));
  flying.set_obstacles(overlay);
  Pose pose{{0.47, 0.2, 0.72}, {1, 0, 0, 0}};
  ASSERT_TRUE(settle_in_free_box(flying, pose));
  // Far away: the free box stays.
  const DynamicPartId far =
      overlay->insert(part_model(116, 0.05, 2), Pose{{0.9, 0.9, 0.1}, {1, 0, 0, 0}});
  EXPECT_TRUE(flying.query(pose).counters.in_free_box);
  overlay->move(far, Pose{{0.85, 0.9, 0.1}, {1, 0, 0, 0}});
  EXPECT_TRUE(flying.query(pose).counters.in_free_box);
  // Near, not touching (2 thousandths apart; the free box reaches beyond the object's box by
  // at least an eighth of its extent): the free box goes, the answer is still free.
  overlay->insert(
      part_model(116, 0.01, 3),
      Pose{{pose.translation[0] + 0.032, pose.translation[1], pose.translation[2]}, {1, 0, 0, 0}});
  const QueryResult near = flying.query(pose);
  EXPECT_FALSE(near.counters.in_free_box);
  EXPECT_FALSE(near.collides);
  // Inside solid 4 while it is hidden: free, in a free box; shown again, the next step collides.
  Pose inside{{0.47, 0.5, 0.5}, {1, 0, 0, 0}};
  overlay->hide_part(4);
  FlyingObject small(scene().index, shape(116, 0.02, 1));
  small.set_obstacles(overlay);
  ASSERT_TRUE(settle_in_free_box(small, inside));
  overlay->show_part(4);
  const QueryResult shown = small.query(inside);
  EXPECT_TRUE(shown.collides);
  EXPECT_EQ(shown.containment, Containment::object_inside_obstacle);
}

TEST(DynamicObstacles, SolidShapesSweptMotionAndOtherAccuracies) {
  // Hull, box and swept answers with dynamic parts are those of the same shapes on the static
  // index plus the parts: a superset of the mesh's contacts (never missing one).
  auto overlay = std::make_shared<DynamicObstacles>(scene().index);
  Random random(3);
  for (int k = 0; k < 8; ++k)
    overlay->insert(part_model(116, 0.12, 40 + k), random_pose(random, 0.15, 0.85));
  FlyingObject mesh(scene().index, shape(300, 0.12, 9)), solid(scene().index, shape(300, 0.12, 9));
  mesh.set_obstacles(overlay);
  solid.set_obstacles(overlay);
  int dynamic_hits = 0;
  for (int i = 0; i < 150; ++i) {
    const Pose pose = random_pose(random, 0.1, 0.9);
    const QueryResult exact = mesh.query(pose);
    for (const ObjectShape shape : {ObjectShape::hull, ObjectShape::box}) {
      QueryOptions options;
      options.shape = shape;
      const QueryResult coarse = solid.query(pose, options);
      EXPECT_TRUE(coarse.collides || !exact.collides)
          << "shape " << int(shape) << " missed a collision, step " << i;
    }
    QueryOptions near;
    near.accuracy = geometry::Accuracy::within(0.01);
    const QueryResult within = solid.query(pose, near);
    EXPECT_TRUE(within.collides || !exact.collides) << "clearance missed a collision, step " << i;
    dynamic_hits += !exact.contacts.empty() && exact.contacts[0].dynamic_part != kNoDynamicPart;
  }
  EXPECT_GT(dynamic_hits, 2);
}

TEST(DynamicObstacles, AGroupsObjectsAnswerAsLoneObjects) {
  auto overlay = std::make_shared<DynamicObstacles>(scene().index);
  Random random(31);
  for (int k = 0; k < 8; ++k)
    overlay->insert(part_model(116, 0.15, 80 + k), random_pose(random, 0.15, 0.85));
  overlay->hide_part(0);
  const std::vector<std::shared_ptr<const ObjectModel>> models = {part_model(116, 0.12, 7),
                                                                  part_model(300, 0.12, 8)};
  ObjectGroup group(scene().index, models);
  group.set_obstacles(overlay);
  FlyingObject a(scene().index, models[0]), b(scene().index, models[1]);
  a.set_obstacles(overlay);
  b.set_obstacles(overlay);
  for (int i = 0; i < 100; ++i) {
    const std::vector<Pose> poses = {random_pose(random, 0.1, 0.9), random_pose(random, 0.1, 0.9)};
    const GroupResult got = group.step(poses);
    EXPECT_EQ(got.environment[0].contacts, a.query(poses[0]).contacts);
    EXPECT_EQ(got.environment[1].contacts, b.query(poses[1]).contacts);
  }
  EXPECT_THROW(ObjectGroup(nullptr, models).set_obstacles(overlay), InputError);
}

TEST(DynamicObstacles, ObjectsOnSeveralThreadsShareOneOverlay) {
  auto overlay = std::make_shared<DynamicObstacles>(scene().index);
  Random random(41);
  for (int k = 0; k < 50; ++k)
    overlay->insert(part_model(116, 0.08, 90 + k % 5), random_pose(random, 0.1, 0.9));
  overlay->hide_part(2);
  std::vector<Pose> poses;
  for (int i = 0; i < 400; ++i) poses.push_back(random_pose(random, 0.05, 0.95));
  const auto model = part_model(116, 0.1, 7);
  auto answers = [&](std::size_t begin, std::size_t end) {
    FlyingObject flying(scene().index, model);
    flying.set_obstacles(overlay);
    std::vector<std::vector<Contact>> found;
    QueryOptions options;
    options.mode = QueryMode::all_contacts;
    for (std::size_t i = begin; i < end; ++i)
      found.push_back(flying.query(poses[i], options).contacts);
    return found;
  };
  const auto expected = answers(0, poses.size());
  std::vector<std::vector<std::vector<Contact>>> got(4);
  std::vector<std::thread> threads;
  for (std::size_t t = 0; t < 4; ++t)
    threads.emplace_back([&, t] { got[t] = answers(t * 100, t * 100 + 100); });
  for (auto& thread : threads) thread.join();
  for (std::size_t t = 0; t < 4; ++t)
    for (std::size_t i = 0; i < 100; ++i) EXPECT_EQ(got[t][i], expected[t * 100 + i]);
}

TEST(DynamicObstacles, SaveAndLoadGiveTheSameAnswers) {
  auto overlay = std::make_shared<DynamicObstacles>(scene().index);
  Random random(21);
  for (int k = 0; k < 5; ++k)
    overlay->insert(part_model(k % 2 ? 300 : 116, 0.15, 60 + k), random_pose(random, 0.15, 0.85),
                    "part with spaces " + std::to_string(k));
  overlay->remove(2);
  overlay->hide_part(3);
  const fs::path path = scene().folder / "overlay.tpo";
  overlay->save(path);
  auto loaded = std::make_shared<DynamicObstacles>(DynamicObstacles::load(scene().index, path));
  ASSERT_EQ(loaded->size(), overlay->size());
  EXPECT_EQ(loaded->hidden_parts(), overlay->hidden_parts());
  for (const auto& part : overlay->parts()) {
    const auto* other = loaded->find(part.id);
    ASSERT_NE(other, nullptr);
    EXPECT_EQ(other->name, part.name);
    EXPECT_EQ(other->pose.translation, part.pose.translation);
    EXPECT_EQ(other->pose.rotation, part.pose.rotation);
    EXPECT_EQ(other->model->mesh.vertices, part.model->mesh.vertices);
    EXPECT_EQ(other->model->mesh.triangles, part.model->mesh.triangles);
  }
  EXPECT_EQ(loaded->insert(part_model(116, 0.1, 1), Pose{{0.5, 0.5, 0.5}, {1, 0, 0, 0}}), 6u);
  loaded->remove(6);
  FlyingObject a(scene().index, shape(116, 0.12, 7)), b(scene().index, shape(116, 0.12, 7));
  a.set_obstacles(overlay);
  b.set_obstacles(loaded);
  for (int i = 0; i < 200; ++i) {
    const Pose pose = random_pose(random, 0.05, 0.95);
    QueryOptions options;
    options.mode = QueryMode::all_contacts;
    const QueryResult x = a.query(pose, options), y = b.query(pose, options);
    EXPECT_EQ(x.collides, y.collides);
    EXPECT_EQ(x.contacts, y.contacts);
    EXPECT_EQ(x.containment, y.containment);
  }
}

TEST(DynamicObstacles, DamagedFilesFailWithAFormatErrorNamingTheFile) {
  auto overlay = std::make_shared<DynamicObstacles>(scene().index);
  Random random(4);
  overlay->insert(part_model(116, 0.15, 1), random_pose(random, 0.2, 0.8), "a");
  overlay->hide_part(2);
  const fs::path path = scene().folder / "good.tpo";
  overlay->save(path);
  std::string text;
  {
    std::ifstream in(path, std::ios::binary);
    text.assign(std::istreambuf_iterator<char>(in), {});
  }
  const fs::path bad = scene().folder / "bad.tpo";
  auto expect_format_error = [&](const std::string& content, const std::string& what) {
    {
      std::ofstream out(bad, std::ios::binary | std::ios::trunc);
      out << content;
    }
    try {
      DynamicObstacles::load(scene().index, bad);
      ADD_FAILURE() << what << ": loaded";
    } catch (const FormatError& e) {
      EXPECT_NE(std::string(e.what()).find(bad.string()), std::string::npos) << e.what();
    }
  };
  // Cut anywhere before the last line's end.
  for (std::size_t cut = 0; cut + 1 < text.size(); cut += 1 + cut / 7)
    expect_format_error(text.substr(0, cut), "cut at " + std::to_string(cut));
  auto replaced = [&](const std::string& from, const std::string& to) {
    std::string copy = text;
    copy.replace(copy.find(from), from.size(), to);
    return copy;
  };
  expect_format_error(replaced("tetrapage-dynamic-obstacles 1", "tetrapage-dynamic-obstacles 2"),
                      "version");
  expect_format_error(replaced("hidden 1 2", "hidden 1 99"), "hidden part beyond the index");
  expect_format_error(replaced("mesh ", "mesh 4000000000"), "huge count");
  expect_format_error(replaced("\nf ", "\nf 99999 "), "vertex out of range");
  expect_format_error(replaced("pose ", "pose nan "), "not a pose");
  expect_format_error(text + "garbage\n", "trailing garbage");
  expect_format_error(std::string("\x00\xff\x10", 3), "binary");
  EXPECT_THROW(DynamicObstacles::load(scene().index, scene().folder / "missing.tpo"), FormatError);
}

// save writes under a temporary name renamed into place, and replaces nothing but a regular
// file that is empty or an overlay: not the index it was opened on, not another index, not what
// a link points to, never a FIFO or a device.
TEST(DynamicObstacles, SaveReplacesNothingButAnOverlay) {
  auto overlay = std::make_shared<DynamicObstacles>(scene().index);
  Random random(9);
  overlay->insert(part_model(116, 0.15, 2), random_pose(random, 0.2, 0.8), "a");
  const fs::path folder = scene().folder / "save-rules";
  fs::remove_all(folder);
  fs::create_directories(folder);
  auto bytes_of = [](const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  const fs::path index_file = scene().folder / "scene.tpi";
  const std::string index_bytes = bytes_of(index_file);
  EXPECT_THROW(overlay->save(index_file), InputError);
  fs::copy_file(index_file, folder / "other.tpi");
  EXPECT_THROW(overlay->save(folder / "other.tpi"), InputError);
  fs::create_symlink(folder / "other.tpi", folder / "link.tpo");
  EXPECT_THROW(overlay->save(folder / "link.tpo"), InputError);
  ASSERT_EQ(::mkfifo((folder / "fifo.tpo").c_str(), 0600), 0);
  EXPECT_THROW(overlay->save(folder / "fifo.tpo"), InputError);
  EXPECT_THROW(overlay->save("/dev/full"), InputError);
  EXPECT_EQ(bytes_of(index_file), index_bytes);
  EXPECT_EQ(bytes_of(folder / "other.tpi"), index_bytes);
  struct stat status {};
  ASSERT_EQ(::stat("/dev/full", &status), 0);
  EXPECT_TRUE(S_ISCHR(status.st_mode));
  // An overlay is replaced; a failed save leaves no temporary.
  overlay->save(folder / "v.tpo");
  overlay->insert(part_model(116, 0.15, 3), random_pose(random, 0.2, 0.8), "b");
  overlay->save(folder / "v.tpo");
  EXPECT_EQ(DynamicObstacles::load(scene().index, folder / "v.tpo").size(), 2u);
  for (const auto& entry : fs::directory_iterator(folder))
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
  // The C API says the same, with the reason.
  tetrapage_index* index = nullptr;
  ASSERT_EQ(tetrapage_open(index_file.c_str(), TETRAPAGE_DEFAULT_BUDGET_BYTES, &index),
            TETRAPAGE_OK);
  tetrapage_obstacles* obstacles = nullptr;
  ASSERT_EQ(tetrapage_obstacles_create(index, &obstacles), TETRAPAGE_OK);
  EXPECT_EQ(tetrapage_obstacles_save(obstacles, index_file.c_str()), TETRAPAGE_ERROR_INPUT);
  EXPECT_EQ(tetrapage_obstacles_save(obstacles, (folder / "other.tpi").c_str()),
            TETRAPAGE_ERROR_INPUT);
  EXPECT_EQ(tetrapage_obstacles_save(obstacles, "/dev/full"), TETRAPAGE_ERROR_INPUT);
  EXPECT_EQ(bytes_of(index_file), index_bytes);
  tetrapage_obstacles_destroy(obstacles);
  tetrapage_close(index);
}

// A name save could not write back on a line of its own is refused when the part is inserted.
TEST(DynamicObstacles, NamesThatCannotRoundTripAreRefused) {
  DynamicObstacles overlay(scene().index);
  Random random(10);
  const Pose pose = random_pose(random, 0.2, 0.8);
  EXPECT_THROW(overlay.insert(part_model(116, 0.15, 2), pose, "two\nlines"), InputError);
  EXPECT_THROW(
      overlay.insert(part_model(116, 0.15, 2), pose, std::string(kMaxObstacleNameBytes + 1, 'n')),
      InputError);
  EXPECT_EQ(overlay.size(), 0u);
  const std::string longest(kMaxObstacleNameBytes, 'n');
  overlay.insert(part_model(116, 0.15, 2), pose, longest);
  overlay.insert(part_model(116, 0.15, 3), pose, "tab\tand\rreturn");
  const fs::path path = scene().folder / "names.tpo";
  overlay.save(path);
  const DynamicObstacles loaded = DynamicObstacles::load(scene().index, path);
  ASSERT_EQ(loaded.size(), 2u);
  EXPECT_EQ(loaded.find(1)->name, longest);
  EXPECT_EQ(loaded.find(2)->name, "tab\tand\rreturn");
}

// Loading reads bounded lines from regular files only, and names the line at fault with a few
// dozen characters of it, whatever the file holds.
TEST(DynamicObstacles, LoadIsBoundedAndNamesTheLineAtFault) {
  EXPECT_THROW(DynamicObstacles::load(scene().index, "/dev/zero"), IoError);
  const fs::path folder = scene().folder;
  auto load_error = [&](const std::string& content) -> std::string {
    {
      std::ofstream out(folder / "hostile.tpo", std::ios::binary | std::ios::trunc);
      out << content;
    }
    try {
      DynamicObstacles::load(scene().index, folder / "hostile.tpo");
    } catch (const FormatError& e) {
      return e.what();
    }
    return "loaded";
  };
  const std::string long_line = load_error(std::string(8u << 20, 'x'));
  EXPECT_NE(long_line.find("line 1: the line is longer than"), std::string::npos)
      << long_line.substr(0, 200);
  EXPECT_LT(long_line.size(), 300u);
  const std::string binary =
      load_error("tetrapage-dynamic-obstacles \x01\x02" + std::string(500, '\xff') + "\n");
  EXPECT_LT(binary.size(), 300u) << binary;
  EXPECT_NE(binary.find("\\x01"), std::string::npos) << binary;
  // A non-finite coordinate or a vertex out of range: the line that holds it.
  DynamicObstacles overlay(scene().index);
  Random random(11);
  overlay.insert(part_model(116, 0.15, 2), random_pose(random, 0.2, 0.8), "a");
  overlay.save(folder / "fine.tpo");
  std::ifstream in(folder / "fine.tpo", std::ios::binary);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  auto joined = [](const std::vector<std::string>& list) {
    std::string text;
    for (const auto& line : list) text += line + "\n";
    return text;
  };
  for (const char* kind : {"v ", "f "}) {
    std::size_t at = 0;
    while (lines[at].rfind(kind, 0) != 0) ++at;
    at += 2;  // the third of its kind
    std::vector<std::string> damaged = lines;
    damaged[at] = kind == std::string("v ") ? "v 0 nan 0" : "f 0 1 4000000";
    const std::string message = load_error(joined(damaged));
    EXPECT_NE(message.find("line " + std::to_string(at + 1) + ":"), std::string::npos)
        << kind << message;
  }
  // A pose insert refuses (not unit): the pose's line.
  std::size_t pose_line = 0;
  while (lines[pose_line].rfind("pose ", 0) != 0) ++pose_line;
  std::vector<std::string> damaged = lines;
  damaged[pose_line] = "pose 0 0 0 2 0 0 0";
  const std::string message = load_error(joined(damaged));
  EXPECT_NE(message.find("line " + std::to_string(pose_line + 1) + ":"), std::string::npos)
      << message;
}

TEST(DynamicObstacles, TheCApiAnswersAsCxx) {
  tetrapage_index* index = nullptr;
  ASSERT_EQ(tetrapage_open((scene().folder / "scene.tpi").c_str(), TETRAPAGE_DEFAULT_BUDGET_BYTES,
                           &index),
            TETRAPAGE_OK);
  const TriangleSoup object = shape(116, 0.12, 7);
  tetrapage_object* flying = nullptr;
  ASSERT_EQ(tetrapage_object_create(index, &object.vertices[0][0], object.vertices.size(),
                                    &object.triangles[0][0], object.triangles.size(), &flying),
            TETRAPAGE_OK);
  tetrapage_obstacles* obstacles = nullptr;
  ASSERT_EQ(tetrapage_obstacles_create(index, &obstacles), TETRAPAGE_OK);
  auto overlay = std::make_shared<DynamicObstacles>(scene().index);
  FlyingObject cxx(scene().index, object);
  cxx.set_obstacles(overlay);
  ASSERT_EQ(tetrapage_object_set_obstacles(flying, obstacles), TETRAPAGE_OK);
  Random random(8);
  for (int k = 0; k < 6; ++k) {
    const TriangleSoup part = shape(116, 0.15, 70 + k);
    const Pose pose = random_pose(random, 0.15, 0.85);
    const double p[7] = {pose.translation[0], pose.translation[1], pose.translation[2],
                         pose.rotation[0],    pose.rotation[1],    pose.rotation[2],
                         pose.rotation[3]};
    std::uint32_t id = 0;
    ASSERT_EQ(tetrapage_obstacles_insert(obstacles, &part.vertices[0][0], part.vertices.size(),
                                         &part.triangles[0][0], part.triangles.size(), p, "p", &id),
              TETRAPAGE_OK);
    EXPECT_EQ(id, overlay->insert(part, pose, "p"));
  }
  ASSERT_EQ(tetrapage_obstacles_hide_part(obstacles, 4, 1), TETRAPAGE_OK);
  overlay->hide_part(4);
  EXPECT_EQ(tetrapage_obstacles_hide_part(obstacles, 99, 1), TETRAPAGE_ERROR_INPUT);
  EXPECT_EQ(tetrapage_obstacles_remove(obstacles, 99), TETRAPAGE_ERROR_INPUT);
  int dynamic = 0;
  for (int i = 0; i < 100; ++i) {
    const Pose pose = random_pose(random, 0.1, 0.9);
    const double p[7] = {pose.translation[0], pose.translation[1], pose.translation[2],
                         pose.rotation[0],    pose.rotation[1],    pose.rotation[2],
                         pose.rotation[3]};
    int collides = 0;
    ASSERT_EQ(tetrapage_collide(flying, p, nullptr, &collides), TETRAPAGE_OK);
    const QueryResult expected = cxx.query(pose);
    EXPECT_EQ(collides != 0, expected.collides);
    tetrapage_hit hit{};
    std::size_t written = 0;
    ASSERT_EQ(tetrapage_get_hits(flying, &hit, 1, &written), TETRAPAGE_OK);
    ASSERT_EQ(written, expected.contacts.size());
    if (written == 1) {
      EXPECT_EQ(hit.dynamic_part, expected.contacts[0].dynamic_part);
      EXPECT_EQ(hit.environment_part == TETRAPAGE_DYNAMIC_PART, hit.dynamic_part != 0);
      EXPECT_EQ(hit.environment_triangle, expected.contacts[0].environment_triangle);
    }
    dynamic += written == 1 && hit.dynamic_part != 0;
  }
  EXPECT_GT(dynamic, 0);
  // A group of the one object answers the same with the overlay.
  tetrapage_group* group = nullptr;
  ASSERT_EQ(tetrapage_group_create(index, &flying, 1, &group), TETRAPAGE_OK);
  ASSERT_EQ(tetrapage_group_set_obstacles(group, obstacles), TETRAPAGE_OK);
  for (int i = 0; i < 50; ++i) {
    const Pose pose = random_pose(random, 0.1, 0.9);
    const double p[7] = {pose.translation[0], pose.translation[1], pose.translation[2],
                         pose.rotation[0],    pose.rotation[1],    pose.rotation[2],
                         pose.rotation[3]};
    std::size_t pairs = 0, written = 0;
    int collides = 0;
    ASSERT_EQ(tetrapage_group_step(group, p, 0, &pairs), TETRAPAGE_OK);
    ASSERT_EQ(tetrapage_group_environment(group, &collides, 1, &written), TETRAPAGE_OK);
    EXPECT_EQ(collides != 0, cxx.query(pose).collides);
  }
  EXPECT_EQ(tetrapage_group_destroy(group), TETRAPAGE_OK);
  const std::string path = (scene().folder / "capi.tpo").string();
  ASSERT_EQ(tetrapage_obstacles_save(obstacles, path.c_str()), TETRAPAGE_OK);
  tetrapage_obstacles* loaded = nullptr;
  ASSERT_EQ(tetrapage_obstacles_load(index, path.c_str(), &loaded), TETRAPAGE_OK);
  EXPECT_NE(loaded, nullptr);
  EXPECT_EQ(tetrapage_obstacles_destroy(loaded), TETRAPAGE_OK);
  EXPECT_EQ(tetrapage_obstacles_load(index, (path + ".missing").c_str(), &loaded),
            TETRAPAGE_ERROR_FORMAT);
  EXPECT_EQ(loaded, nullptr);
  EXPECT_EQ(tetrapage_object_set_obstacles(flying, nullptr), TETRAPAGE_OK);
  EXPECT_EQ(tetrapage_obstacles_destroy(obstacles), TETRAPAGE_OK);
  EXPECT_EQ(tetrapage_obstacles_destroy(obstacles), TETRAPAGE_ERROR_STALE_HANDLE);
  tetrapage_object_destroy(flying);
  tetrapage_close(index);
}

}  // namespace
}  // namespace tetrapage
