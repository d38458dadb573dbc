// The box search against brute force, and its exact tet/box test against two independent
// oracles: CGAL's exact-construction kernel (do_intersect of a solid Tetrahedron_3 and an
// Iso_cuboid_3), and a composition of the kernel's own exact tests (a face of the tet meets
// the box, or a corner of the box lies in the tet), which also covers flat boxes.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "GeometryTestSupport.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/preprocess/CoarseMesh.h"
#include "tetrapage/runtime/geometry/FloatBox.h"
#include "tetrapage/runtime/geometry/PointTetrahedron.h"
#include "tetrapage/runtime/geometry/TriangleBox.h"
#include "tetrapage/runtime/paging/BoxSearch.h"
#include "tetrapage/runtime/query/MeshWalk.h"

namespace tetrapage {
namespace {

using geometry::Box;
using geometry::Point;
using geometry::Tetrahedron;
using geometry::testing::Generator;
using geometry::testing::hex;
using geometry::testing::to_epeck;
using Epeck = geometry::testing::Epeck;

bool composed_oracle(const Tetrahedron& t, const Box& box) {
  for (const auto& f : geometry::kTetrahedronFaces)
    if (geometry::triangle_intersects_box({t[f[0]], t[f[1]], t[f[2]]}, box)) return true;
  const Point corner = box.lo;
  if (geometry::orient3d(t[0], t[1], t[2], t[3]) == geometry::Sign::zero) return false;
  return geometry::locate_in_tetrahedron(corner, t).position !=
         geometry::TetrahedronPosition::outside;
}

bool cgal_oracle(const Tetrahedron& t, const Box& box) {
  const Epeck::Iso_cuboid_3 cuboid(to_epeck(box.lo), to_epeck(box.hi));
  return CGAL::do_intersect(to_epeck(t), cuboid);
}

bool flat(const Box& box) {
  return box.lo[0] == box.hi[0] || box.lo[1] == box.hi[1] || box.lo[2] == box.hi[2];
}

std::string describe(const Tetrahedron& t, const Box& box) {
  return "tet " + hex(t) + ", box " + hex(box.lo) + " .. " + hex(box.hi);
}

Box box_between(Point a, Point b) {
  Box box;
  for (int k = 0; k < 3; ++k) {
    box.lo[k] = std::min(a[k], b[k]);
    box.hi[k] = std::max(a[k], b[k]);
  }
  return box;
}

TEST(TetrahedronBox, AgreesWithCgalAndWithTheKernelsFaceTests) {
  geometry::testing::Disagreements with_cgal("tetrahedron_intersects_box vs CGAL Epeck");
  geometry::testing::Disagreements with_faces("tetrahedron_intersects_box vs face/box tests");
  std::uint64_t cases = 0, hits = 0, cgal_cases = 0;
  for (std::uint64_t seed = 0; seed < 20000; ++seed) {
    Generator g(seed);
    const auto transform = geometry::testing::random_exact_transform(g, 2);
    Tetrahedron t;
    Box box;
    const int family = int(seed % 4);
    if (family == 0) {  // random doubles
      for (auto& v : t) v = {g.uniform(), g.uniform(), g.uniform()};
      box = box_between({g.uniform(), g.uniform(), g.uniform()},
                        {g.uniform(), g.uniform(), g.uniform()});
    } else {  // lattice tets and half-integer boxes: touching at faces, edges and corners
      for (auto& v : t) v = geometry::testing::lattice_point(g, 3);
      if (family == 2) t[3] = geometry::testing::dyadic_point_on(g, {t[0], t[1], t[2]}, 3, 1);  // flat
      auto coordinate = [&] { return double(g.integer(-8, 8)) / 2; };
      Point a{coordinate(), coordinate(), coordinate()}, b{coordinate(), coordinate(), coordinate()};
      if (family == 3) b[g.integer(0, 2)] = a[0];  // often flat
      box = box_between(a, b);
    }
    t = transform(t);
    box = box_between(transform(box.lo), transform(box.hi));
    const bool got = geometry::tetrahedron_intersects_box(t, box);
    ++cases;
    hits += got;
    const bool tet_flat = geometry::orient3d(t[0], t[1], t[2], t[3]) == geometry::Sign::zero;
    if (!tet_flat && got != composed_oracle(t, box))
      with_faces.add(seed, describe(t, box) + (got ? ": said yes" : ": said no"));
    if (!tet_flat && !flat(box)) {
      ++cgal_cases;
      if (got != cgal_oracle(t, box))
        with_cgal.add(seed, describe(t, box) + (got ? ": said yes" : ": said no"));
    }
    if (tet_flat) {
      // A flat tet is the union of its four (flat) faces' triangles' hull: a face meeting the
      // box implies a hit, and every hit meets some face or lies in the hull's plane region.
      bool face_hit = false;
      for (const auto& f : geometry::kTetrahedronFaces)
        face_hit |= geometry::triangle_intersects_box({t[f[0]], t[f[1]], t[f[2]]}, box);
      if (face_hit != got) with_faces.add(seed, describe(t, box) + " (flat tet)");
    }
  }
  std::printf("%llu cases (%llu against CGAL), %llu meet\n", (unsigned long long)cases,
              (unsigned long long)cgal_cases, (unsigned long long)hits);
  with_cgal.expect_none(cgal_cases);
  with_faces.expect_none(cases);
  EXPECT_GT(hits, cases / 10);
  EXPECT_LT(hits, cases - cases / 10);
}

// Boxes a hair's breadth from a tet: a box with one corner on a face (interior, edge or vertex)
// and the rest on the face's outer side touches the tet; moved out by 2^-45 or 2^-20 it misses it;
// moved in by 2^-45, it meets it. Double precision cannot tell the nearest apart, so the answer
// must come from the exact tests; scaled and moved far from the origin by exact transforms.
TEST(TetrahedronBox, BoxesAHairFromAFace) {
  geometry::testing::Disagreements with_cgal("tetrahedron_intersects_box vs CGAL Epeck, near contact");
  std::uint64_t cases = 0, touching = 0, apart = 0;
  for (std::uint64_t seed = 0; seed < 3000; ++seed) {
    Generator g(seed + 1'000'000);
    Tetrahedron t;
    for (auto& v : t) v = geometry::testing::lattice_point(g, 3);
    const geometry::Sign orientation = geometry::orient3d(t[0], t[1], t[2], t[3]);
    if (orientation == geometry::Sign::zero) continue;
    const int k = int(g.integer(0, 3));
    const auto& f = geometry::kTetrahedronFaces[k];
    const geometry::Triangle face{t[f[0]], t[f[1]], t[f[2]]};
    const Point p = geometry::testing::dyadic_point_on(g, face, int(g.integer(0, 2)), 8);
    // The face's outward normal (exact: small integers), away from the opposite vertex.
    Point n;
    for (int a = 0; a < 3; ++a) {
      const int i = (a + 1) % 3, j = (a + 2) % 3;
      n[a] = (face[1][i] - face[0][i]) * (face[2][j] - face[0][j]) - (face[1][j] - face[0][j]) * (face[2][i] - face[0][i]);
    }
    if (n[0] == 0 || n[1] == 0 || n[2] == 0) continue;
    const double towards_opposite = n[0] * (t[k][0] - p[0]) + n[1] * (t[k][1] - p[1]) + n[2] * (t[k][2] - p[2]);
    for (auto& x : n) x = towards_opposite > 0 ? -x : x;
    const auto transform = geometry::testing::random_exact_transform(g, 48);
    for (const double shift : {0.0, 0x1p-45, -0x1p-45, 0x1p-20}) {
      Point a, b;
      for (int axis = 0; axis < 3; ++axis) {
        const double s = n[axis] > 0 ? 1.0 : -1.0;
        a[axis] = p[axis] + shift * s;
        b[axis] = a[axis] + s;
      }
      const Tetrahedron placed{transform(t[0]), transform(t[1]), transform(t[2]), transform(t[3])};
      const Box box = box_between(transform(a), transform(b));
      const bool got = geometry::tetrahedron_intersects_box(placed, box);
      ++cases;
      if (got != cgal_oracle(placed, box))
        with_cgal.add(seed, describe(placed, box) + (got ? ": said yes" : ": said no") + ", shift " + std::to_string(shift));
      if (shift == 0 && !got) with_cgal.add(seed, "a box touching the face at a point must meet the tet");
      if (shift > 0 && got) with_cgal.add(seed, "a box outside the face's plane must miss the tet");
      touching += shift == 0;
      apart += shift > 0;
    }
  }
  with_cgal.expect_none(cases);
  EXPECT_GT(touching, 1000u);
  EXPECT_GT(apart, 1000u);
}

TetMesh random_mesh(std::size_t sites, std::uint64_t seed, int exponent, double offset) {
  Generator g(seed);
  auto place = [&](Point p) {
    for (auto& x : p) x = std::ldexp(x, exponent) + offset;
    return p;
  };
  std::vector<Vec3> points;
  for (std::size_t i = 0; i < sites; ++i) points.push_back(place({g.uniform(), g.uniform(), g.uniform()}));
  for (int c = 0; c < 8; ++c)
    points.push_back(place({c & 1 ? 1.05 : -0.05, c & 2 ? 1.05 : -0.05, c & 4 ? 1.05 : -0.05}));
  return build_coarse_mesh(points);
}

TetMesh lattice_mesh(int n) {
  std::vector<Vec3> points;
  for (int x = 0; x < n; ++x)
    for (int y = 0; y < n; ++y)
      for (int z = 0; z < n; ++z) points.push_back({double(x), double(y), double(z)});
  return build_coarse_mesh(points);
}

std::vector<std::uint32_t> brute_force(const TetMesh& mesh, const Box& box, bool use_oracle) {
  std::vector<std::uint32_t> out;
  for (std::uint32_t t = 0; t < mesh.tet_count(); ++t) {
    if (!geometry::boxes_overlap(mesh.bounds(t), box)) continue;
    const bool meets = use_oracle ? composed_oracle(mesh.corners(t), box)
                                  : geometry::tetrahedron_intersects_box(mesh.corners(t), box);
    if (meets) out.push_back(t);
  }
  return out;
}

/// Searches from the tet located for a corner of the box (or any tet meeting it, when the
/// corner is outside the mesh) and compares with brute force.
void check_search(const TetMesh& mesh, const TetBoxFilter& filter, const Box& box, std::uint32_t walk_start,
                  BoxSearchScratch& scratch, const std::string& what, int& failures,
                  double& visited_per_found) {
  const auto expected = brute_force(mesh, box, false);
  EXPECT_EQ(expected, brute_force(mesh, box, true)) << what << ": the exact test disagrees with "
                                                    << "the face/box oracle";
  // The filter (a flying object's test before a page-in) keeps every tet that meets the box.
  for (const std::uint32_t tet : expected)
    EXPECT_TRUE(filter.may_meet(tet, box)) << what << ": tet " << tet << ", box " << hex(box.lo) << " .. "
                                                  << hex(box.hi);
  if (expected.empty()) return;
  std::uint32_t start = locate_point(mesh, walk_start, box.lo).tet;
  if (start == TetMesh::no_neighbour) start = expected[expected.size() / 2];
  const BoxSearchResult result = tets_overlapping_box(mesh, start, box, scratch);
  std::vector<std::uint32_t> got(result.tets.begin(), result.tets.end());
  std::sort(got.begin(), got.end());
  std::vector<std::uint32_t> missed, extra;
  std::set_difference(expected.begin(), expected.end(), got.begin(), got.end(),
                      std::back_inserter(missed));
  std::set_difference(got.begin(), got.end(), expected.begin(), expected.end(),
                      std::back_inserter(extra));
  EXPECT_TRUE(missed.empty() && extra.empty())
      << what << ": box " << hex(box.lo) << " .. " << hex(box.hi) << " from tet " << start
      << ": " << missed.size() << " tets missed, " << extra.size() << " extra, of "
      << expected.size();
  EXPECT_GE(result.tets_visited, result.exact_tests);
  EXPECT_GE(result.exact_tests, result.tets.size());
  visited_per_found += double(result.tets_visited) / double(result.tets.size());
  if (!missed.empty() || !extra.empty()) ++failures;

  // The cheap search (the flying object's region) keeps every tet that meets the box; what it
  // keeps beyond them has a bounding box that meets it, both rounded outward to floats.
  const BoxSearchResult near = tets_near_box(mesh, filter, start, box, scratch);
  std::vector<std::uint32_t> near_tets(near.tets.begin(), near.tets.end());
  std::sort(near_tets.begin(), near_tets.end());
  std::vector<std::uint32_t> near_missed;
  std::set_difference(expected.begin(), expected.end(), near_tets.begin(), near_tets.end(),
                      std::back_inserter(near_missed));
  EXPECT_TRUE(near_missed.empty()) << what << ": box " << hex(box.lo) << " .. " << hex(box.hi)
                                   << ": the near search missed " << near_missed.size() << " of "
                                   << expected.size() << " tets meeting it";
  for (const std::uint32_t tet : near_tets)
    EXPECT_TRUE(geometry::boxes_overlap(geometry::FloatBox::enclosing(mesh.bounds(tet)).box(),
                                        geometry::FloatBox::enclosing(box).box()))
        << what << ": near tet " << tet;
  EXPECT_EQ(near.exact_tests, 0u);
  if (!near_missed.empty()) ++failures;
}

// A shard's stored bounds are kept as floats rounded outward (CollisionIndex::shard_bounds):
// each holds its box, within a float's rounding, also far from the origin, tiny, beyond
// float's range, and empty.
TEST(FloatBox, HoldsItsBoxWithinAFloatsRounding) {
  for (const auto& [exponent, offset] : {std::pair{-30, 0.0}, std::pair{0, 0.0}, std::pair{0, 1e6}}) {
    const TetMesh mesh = random_mesh(300, 11, exponent, offset);
    for (std::uint32_t t = 0; t < mesh.tet_count(); ++t) {
      const geometry::Box exact = mesh.bounds(t), held = geometry::FloatBox::enclosing(exact).box();
      for (int a = 0; a < 3; ++a) {
        ASSERT_LE(held.lo[a], exact.lo[a]) << "tet " << t;
        ASSERT_GE(held.hi[a], exact.hi[a]) << "tet " << t;
        EXPECT_LE(exact.lo[a] - held.lo[a], std::fabs(exact.lo[a]) * 0x1p-23) << "tet " << t;
        EXPECT_LE(held.hi[a] - exact.hi[a], std::fabs(exact.hi[a]) * 0x1p-23) << "tet " << t;
      }
    }
  }
  geometry::Box huge;
  huge.lo = {-1e300, -1.0, 1e-300};
  huge.hi = {1e300, 1.0 + 1e-12, 2e-300};
  const geometry::Box held = geometry::FloatBox::enclosing(huge).box();
  for (int a = 0; a < 3; ++a) {
    EXPECT_LE(held.lo[a], huge.lo[a]);
    EXPECT_GE(held.hi[a], huge.hi[a]);
  }
  EXPECT_TRUE(geometry::FloatBox::enclosing(geometry::Box{}).box().empty());
}

TEST(BoxSearch, FindsExactlyTheTetsMeetingTheBoxInRandomMeshes) {
  struct Case {
    std::size_t sites;
    int exponent;
    double offset;
    int queries;
  };
  for (const Case c : {Case{500, 0, 0, 150}, Case{500, -30, std::ldexp(1.0, -10), 100},
                       Case{500, 30, 1e18, 100}, Case{5000, 0, 1e6, 60}}) {
    const std::uint64_t seed = 42 + c.sites + std::uint64_t(c.exponent + 64);
    const TetMesh mesh = random_mesh(c.sites, seed, c.exponent, c.offset);
    const TetBoxFilter filter(mesh);
    Generator g(seed + 0x51ed);  // not the sites' sequence
    BoxSearchScratch scratch;
    const std::string what = std::to_string(c.sites) + " sites, seed " + std::to_string(seed) +
                             ", scale 2^" + std::to_string(c.exponent);
    auto place = [&](Point p) {
      for (auto& x : p) x = std::ldexp(x, c.exponent) + c.offset;
      return p;
    };
    int failures = 0, searched = 0;
    double visited_per_found = 0;
    for (int q = 0; q < c.queries && failures < 5; ++q) {
      const Point centre{g.uniform(-0.2, 1.2), g.uniform(-0.2, 1.2), g.uniform(-0.2, 1.2)};
      Point half;
      for (auto& h : half) h = g.log_uniform(-3, -0.5);
      if (q % 7 == 0) half[g.integer(0, 2)] = 0;  // flat
      if (q % 11 == 0) half = {0, 0, 0};            // a point
      const Box box = box_between(place({centre[0] - half[0], centre[1] - half[1], centre[2] - half[2]}),
                                  place({centre[0] + half[0], centre[1] + half[1], centre[2] + half[2]}));
      const auto walk_start = std::uint32_t(g.integer(0, std::int64_t(mesh.tet_count()) - 1));
      check_search(mesh, filter, box, walk_start, scratch, what, failures, visited_per_found);
      ++searched;
    }
    std::printf("%s: %d boxes, %.2f tets visited per tet found\n", what.c_str(), searched,
                visited_per_found / searched);
  }
}

TEST(BoxSearch, LatticeBoxesTouchingFacesEdgesAndVertices) {
  const TetMesh mesh = lattice_mesh(6);
  const TetBoxFilter filter(mesh);
  Generator g(8);
  BoxSearchScratch scratch;
  int failures = 0;
  double visited_per_found = 0;
  for (int q = 0; q < 300 && failures < 5; ++q) {
    // Half-integer bounds: box faces on lattice planes and through edge midpoints.
    auto coordinate = [&] { return double(g.integer(-2, 12)) / 2; };
    Point a{coordinate(), coordinate(), coordinate()}, b{coordinate(), coordinate(), coordinate()};
    if (q % 5 == 0) b = a;  // a point box, often a vertex
    check_search(mesh, filter, box_between(a, b), std::uint32_t(g.integer(0, std::int64_t(mesh.tet_count()) - 1)),
                 scratch, "lattice 6^3, seed 8", failures, visited_per_found);
  }
}

TEST(BoxSearch, ScratchServesSeveralMeshesAndRepeatsAnswers) {
  const TetMesh small = random_mesh(50, 3, 0, 0);
  const TetMesh large = random_mesh(1000, 4, 0, 0);
  BoxSearchScratch shared;
  Generator g(3);
  for (int q = 0; q < 40; ++q) {
    const TetMesh& mesh = q % 2 ? small : large;
    const Point c{g.uniform(0.1, 0.9), g.uniform(0.1, 0.9), g.uniform(0.1, 0.9)};
    const Box box = box_between({c[0] - 0.05, c[1] - 0.05, c[2] - 0.05}, {c[0] + 0.05, c[1] + 0.05, c[2] + 0.05});
    const std::uint32_t start = locate_point(mesh, 0, c).tet;
    ASSERT_NE(start, TetMesh::no_neighbour);
    const auto first = tets_overlapping_box(mesh, start, box, shared);
    std::vector<std::uint32_t> a(first.tets.begin(), first.tets.end());
    BoxSearchScratch fresh;
    const auto second = tets_overlapping_box(mesh, start, box, fresh);
    std::vector<std::uint32_t> b(second.tets.begin(), second.tets.end());
    EXPECT_EQ(a, b) << "query " << q;
    EXPECT_EQ(first.tets_visited, second.tets_visited);
  }
}

TEST(BoxSearch, RejectsBadArguments) {
  const TetMesh mesh = random_mesh(50, 5, 0, 0);
  BoxSearchScratch scratch;
  const Box box = box_between({0.4, 0.4, 0.4}, {0.5, 0.5, 0.5});
  const std::uint32_t inside = locate_point(mesh, 0, {0.45, 0.45, 0.45}).tet;
  EXPECT_THROW(tets_overlapping_box(mesh, std::uint32_t(mesh.tet_count()), box, scratch), InputError);
  Box bad = box;
  bad.hi[1] = NAN;
  EXPECT_THROW(tets_overlapping_box(mesh, inside, bad, scratch), InputError);
  // A tet far from the box.
  const std::uint32_t far = locate_point(mesh, 0, {1.04, 1.04, 1.04}).tet;
  EXPECT_THROW(tets_overlapping_box(mesh, far, box, scratch), InputError);
  Box inverted = box;
  inverted.lo[2] = 0.6;
  EXPECT_TRUE(tets_overlapping_box(mesh, inside, inverted, scratch).tets.empty());
  // The near search needs a filter made for the mesh.
  EXPECT_FALSE(tets_near_box(mesh, TetBoxFilter(mesh), inside, box, scratch).tets.empty());
  EXPECT_THROW(tets_near_box(mesh, TetBoxFilter(lattice_mesh(2)), inside, box, scratch), InputError);
}

}  // namespace
}  // namespace tetrapage
