// Embree as the independent reference for point location and stabbing numbers, on coarse
// meshes that preprocess builds from small generated models:
// - the Embree scene lists each face once and reports exactly the faces a segment crosses
//   (CGAL's exact segment/triangle test over every face as the oracle);
// - check_locations counts a disagreement exactly where a locator is wrong by brute force
//   (CGAL's exact point-in-tet test over every tet): zero for the runtime's walk over random
//   and on-face/edge/vertex points, and every error of deliberately wrong locators;
// - the stabbing numbers of the walk and of Embree agree segment by segment, and both equal
//   the number of tets the segment meets (CGAL exact, brute force);
// - `tetrapage check-location` and `tetrapage inspect` print and exit as documented.

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "RunCli.h"
#include "tetrapage/formats/index/IndexReader.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/preprocess/Preprocess.h"
#include "tetrapage/runtime/geometry/PointTetrahedron.h"
#include "tetrapage/runtime/query/MeshWalk.h"
#include "tetrapage/tools/EmbreeMeshFaces.h"
#include "tetrapage/tools/LocationCheck.h"
#include "tetrapage/tools/MeshLibrary.h"
#include "tetrapage/tools/Random.h"
#include "tetrapage/tools/SceneGenerator.h"
#include "tetrapage/tools/StabbingNumbers.h"
#include "tetrapage/tools/TetrasGenerator.h"

namespace tetrapage {
namespace {

namespace fs = std::filesystem;
using Epick = CGAL::Exact_predicates_inexact_constructions_kernel;
using geometry::Point;

Epick::Point_3 to_cgal(const Vec3& p) { return {p[0], p[1], p[2]}; }

enum class Model { scene, tetras, far_tetras };

struct Indexed {
  fs::path index;
  TetMesh mesh;
  BoundingBox model_box;
};

// Generates a small model, preprocesses it (double coordinates) and reads its coarse mesh.
// far_tetras moves the model to 1e6 from the origin and shrinks it, so that Embree's floats
// keep only a few bits of each coordinate's offset from the box centre.
const Indexed& indexed(Model model) {
  static std::map<Model, Indexed> cache;
  if (auto it = cache.find(model); it != cache.end()) return it->second;
  const std::string name =
      model == Model::scene ? "scene" : (model == Model::tetras ? "tetras" : "far_tetras");
  // One folder per process (ctest runs test cases in parallel processes), removed at exit.
  struct Folder {
    fs::path path;
    ~Folder() {
      std::error_code ignored;
      fs::remove_all(path, ignored);
    }
  };
  static const Folder root{fs::path(TETRAPAGE_TEST_TMP) / "location" / std::to_string(getpid())};
  const fs::path folder = root.path / name;
  fs::remove_all(folder);
  fs::create_directories(folder);
  const fs::path input = folder / (name + ".ply");
  if (model == Model::scene) {
    static const MeshLibrary library = MeshLibrary::load_default();
    SceneOptions options;
    options.triangles = 20'000;
    options.seed = 3;
    MeshWriter writer(input);
    generate_scene(library, options, writer);
    writer.commit();
  } else {
    const fs::path raw = folder / "raw.ply";
    {
      TetrasOptions options;
      options.triangles = 4 * 1500;
      options.seed = 5;
      MeshWriter writer(model == Model::tetras ? input : raw);
      generate_tetras(options, writer);
      writer.commit();
    }
    if (model == Model::far_tetras) {
      TriangleSoup soup = read_mesh(raw);
      for (auto& v : soup.vertices)
        for (auto& c : v) c = 1e6 + 1e-2 * c;
      write_mesh(input, soup);
    }
  }
  PreprocessOptions options;
  options.region_triangles = 40;
  options.precision = StoredPrecision::float64;
  const fs::path index = folder / (name + ".tpi");
  preprocess({input}, index, options);
  const IndexReader reader(index);
  Indexed out{index, reader.read_mesh(), reader.header().bounds};
  return cache.emplace(model, std::move(out)).first->second;
}

std::string model_name(Model model) {
  return model == Model::scene ? "scene" : (model == Model::tetras ? "tetras" : "far_tetras");
}

// Brute force: every tet whose closed region holds p (CGAL, exact predicates).
std::vector<std::uint32_t> tets_holding(const TetMesh& mesh, const Point& p) {
  std::vector<std::uint32_t> out;
  const auto q = to_cgal(p);
  for (std::uint32_t t = 0; t < mesh.tet_count(); ++t) {
    const BoundingBox box = mesh.bounds(t);
    if (p[0] < box.lo[0] || p[0] > box.hi[0] || p[1] < box.lo[1] || p[1] > box.hi[1] ||
        p[2] < box.lo[2] || p[2] > box.hi[2])
      continue;
    const auto c = mesh.corners(t);
    const Epick::Tetrahedron_3 tet(to_cgal(c[0]), to_cgal(c[1]), to_cgal(c[2]), to_cgal(c[3]));
    if (!tet.has_on_unbounded_side(q)) out.push_back(t);
  }
  return out;
}

// Whether `answer` (a tet or no_neighbour) is a right answer for p, by brute force.
bool brute_force_right(const TetMesh& mesh, const Point& p, std::uint32_t answer) {
  const auto holding = tets_holding(mesh, p);
  if (answer == TetMesh::no_neighbour) return holding.empty();
  return std::find(holding.begin(), holding.end(), answer) != holding.end();
}

class LocationCheckTest : public ::testing::TestWithParam<Model> {};

TEST_P(LocationCheckTest, SceneListsEachFaceOnce) {
  const Indexed& model = indexed(GetParam());
  const EmbreeMeshFaces faces(model.mesh);
  std::map<std::pair<std::uint32_t, int>, int> seen;
  std::size_t hull = 0;
  for (const MeshFace& f : faces.faces()) {
    for (std::uint32_t t : {f.tet, f.other}) {
      if (t == TetMesh::no_neighbour) continue;
      // The face's vertices are the corners of t but one: the face opposite that corner.
      int opposite = -1, matches = 0;
      for (int k = 0; k < 4; ++k) {
        const std::uint32_t v = model.mesh.tets[t][k];
        if (std::find(f.vertices.begin(), f.vertices.end(), v) != f.vertices.end())
          ++matches;
        else
          opposite = k;
      }
      ASSERT_EQ(matches, 3);
      ++seen[{t, opposite}];
    }
    hull += f.other == TetMesh::no_neighbour ? 1 : 0;
  }
  EXPECT_EQ(seen.size(), 4 * model.mesh.tet_count());
  for (const auto& [key, count] : seen) EXPECT_EQ(count, 1) << "tet " << key.first << " face " << key.second;
  EXPECT_EQ(2 * faces.faces().size() - hull, 4 * model.mesh.tet_count());
}

TEST_P(LocationCheckTest, HitsAreTheFacesTheSegmentCrosses) {
  const Indexed& model = indexed(GetParam());
  const EmbreeMeshFaces faces(model.mesh);
  BoundingBox box;
  for (const auto& v : model.mesh.vertices) box.extend(v);
  Random random(11);
  std::vector<FaceHit> hits;
  std::size_t total = 0;
  for (int s = 0; s < 100; ++s) {
    Point a, b;
    for (int k = 0; k < 3; ++k) {
      a[k] = random.uniform(box.lo[k], box.hi[k]);
      b[k] = random.uniform(box.lo[k], box.hi[k]);
    }
    faces.hits(a, b, hits);
    std::vector<std::uint32_t> got;
    for (const FaceHit& h : hits) {
      got.push_back(h.face);
      EXPECT_GE(h.t, 0.f);
      EXPECT_LE(h.t, 1.f);
    }
    std::sort(got.begin(), got.end());
    std::vector<std::uint32_t> expected;
    const Epick::Segment_3 segment(to_cgal(a), to_cgal(b));
    for (std::uint32_t f = 0; f < faces.faces().size(); ++f) {
      const auto& v = faces.faces()[f].vertices;
      const Epick::Triangle_3 triangle(to_cgal(model.mesh.vertices[v[0]]),
                                       to_cgal(model.mesh.vertices[v[1]]),
                                       to_cgal(model.mesh.vertices[v[2]]));
      if (CGAL::do_intersect(segment, triangle)) expected.push_back(f);
    }
    EXPECT_EQ(got, expected) << "segment " << s;
    total += expected.size();
    // Stepping across them from a tet holding a ends in a tet holding b.
    const std::uint32_t start = locate_point(model.mesh, 0, a).tet;
    ASSERT_NE(start, TetMesh::no_neighbour);
    const FaceTrace trace = faces.trace(start, a, b);
    EXPECT_FALSE(trace.outside);
    EXPECT_EQ(trace.resyncs, 0u);
    ASSERT_EQ(trace.end_tets.size(), 1u);
    EXPECT_TRUE(brute_force_right(model.mesh, b, trace.end_tets[0]));
  }
  EXPECT_GT(total, 100u) << "segments should cross many faces";
}

// The check against brute force: it reports a disagreement exactly on the points where the
// locator's answer is wrong.
void expect_disagreements_are_errors(const EmbreeMeshFaces& faces, const LocationPointSet& set,
                                     const PointLocator& locator, const std::string& what,
                                     std::uint64_t* errors_out = nullptr) {
  const TetMesh& mesh = faces.mesh();
  LocationCheckOptions options;
  options.threads = 2;
  const LocationCheckSummary summary = check_locations(faces, set.points, locator, options);
  std::uint64_t errors = 0;
  std::vector<Point> wrong;
  for (const LocationPoint& p : set.points)
    if (!brute_force_right(mesh, p.point, locator(p.point, p.locator_start))) {
      ++errors;
      wrong.push_back(p.point);
    }
  EXPECT_EQ(summary.disagreements, errors) << what;
  ASSERT_EQ(summary.listed.size(), summary.disagreements) << what;
  // The listed points are the wrong ones, in order.
  for (std::size_t i = 0; i < summary.listed.size() && i < wrong.size(); ++i)
    EXPECT_EQ(summary.listed[i].point, wrong[i]) << what << ", disagreement " << i;
  std::uint64_t points = 0;
  for (const auto& kind : summary.by_kind) {
    EXPECT_EQ(kind.same_tet + kind.exact_ties + kind.outside + kind.disagreements, kind.points);
    points += kind.points;
  }
  EXPECT_EQ(points, set.points.size());
  if (errors_out) *errors_out = errors;
}

TEST_P(LocationCheckTest, RuntimeWalkAgreesWithEmbreeOnRandomAndBoundaryPoints) {
  const Indexed& model = indexed(GetParam());
  const EmbreeMeshFaces faces(model.mesh);
  LocationPointOptions options;
  options.points = 6000;
  options.seed = 21;
  const LocationPointSet set = make_location_points(model.mesh, options);
  // Every kind was produced (exact points on faces and edges may run short, not out), and
  // the boundary points are exactly where they claim to be.
  EXPECT_EQ(set.count[0], 3000u);
  EXPECT_EQ(set.count[3], 600u);
  for (std::size_t k = 0; k < kLocationPointKinds; ++k) EXPECT_GT(set.distinct[k], 1u) << k;
  std::printf("%s: %llu face points (%llu distinct) of %llu tried, %llu edge points (%llu distinct) of %llu tried\n",
              model_name(GetParam()).c_str(), (unsigned long long)set.count[1],
              (unsigned long long)set.distinct[1], (unsigned long long)set.attempts[1],
              (unsigned long long)set.count[2], (unsigned long long)set.distinct[2],
              (unsigned long long)set.attempts[2]);
  std::array<std::size_t, kLocationPointKinds> outside{};
  for (const LocationPoint& p : set.points) {
    const auto holding = tets_holding(model.mesh, p.point);
    if (holding.empty()) ++outside[std::size_t(p.kind)];
    if (p.kind != LocationPointKind::random) {
      EXPECT_FALSE(holding.empty());
      // A point on a face, edge or vertex lies on the boundary of each tet that holds it.
      for (std::uint32_t t : holding) {
        const auto c = model.mesh.corners(t);
        const Epick::Tetrahedron_3 tet(to_cgal(c[0]), to_cgal(c[1]), to_cgal(c[2]), to_cgal(c[3]));
        EXPECT_TRUE(tet.has_on_boundary(to_cgal(p.point))) << to_string(p.kind) << " point, tet " << t;
      }
    }
  }
  EXPECT_GT(outside[0], 0u) << "some random points should fall outside the mesh";

  LocationCheckOptions check_options;
  check_options.threads = 2;
  const LocationCheckSummary summary =
      check_locations(faces, set.points, runtime_locator(model.mesh), check_options);
  EXPECT_EQ(summary.disagreements, 0u);
  for (const auto& d : summary.listed)
    ADD_FAILURE() << to_string(d.kind) << " point (" << d.point[0] << ", " << d.point[1] << ", "
                  << d.point[2] << "): " << d.reason;
  // Outside for both, or (within float error of the hull) a tie the exact predicates decided.
  EXPECT_LE(summary.by_kind[0].outside, outside[0]);
  EXPECT_GE(summary.by_kind[0].outside + summary.by_kind[0].exact_ties, outside[0]);
  // Points on vertices and edges are held by several tets: the exact tie rule decides.
  EXPECT_GT(summary.by_kind[std::size_t(LocationPointKind::on_vertex)].exact_ties, 0u);
  // The same result from one thread.
  LocationCheckOptions one_thread;
  one_thread.threads = 1;
  const LocationCheckSummary again =
      check_locations(faces, set.points, runtime_locator(model.mesh), one_thread);
  for (std::size_t k = 0; k < kLocationPointKinds; ++k) {
    EXPECT_EQ(again.by_kind[k].same_tet, summary.by_kind[k].same_tet);
    EXPECT_EQ(again.by_kind[k].exact_ties, summary.by_kind[k].exact_ties);
  }
}

TEST_P(LocationCheckTest, WrongLocatorsAreCaught) {
  const Indexed& model = indexed(GetParam());
  const TetMesh& mesh = model.mesh;
  const EmbreeMeshFaces faces(mesh);
  LocationPointOptions options;
  options.points = 3000;
  options.seed = 33;
  const LocationPointSet set = make_location_points(mesh, options);
  const PointLocator right = runtime_locator(mesh);
  BoundingBox box;
  for (const auto& v : mesh.vertices) box.extend(v);

  std::uint64_t errors = 0;
  expect_disagreements_are_errors(faces, set, right, "runtime walk", &errors);
  EXPECT_EQ(errors, 0u);

  // A neighbour of the right tet: right only when the point lies on their shared face.
  const PointLocator neighbour = [&](const Point& p, std::uint32_t start) {
    const std::uint32_t t = right(p, start);
    if (t == TetMesh::no_neighbour) return t;
    for (std::uint32_t n : mesh.neighbours[t])
      if (n != TetMesh::no_neighbour) return n;
    return t;
  };
  expect_disagreements_are_errors(faces, set, neighbour, "neighbour", &errors);
  EXPECT_GT(errors, set.points.size() / 4);

  // "Outside" near the hull: wrong for every point of the mesh within 2% of its box.
  const PointLocator shy = [&](const Point& p, std::uint32_t start) {
    for (int k = 0; k < 3; ++k) {
      const double margin = 0.02 * (box.hi[k] - box.lo[k]);
      if (p[k] < box.lo[k] + margin || p[k] > box.hi[k] - margin) return TetMesh::no_neighbour;
    }
    return right(p, start);
  };
  expect_disagreements_are_errors(faces, set, shy, "outside near the hull", &errors);
  EXPECT_GT(errors, 0u);

  // A tet for points outside the mesh (the start tet).
  const PointLocator grabby = [&](const Point& p, std::uint32_t start) {
    const std::uint32_t t = right(p, start);
    return t == TetMesh::no_neighbour ? start : t;
  };
  expect_disagreements_are_errors(faces, set, grabby, "inside for outside points", &errors);
  EXPECT_GT(errors, 0u);

  // Off by one tet index (sometimes right by chance, on a shared vertex or edge).
  const PointLocator shifted = [&](const Point& p, std::uint32_t start) {
    const std::uint32_t t = right(p, start);
    return t == TetMesh::no_neighbour ? t : std::uint32_t((t + 1) % mesh.tet_count());
  };
  expect_disagreements_are_errors(faces, set, shifted, "off by one", &errors);
  EXPECT_GT(errors, set.points.size() / 4);
}

// The number of tets the closed segment meets (CGAL exact, every tet).
std::uint64_t tets_met(const TetMesh& mesh, const Point& a, const Point& b) {
  const Epick::Segment_3 segment(to_cgal(a), to_cgal(b));
  std::uint64_t count = 0;
  for (std::uint32_t t = 0; t < mesh.tet_count(); ++t) {
    const auto c = mesh.corners(t);
    const Epick::Tetrahedron_3 tet(to_cgal(c[0]), to_cgal(c[1]), to_cgal(c[2]), to_cgal(c[3]));
    if (CGAL::do_intersect(segment, tet)) ++count;
  }
  return count;
}

TEST_P(LocationCheckTest, StabbingNumbersOfWalkAndEmbreeAgreeWithBruteForce) {
  const Indexed& model = indexed(GetParam());
  const EmbreeMeshFaces faces(model.mesh);
  StabbingOptions options;
  options.segments = 2000;
  options.seed = 7;
  const StabbingNumbers numbers = measure_stabbing_numbers(faces, model.model_box, options);
  EXPECT_EQ(numbers.segments, options.segments);
  EXPECT_EQ(numbers.differing, 0u);
  for (const auto& d : numbers.differences)
    ADD_FAILURE() << "walk " << d.walk_tets << " tets, Embree " << d.embree_tets;
  EXPECT_EQ(numbers.incomplete_walks, 0u);
  EXPECT_DOUBLE_EQ(numbers.walk, numbers.embree);
  EXPECT_GT(numbers.walk_tets_per_segment, 2.0);

  // The same segments (same seed, same draws) against brute force, for the first 60.
  Random random(options.seed);
  double sum = 0;
  const auto& box = model.model_box;
  for (int s = 0; s < 60; ++s) {
    Point a, b;
    for (int k = 0; k < 3; ++k) a[k] = random.uniform(box.lo[k], box.hi[k]);
    for (int k = 0; k < 3; ++k) b[k] = random.uniform(box.lo[k], box.hi[k]);
    const SegmentWalk walk = walk_segment(model.mesh, 0, a, b);
    EXPECT_EQ(walk.tets.size(), tets_met(model.mesh, a, b)) << "segment " << s;
    std::vector<FaceHit> hits;
    faces.hits(a, b, hits);
    EXPECT_EQ(hits.size() + 1, walk.tets.size()) << "segment " << s;
    double length = 0;
    for (int k = 0; k < 3; ++k) length += (b[k] - a[k]) * (b[k] - a[k]);
    sum += double(walk.tets.size()) / std::sqrt(length);
  }
  // The reported mean over 2000 segments is a mean of these per-segment figures.
  StabbingOptions first;
  first.segments = 60;
  first.seed = options.seed;
  EXPECT_NEAR(measure_stabbing_numbers(faces, model.model_box, first).walk, sum / 60, 1e-9 * sum);
}

INSTANTIATE_TEST_SUITE_P(Models, LocationCheckTest,
                         ::testing::Values(Model::scene, Model::tetras, Model::far_tetras),
                         [](const auto& param_info) { return model_name(param_info.param); });

TEST(LocationCheckCommand, PrintsDisagreementsAndExitsZero) {
  const Indexed& model = indexed(Model::tetras);
  const fs::path report = model.index.parent_path() / "check.json";
  std::string out;
  ASSERT_EQ(test::run_cli("check-location " + model.index.string() + " --points 4000 --seed 2 --report " +
                    report.string(),
                out),
            0)
      << out;
  EXPECT_NE(out.find("\ndisagreements: 0\n"), std::string::npos) << out;
  std::ifstream in(report);
  const auto json = nlohmann::json::parse(in);
  EXPECT_GT(json.at("points").get<std::uint64_t>(), 2400u);  // exact face points may run short
  EXPECT_EQ(json.at("disagreements").get<std::uint64_t>(), 0u);
  EXPECT_GT(json.at("points_per_second").get<double>(), 0);

  const fs::path inspect = model.index.parent_path() / "inspect.json";
  ASSERT_EQ(test::run_cli("inspect " + model.index.string() + " --stabbing-segments 500 --report " +
                    inspect.string(),
                out),
            0)
      << out;
  EXPECT_NE(out.find("stabbing number"), std::string::npos) << out;
  std::ifstream inspect_in(inspect);
  const auto figures = nlohmann::json::parse(inspect_in);
  EXPECT_EQ(figures.at("stabbing_segments").get<std::uint64_t>(), 500u);
  EXPECT_EQ(figures.at("stabbing_segments_differing").get<std::uint64_t>(), 0u);
  EXPECT_EQ(figures.at("stabbing_number_walk").get<double>(),
            figures.at("stabbing_number_embree").get<double>());
  EXPECT_GT(figures.at("stabbing_number_walk").get<double>(), 0);

  ASSERT_EQ(test::run_cli("inspect " + model.index.string() + " --stabbing-segments 0", out), 0);
  EXPECT_EQ(out.find("stabbing number"), std::string::npos) << out;
}

}  // namespace
}  // namespace tetrapage
