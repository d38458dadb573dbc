// The straight-line walk against brute force: for every query, the exact closed test over all
// tets gives the set of tets holding the point (empty outside the mesh); the walk's answer must
// be one of them. Meshes are CGAL Delaunay meshes of random sites (with the enlarged box's
// corners, as the preprocess builds them) and of lattice sites, where points on faces, edges
// and vertices and rays through vertices and edges are exact; at scales 2^-30 .. 2^30 and
// offsets up to about 1e9.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "GeometryTestSupport.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/preprocess/CoarseMesh.h"
#include "tetrapage/runtime/geometry/SegmentTriangle.h"
#include "tetrapage/runtime/query/MeshWalk.h"

namespace tetrapage {
namespace {

using geometry::Point;
using geometry::TetrahedronPosition;
using geometry::testing::Generator;
using geometry::testing::hex;

/// x -> offset + 2^exponent x: exact for lattice and dyadic points when offset is a multiple
/// of a small enough power of two.
struct Placement {
  int exponent = 0;
  double offset = 0;
  Point operator()(const Point& p) const {
    return {std::ldexp(p[0], exponent) + offset, std::ldexp(p[1], exponent) + offset,
            std::ldexp(p[2], exponent) + offset};
  }
  std::string name() const {
    return "scale 2^" + std::to_string(exponent) + ", offset " + std::to_string(offset);
  }
};

// Scales about 1e-9, 1 and 1e9; offsets 0, about 1e6 and about 1e9 times the scale.
const Placement kPlacements[] = {
    {0, 0},   {-30, 0}, {30, 0}, {0, std::ldexp(1.0, 20)}, {0, std::ldexp(1.0, 30)},
    {-30, std::ldexp(1.0, -10)}, {30, std::ldexp(1.0, 60)}, {-20, 1e6 * std::ldexp(1.0, -20)}};

void expect_valid_mesh(const TetMesh& mesh) {
  ASSERT_GT(mesh.tet_count(), 0u);
  for (std::size_t t = 0; t < mesh.tet_count(); ++t) {
    const auto c = mesh.corners(t);
    ASSERT_EQ(geometry::orient3d(c[0], c[1], c[2], c[3]), geometry::Sign::positive) << "tet " << t;
  }
}

/// Random sites in the unit cube plus the corners of the cube enlarged by 0.05.
TetMesh random_mesh(std::size_t sites, std::uint64_t seed, const Placement& placement) {
  Generator g(seed);
  std::vector<Vec3> points;
  for (std::size_t i = 0; i < sites; ++i)
    points.push_back(placement({g.uniform(), g.uniform(), g.uniform()}));
  for (int corner = 0; corner < 8; ++corner)
    points.push_back(placement({corner & 1 ? 1.05 : -0.05, corner & 2 ? 1.05 : -0.05,
                                corner & 4 ? 1.05 : -0.05}));
  return build_coarse_mesh(points);
}

/// The sites of an n x n x n integer lattice (highly degenerate for Delaunay: CGAL breaks the
/// ties), placed exactly.
TetMesh lattice_mesh(int n, const Placement& placement) {
  std::vector<Vec3> points;
  for (int x = 0; x < n; ++x)
    for (int y = 0; y < n; ++y)
      for (int z = 0; z < n; ++z) points.push_back(placement({double(x), double(y), double(z)}));
  return build_coarse_mesh(points);
}

std::vector<std::uint32_t> tets_holding(const TetMesh& mesh, const Point& p) {
  std::vector<std::uint32_t> out;
  for (std::uint32_t t = 0; t < mesh.tet_count(); ++t)
    if (geometry::locate_in_tetrahedron(p, mesh.corners(t)).position != TetrahedronPosition::outside)
      out.push_back(t);
  return out;
}

/// Walks from start to p and checks the answer against brute force. Returns false on failure.
bool check_walk(const TetMesh& mesh, std::uint32_t start, const Point& p, const std::string& what,
                std::uint64_t* crossed = nullptr) {
  const auto holding = tets_holding(mesh, p);
  WalkResult result;
  try {
    result = locate_point(mesh, start, p);
  } catch (const Error& e) {
    ADD_FAILURE() << what << ": walk from tet " << start << " to " << hex(p) << " threw " << e.what();
    return false;
  }
  if (crossed) *crossed += result.tets_crossed;
  if (holding.empty()) {
    EXPECT_EQ(result.tet, TetMesh::no_neighbour)
        << what << ": " << hex(p) << " is outside the mesh, the walk from tet " << start
        << " found tet " << result.tet;
    EXPECT_EQ(result.location.position, TetrahedronPosition::outside) << what;
    return result.tet == TetMesh::no_neighbour;
  }
  const bool found = std::find(holding.begin(), holding.end(), result.tet) != holding.end();
  EXPECT_TRUE(found) << what << ": the walk from tet " << start << " to " << hex(p)
                     << " returned tet " << result.tet << ", not one of the " << holding.size()
                     << " tets holding the point";
  if (!found) return false;
  EXPECT_EQ(result.location.position,
            geometry::locate_in_tetrahedron(p, mesh.corners(result.tet)).position)
      << what;
  const bool start_holds = std::find(holding.begin(), holding.end(), start) != holding.end();
  if (!start_holds) {
    EXPECT_GE(result.tets_crossed, 1u) << what << ": moved without crossing";
  }
  EXPECT_LE(result.tets_crossed, mesh.tet_count()) << what;
  return true;
}

TEST(MeshWalk, RandomPointsInRandomDelaunayMeshes) {
  struct Case {
    std::size_t sites;
    std::size_t placements;  // how many of kPlacements
    int queries;
  };
  for (const Case c : {Case{50, 8, 300}, Case{500, 8, 150}, Case{5000, 2, 60}}) {
    for (std::size_t pi = 0; pi < c.placements; ++pi) {
      const Placement placement = kPlacements[pi];
      const std::uint64_t seed = 1000 + c.sites + pi;
      const TetMesh mesh = random_mesh(c.sites, seed, placement);
      expect_valid_mesh(mesh);
      Generator g(seed + 0x51ed);  // not the sites' sequence
      const std::string what = std::to_string(c.sites) + " sites, seed " + std::to_string(seed) +
                               ", " + placement.name();
      int failures = 0;
      std::uint64_t crossed = 0;
      for (int q = 0; q < c.queries && failures < 5; ++q) {
        const auto start = std::uint32_t(g.integer(0, std::int64_t(mesh.tet_count()) - 1));
        const auto& corners = mesh.tets[std::size_t(g.integer(0, std::int64_t(mesh.tet_count()) - 1))];
        const Point& a = mesh.vertices[corners[0]];
        const Point& b = mesh.vertices[corners[1]];
        const Point& d = mesh.vertices[corners[2]];
        Point p;
        switch (q % 6) {
          case 0:  // anywhere in the enlarged box
            p = placement({g.uniform(-0.05, 1.05), g.uniform(-0.05, 1.05), g.uniform(-0.05, 1.05)});
            break;
          case 1:  // anywhere, often outside the mesh
            p = placement({g.uniform(-1, 2), g.uniform(-1, 2), g.uniform(-1, 2)});
            break;
          case 2:  // a mesh vertex
            p = a;
            break;
          case 3:  // on (or, rounded, next to) an edge
            for (int k = 0; k < 3; ++k) p[k] = 0.5 * a[k] + 0.5 * b[k];
            break;
          case 4:  // on (or next to) a face
            for (int k = 0; k < 3; ++k) p[k] = 0.25 * a[k] + 0.25 * b[k] + 0.5 * d[k];
            break;
          default:  // the start tet's own reference point, or a point on the hull
            if (g.coin()) {
              p = *walk_reference_point(mesh, start);
            } else {
              p = placement({-0.05, g.uniform(-0.05, 1.05), g.uniform(-0.05, 1.05)});
            }
        }
        if (!check_walk(mesh, start, p, what, &crossed)) ++failures;
      }
      std::printf("%s: %d queries, %.2f faces crossed per walk\n", what.c_str(), c.queries,
                  double(crossed) / c.queries);
    }
  }
}

TEST(MeshWalk, FromEveryStartTet) {
  const TetMesh mesh = random_mesh(50, 77, kPlacements[0]);
  Generator g(78);
  std::vector<Point> targets{mesh.vertices[0], mesh.vertices[mesh.vertices.size() - 1],
                             {0.5, 0.5, 0.5}, {2, 2, 2}, {-0.05, 0.3, 0.7}};
  for (int i = 0; i < 3; ++i) targets.push_back({g.uniform(), g.uniform(), g.uniform()});
  int failures = 0;
  for (const Point& p : targets)
    for (std::uint32_t start = 0; start < mesh.tet_count() && failures < 5; ++start)
      if (!check_walk(mesh, start, p, "seed 77")) ++failures;
  // A point strictly inside the start tet is located there without a walk.
  for (std::uint32_t start = 0; start < mesh.tet_count(); ++start) {
    const auto inside = walk_reference_point(mesh, start);
    if (!inside) continue;
    const WalkResult found = locate_point(mesh, start, *inside);
    EXPECT_EQ(found.tet, start);
    EXPECT_EQ(found.tets_crossed, 0u);
    EXPECT_EQ(found.location.position, geometry::TetrahedronPosition::inside);
  }
}

/// For lattice meshes every special point is exact: vertices, edge midpoints, dyadic face
/// points, and targets on the rays from the (exact) reference point of a start tet through a
/// vertex, an edge midpoint or a face point, beyond it.
TEST(MeshWalk, LatticeMeshesFacesEdgesVerticesAndRaysThroughThem) {
  const Placement placements[] = {{0, 0},
                                  {-30, 0},
                                  {30, 0},
                                  {0, std::ldexp(1.0, 20)},
                                  {-30, std::ldexp(1.0, -10)},
                                  {-10, std::ldexp(1.0, 20)},
                                  {20, std::ldexp(1.0, 50)}};
  for (const Placement& placement : placements) {
    const TetMesh mesh = lattice_mesh(5, placement);
    expect_valid_mesh(mesh);
    const std::uint64_t seed = 31 + std::uint64_t(placement.exponent + 64);
    Generator g(seed);
    const std::string what = "lattice 5^3, " + placement.name() + ", seed " + std::to_string(seed);
    int failures = 0;
    int rays_through_features = 0;
    std::uint64_t crossed = 0;
    int walks = 0;
    for (int q = 0; q < 400 && failures < 5; ++q) {
      const auto start = std::uint32_t(g.integer(0, std::int64_t(mesh.tet_count()) - 1));
      const auto& corners = mesh.tets[std::size_t(g.integer(0, std::int64_t(mesh.tet_count()) - 1))];
      const int rotate = int(g.integer(0, 3));
      const Point& a = mesh.vertices[corners[rotate]];
      const Point& b = mesh.vertices[corners[(rotate + 1) % 4]];
      const Point& d = mesh.vertices[corners[(rotate + 2) % 4]];
      Point feature;
      const int kind = q % 3;
      for (int k = 0; k < 3; ++k) {
        if (kind == 0) feature[k] = a[k];
        if (kind == 1) feature[k] = 0.5 * a[k] + 0.5 * b[k];
        if (kind == 2) feature[k] = 0.25 * a[k] + 0.25 * b[k] + 0.5 * d[k];
      }
      // The feature itself, exactly on it.
      ++walks;
      if (!check_walk(mesh, start, feature, what + ", feature kind " + std::to_string(kind), &crossed))
        ++failures;
      // Beyond it on the ray from the start's reference point (maybe out of the mesh).
      const Point reference = *walk_reference_point(mesh, start);
      const double stretch = double(g.integer(1, 3));  // 2, 3 or 4 times as far
      Point beyond;
      for (int k = 0; k < 3; ++k) beyond[k] = feature[k] + stretch * (feature[k] - reference[k]);
      if (geometry::is_degenerate(reference, feature, beyond)) ++rays_through_features;
      ++walks;
      if (!check_walk(mesh, start, beyond, what + ", ray through feature kind " + std::to_string(kind),
                      &crossed))
        ++failures;
    }
    // The constructions must be exact, or this test would not exercise degenerate rays.
    EXPECT_GE(rays_through_features, 300) << what;
    std::printf("%s: %d of 400 rays exactly through a vertex, edge or face point, %.2f faces "
                "crossed per walk\n",
                what.c_str(), rays_through_features, double(crossed) / walks);
  }
}

/// True when the closed segment meets the closed tet (exact, from the kernel's tests).
bool segment_meets_tet(const Point& a, const Point& b, const geometry::Tetrahedron& t) {
  if (geometry::locate_in_tetrahedron(a, t).position != TetrahedronPosition::outside) return true;
  if (geometry::locate_in_tetrahedron(b, t).position != TetrahedronPosition::outside) return true;
  for (const auto& f : geometry::kTetrahedronFaces)
    if (geometry::segment_intersects_triangle({a, b}, {t[f[0]], t[f[1]], t[f[2]]})) return true;
  return false;
}

/// Checks a segment walk; `generic` asks for the exact set of tets the segment meets.
void check_segment_walk(const TetMesh& mesh, std::uint32_t start, const Point& a, const Point& b,
                        bool generic, const std::string& what, int& failures) {
  SegmentWalk walk;
  try {
    walk = walk_segment(mesh, start, a, b);
  } catch (const Error& e) {
    ADD_FAILURE() << what << ": " << hex(a) << " -> " << hex(b) << " threw " << e.what();
    ++failures;
    return;
  }
  const std::string segment = what + ": " + hex(a) + " -> " + hex(b);
  const bool inside = !tets_holding(mesh, a).empty() && !tets_holding(mesh, b).empty();
  std::set<std::uint32_t> seen;
  bool ok = true;
  for (std::size_t i = 0; i < walk.tets.size(); ++i) {
    const std::uint32_t t = walk.tets[i];
    ok &= seen.insert(t).second;
    ok &= segment_meets_tet(a, b, mesh.corners(t));
    if (i > 0) {
      const auto& n = mesh.neighbours[walk.tets[i - 1]];
      ok &= std::find(n.begin(), n.end(), t) != n.end();
    }
  }
  EXPECT_TRUE(ok) << segment << ": a tet repeats, misses the segment, or is not the previous "
                  << "tet's neighbour";
  if (!walk.tets.empty()) {
    EXPECT_NE(geometry::locate_in_tetrahedron(a, mesh.corners(walk.tets.front())).position,
              TetrahedronPosition::outside) << segment;
    if (walk.complete) {
      EXPECT_NE(geometry::locate_in_tetrahedron(b, mesh.corners(walk.tets.back())).position,
                TetrahedronPosition::outside) << segment;
    }
  }
  if (generic && inside) {
    EXPECT_TRUE(walk.complete) << segment;
    std::vector<std::uint32_t> expected;
    for (std::uint32_t t = 0; t < mesh.tet_count(); ++t)
      if (segment_meets_tet(a, b, mesh.corners(t))) expected.push_back(t);
    std::vector<std::uint32_t> got(walk.tets.begin(), walk.tets.end());
    std::sort(got.begin(), got.end());
    EXPECT_EQ(got, expected) << segment;
    ok &= got == expected;
  }
  if (!ok) ++failures;
}

TEST(MeshWalk, SegmentsInRandomMeshesCrossExactlyTheTetsTheyMeet) {
  for (const std::size_t sites : {std::size_t(50), std::size_t(2000)}) {
    for (const std::size_t pi : {std::size_t(0), std::size_t(2), std::size_t(4)}) {
      const std::uint64_t seed = 500 + sites + pi;
      const TetMesh mesh = random_mesh(sites, seed, kPlacements[pi]);
      Generator g(seed + 0x51ed);  // not the sites' sequence
      const std::string what = std::to_string(sites) + " sites, seed " + std::to_string(seed) +
                               ", " + kPlacements[pi].name();
      int failures = 0;
      double crossed = 0, length = 0;
      for (int q = 0; q < 60 && failures < 5; ++q) {
        const auto start = std::uint32_t(g.integer(0, std::int64_t(mesh.tet_count()) - 1));
        const Point a = kPlacements[pi]({g.uniform(), g.uniform(), g.uniform()});
        const Point b = kPlacements[pi]({g.uniform(), g.uniform(), g.uniform()});
        check_segment_walk(mesh, start, a, b, true, what, failures);
        const SegmentWalk walk = walk_segment(mesh, start, a, b);
        crossed += double(walk.tets.size() - 1);
        length += std::hypot(b[0] - a[0], b[1] - a[1], b[2] - a[2]) /
                  std::ldexp(1.0, kPlacements[pi].exponent);
      }
      std::printf("%s: %.1f faces crossed per unit length\n", what.c_str(), crossed / length);
    }
  }
}

TEST(MeshWalk, SegmentsAlongLatticeLinesThroughVerticesAndEdges) {
  for (const Placement& placement : {Placement{0, 0}, Placement{-30, std::ldexp(1.0, -10)},
                                     Placement{0, std::ldexp(1.0, 30)}}) {
    const TetMesh mesh = lattice_mesh(5, placement);
    Generator g(9);
    const std::string what = "lattice 5^3, " + placement.name();
    int failures = 0;
    for (int q = 0; q < 200 && failures < 5; ++q) {
      const auto start = std::uint32_t(g.integer(0, std::int64_t(mesh.tet_count()) - 1));
      // Lattice points (vertices), edge midpoints and quarter points: the segments run along
      // mesh edges, across vertices, and within faces.
      auto point = [&]() {
        return placement({double(g.integer(0, 16)) / 4, double(g.integer(0, 16)) / 4,
                          double(g.integer(0, 16)) / 4});
      };
      const Point a = point();
      Point b = point();
      if (q % 4 == 0) {  // axis-aligned through a row of vertices
        b = a;
        const int axis = int(g.integer(0, 2));
        b[axis] = placement({double(g.integer(0, 4)), 0, 0})[0];
      }
      check_segment_walk(mesh, start, a, b, false, what, failures);
    }
  }
}

TEST(MeshWalk, RejectsBadArguments) {
  const TetMesh mesh = random_mesh(50, 5, kPlacements[0]);
  EXPECT_THROW(locate_point(mesh, std::uint32_t(mesh.tet_count()), {0.5, 0.5, 0.5}), InputError);
  EXPECT_THROW(locate_point(mesh, 0, {NAN, 0.5, 0.5}), InputError);
  EXPECT_THROW(locate_point(mesh, 0, {INFINITY, 0.5, 0.5}), InputError);
  EXPECT_THROW(walk_segment(mesh, 0, {0.5, 0.5, 0.5}, {0.5, NAN, 0.5}), InputError);
  EXPECT_THROW(locate_point(TetMesh{}, 0, {0.5, 0.5, 0.5}), InputError);
  EXPECT_THROW(walk_reference_point(mesh, std::uint32_t(mesh.tet_count())), InputError);
}

TEST(MeshWalk, CorruptNeighboursThrowInsteadOfLooping) {
  TetMesh mesh = random_mesh(200, 6, kPlacements[0]);
  // Point every neighbour at tet 0: the walk must notice, not spin.
  for (auto& n : mesh.neighbours)
    for (auto& t : n)
      if (t != TetMesh::no_neighbour) t = 0;
  Generator g(6);
  int threw = 0;
  for (int q = 0; q < 50; ++q) {
    try {
      locate_point(mesh, std::uint32_t(g.integer(1, std::int64_t(mesh.tet_count()) - 1)),
                   {g.uniform(), g.uniform(), g.uniform()});
    } catch (const Error&) {
      ++threw;
    }
  }
  EXPECT_GT(threw, 0);
}

}  // namespace
}  // namespace tetrapage
