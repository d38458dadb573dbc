// Exact triangle/box and box/box tests against CGAL's exact kernel, with triangles touching
// box faces, edges and corners exactly, lying in face planes, and nudged off them.

#include "tetrapage/runtime/geometry/TriangleBox.h"

#include "GeometryTestSupport.h"

namespace tetrapage::geometry {
namespace {

using namespace testing;

struct Case {
  Triangle t;
  Box box;
};

// A point of the box's surface: on a face, an edge or a corner, with dyadic coordinates.
Point on_box(Generator& g, const Box& box, int where) {
  Point p;
  for (int k = 0; k < 3; ++k)
    p[k] = box.lo[k] + std::ldexp(double(g.integer(0, 256)), -8) * (box.hi[k] - box.lo[k]);
  const int axes = where == 0 ? 1 : (where == 1 ? 2 : 3);  // face, edge, corner
  const int first = int(g.integer(0, 2));
  for (int i = 0; i < axes; ++i) {
    const int k = (first + i) % 3;
    p[k] = g.coin() ? box.lo[k] : box.hi[k];
  }
  return p;
}

Case box_case(Generator& g, int family) {
  const std::int64_t range = g.coin() ? 8 : (std::int64_t(1) << 20);
  Box box;
  box.lo = box.hi = lattice_point(g, range);
  box.extend(lattice_point(g, range));
  if (g.integer(0, 9) == 0) {  // a flat box
    const int k = int(g.integer(0, 2));
    box.hi[k] = box.lo[k];
  }
  Box grown = box;  // lattice points around the box
  for (int k = 0; k < 3; ++k) {
    const double size = std::max(1.0, box.hi[k] - box.lo[k]);
    grown.lo[k] -= size;
    grown.hi[k] += size;
  }
  auto around = [&] {
    Point p;
    for (int k = 0; k < 3; ++k) p[k] = std::floor(g.uniform(grown.lo[k], grown.hi[k]));
    return p;
  };
  Triangle t;
  switch (family) {
    case 0: t = {around(), around(), around()}; break;  // near the box, anywhere
    case 1:  // a vertex on the surface
      t = {on_box(g, box, int(g.integer(0, 2))), around(), around()};
      break;
    case 2: {  // an edge through a surface point
      const Point x = on_box(g, box, int(g.integer(0, 2)));
      const Point w = lattice_point(g, 64);
      t = {Point{x[0] + w[0], x[1] + w[1], x[2] + w[2]}, Point{x[0] - w[0], x[1] - w[1], x[2] - w[2]},
           around()};
      break;
    }
    case 3: {  // a triangle around a box corner (its centroid), in a random plane
      const Point c = on_box(g, box, 2);
      const Point u = lattice_point(g, 64), v = lattice_point(g, 64);
      t = {Point{c[0] + u[0], c[1] + u[1], c[2] + u[2]}, Point{c[0] + v[0], c[1] + v[1], c[2] + v[2]},
           Point{c[0] - u[0] - v[0], c[1] - u[1] - v[1], c[2] - u[2] - v[2]}};
      if (g.coin()) {  // sometimes shifted along the plane, off the corner or not
        const int shift = int(g.integer(-3, 2));
        for (auto& p : t)
          for (int k = 0; k < 3; ++k) p[k] += std::ldexp(u[k] - v[k], shift);
      }
      break;
    }
    case 4: {  // in a face plane
      const int k = int(g.integer(0, 2));
      const double plane = g.coin() ? box.lo[k] : box.hi[k];
      t = {around(), around(), around()};
      for (auto& p : t) p[k] = plane;
      break;
    }
    default:  // any of the above, nudged
      return [&] {
        Case c = box_case(g, int(g.integer(0, 4)));
        c.t[g.integer(0, 2)] = nudge(g, c.t[g.integer(0, 2)]);
        return c;
      }();
  }
  const ExactTransform transform = random_exact_transform(g);
  Case c{transform(t), {}};
  c.box.lo = c.box.hi = transform(box.lo);
  c.box.extend(transform(box.hi));
  return c;
}

TEST(TriangleBox, MatchesEpeck) {
  constexpr int kFamilies = 6;
  constexpr std::uint64_t kCasesPerFamily = 80000;
  // Families of shared features always touch; misses must occur over the whole test.
  std::uint64_t all_tested = 0, all_hits = 0;
  for (int family = 0; family < kFamilies; ++family) {
    Disagreements disagreements("classify_triangle_box family " + std::to_string(family));
    std::uint64_t tested = 0, hits = 0;
    for (std::uint64_t c = 0; c < kCasesPerFamily; ++c) {
      const std::uint64_t seed = 3000000 * std::uint64_t(family) + c;
      Generator g(seed);
      const Case k = box_case(g, family);
      if (epeck_degenerate(k.t)) continue;
      const CGAL::Bbox_3 bbox(k.box.lo[0], k.box.lo[1], k.box.lo[2], k.box.hi[0], k.box.hi[1],
                              k.box.hi[2]);
      const bool expected = CGAL::do_intersect(to_epeck(k.t), bbox);
      const bool inside = box_contains(k.box, k.t[0]) && box_contains(k.box, k.t[1]) &&
                          box_contains(k.box, k.t[2]);
      const TriangleBoxContact got = classify_triangle_box(k.t, k.box);
      const TriangleBoxContact wanted =
          !expected ? TriangleBoxContact::none
                    : (inside ? TriangleBoxContact::contained : TriangleBoxContact::intersects);
      ++tested;
      hits += expected;
      if (got != wanted)
        disagreements.add(seed, "triangle " + hex(k.t) + " box " + hex(std::array<Point, 2>{k.box.lo, k.box.hi}) +
                                    " expected " + std::to_string(int(wanted)) + " got " +
                                    std::to_string(int(got)));
    }
    disagreements.expect_none(tested);
    // Every family must hit; the misses are checked over the whole test below.
    EXPECT_GT(hits, tested / 1000) << "family " << family;
    all_tested += tested;
    all_hits += hits;
  }
  EXPECT_LT(all_hits, all_tested - all_tested / 100);
}

TEST(TriangleBox, DegenerateTrianglesAreSegments) {
  constexpr std::uint64_t kCases = 40000;
  Disagreements disagreements("degenerate triangle/box");
  for (std::uint64_t c = 0; c < kCases; ++c) {
    Generator g(c);
    Case k = box_case(g, int(c % 5));
    k.t[2] = c % 3 ? dyadic_combination(k.t[0], k.t[1], k.t[1], g.integer(-64, 128), 0, 6) : k.t[1];
    if (!epeck_degenerate(k.t)) continue;  // rounding in the combination: not collinear
    const CGAL::Bbox_3 bbox(k.box.lo[0], k.box.lo[1], k.box.lo[2], k.box.hi[0], k.box.hi[1],
                            k.box.hi[2]);
    bool expected = false;
    for (int e = 0; e < 3; ++e) {
      const auto p = to_epeck(k.t[e]), q = to_epeck(k.t[(e + 1) % 3]);
      expected = expected || (p == q ? CGAL::do_intersect(p, Epeck::Iso_cuboid_3(
                                                                to_epeck(k.box.lo), to_epeck(k.box.hi)))
                                     : CGAL::do_intersect(Epeck::Segment_3(p, q), bbox));
    }
    if (triangle_intersects_box(k.t, k.box) != expected)
      disagreements.add(c, "triangle " + hex(k.t));
  }
  disagreements.expect_none(kCases);
}

// GCC 12 sees a false "maybe uninitialized" inside CGAL's lazy Iso_cuboid_3 intersection.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
TEST(Box, ClassificationMatchesEpeckCuboids) {
  constexpr std::uint64_t kCases = 300000;
  Disagreements disagreements("classify_boxes");
  std::array<std::uint64_t, 3> seen{};
  for (std::uint64_t c = 0; c < kCases; ++c) {
    Generator g(c);
    const ExactTransform transform = random_exact_transform(g);
    Box boxes[2];
    for (auto& b : boxes) {
      b.lo = b.hi = transform(lattice_point(g, 3));
      b.extend(transform(lattice_point(g, 3)));
    }
    const Epeck::Iso_cuboid_3 a(to_epeck(boxes[0].lo), to_epeck(boxes[0].hi));
    const Epeck::Iso_cuboid_3 b(to_epeck(boxes[1].lo), to_epeck(boxes[1].hi));
    BoxContact expected = BoxContact::none;
    if (const auto meet = CGAL::intersection(a, b)) {
      const auto* cuboid = boost::get<Epeck::Iso_cuboid_3>(&*meet);
      expected = cuboid && cuboid->volume() > 0 ? BoxContact::overlapping : BoxContact::touching;
    }
    ++seen[std::size_t(expected)];
    if (classify_boxes(boxes[0], boxes[1]) != expected || classify_boxes(boxes[1], boxes[0]) != expected)
      disagreements.add(c, hex(std::array<Point, 4>{boxes[0].lo, boxes[0].hi, boxes[1].lo, boxes[1].hi}));
  }
  disagreements.expect_none(kCases);
  for (auto s : seen) EXPECT_GT(s, kCases / 50);
  EXPECT_FALSE(boxes_overlap(Box{}, Box{}));  // empty boxes meet nothing
}
#pragma GCC diagnostic pop

}  // namespace
}  // namespace tetrapage::geometry
