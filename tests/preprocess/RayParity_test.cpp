// Exact vertical ray parity (RayParity.h) at its extremes: rays through the edges and vertices
// of axis-aligned boxes and of an octahedron, points on faces, edges and vertices, both
// orientations of the surface. The oracles are closed-form: a box's and an octahedron's
// inside, surface and outside in exact arithmetic on small dyadic coordinates.

#include "tetrapage/preprocess/RayParity.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace tetrapage {
namespace {

using geometry::Point;
using geometry::Triangle;

enum class Where { inside, surface, outside };

std::vector<Triangle> box_triangles(double lo, double hi, bool other_diagonals) {
  std::vector<Point> v;
  for (int i = 0; i < 8; ++i)
    v.push_back({(i & 1) ? hi : lo, (i & 2) ? hi : lo, (i & 4) ? hi : lo});
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  std::vector<Triangle> out;
  for (const auto& f : faces) {
    if (other_diagonals) {
      out.push_back({v[f[1]], v[f[2]], v[f[3]]});
      out.push_back({v[f[1]], v[f[3]], v[f[0]]});
    } else {
      out.push_back({v[f[0]], v[f[1]], v[f[2]]});
      out.push_back({v[f[0]], v[f[2]], v[f[3]]});
    }
  }
  return out;
}

std::vector<Triangle> octahedron_triangles(double r) {
  std::vector<Triangle> out;
  for (int sx : {-1, 1})
    for (int sy : {-1, 1})
      for (int sz : {-1, 1}) {
        Triangle t{Point{sx * r, 0, 0}, Point{0, sy * r, 0}, Point{0, 0, sz * r}};
        if (sx * sy * sz < 0) std::swap(t[1], t[2]);  // outward, consistently
        out.push_back(t);
      }
  return out;
}

std::vector<Triangle> flipped(std::vector<Triangle> triangles) {
  for (auto& t : triangles) std::swap(t[1], t[2]);
  return triangles;
}

// Classifies the points against one part by RayParity and compares with the oracle.
void expect_classes(const std::vector<Triangle>& surface, const std::vector<Point>& points,
                    Where (*oracle)(const Point&)) {
  std::vector<std::vector<std::uint32_t>> asked(1);
  for (std::uint32_t i = 0; i < points.size(); ++i) asked[0].push_back(i);
  RayParity parity(points, asked);
  for (const Triangle& t : surface) parity.add_triangle(0, t);
  int inside = 0, surface_points = 0, checked = 0;
  parity.for_each_answer([&](std::uint32_t i, std::uint32_t part, bool odd, bool on_surface) {
    ++checked;
    EXPECT_EQ(part, 0u);
    const Point& q = points[i];
    const Where expected = oracle(q);
    inside += expected == Where::inside;
    surface_points += expected == Where::surface;
    if (expected == Where::surface) {
      EXPECT_TRUE(on_surface) << q[0] << " " << q[1] << " " << q[2];
    } else {
      EXPECT_FALSE(on_surface) << q[0] << " " << q[1] << " " << q[2];
      EXPECT_EQ(odd, expected == Where::inside) << q[0] << " " << q[1] << " " << q[2];
    }
  });
  EXPECT_EQ(checked, int(points.size()));
  EXPECT_GT(inside, 0);
  EXPECT_GT(surface_points, 0);
}

Where in_box(const Point& q) {  // the box [0, 2]^3
  bool on_boundary = false;
  for (const double c : q) {
    if (c < 0 || c > 2) return Where::outside;
    on_boundary = on_boundary || c == 0 || c == 2;
  }
  return on_boundary ? Where::surface : Where::inside;
}

Where in_octahedron(const Point& q) {  // |x| + |y| + |z| <= 2, exact on these coordinates
  const double l1 = std::fabs(q[0]) + std::fabs(q[1]) + std::fabs(q[2]);
  return l1 < 2 ? Where::inside : (l1 == 2 ? Where::surface : Where::outside);
}

// Every point of a lattice of step 1/2 around the shape: rays through its vertices, its edges
// (seen from above, the box's vertical faces are lines and its diagonals cross the lattice).
std::vector<Point> lattice(double lo, double hi) {
  std::vector<Point> points;
  for (double x = lo; x <= hi; x += 0.5)
    for (double y = lo; y <= hi; y += 0.5)
      for (double z = lo; z <= hi; z += 0.5) points.push_back({x, y, z});
  return points;
}

TEST(RayParity, BoxLatticeThroughEdgesAndVerticesBothDiagonalsBothOrientations) {
  const auto points = lattice(-1, 3);
  for (const bool diagonals : {false, true}) {
    const auto box = box_triangles(0, 2, diagonals);
    expect_classes(box, points, in_box);
    expect_classes(flipped(box), points, in_box);
  }
}

TEST(RayParity, OctahedronLatticeThroughItsAxisVerticesAndEdges) {
  const auto points = lattice(-3, 3);
  expect_classes(octahedron_triangles(2), points, in_octahedron);
  expect_classes(flipped(octahedron_triangles(2)), points, in_octahedron);
}

TEST(RayParity, FarCoordinatesAndTinyShapes) {
  // A box of side 2^-20 at 1e9: its coordinates are exact doubles, the predicates stay exact.
  const double base = 1e9, side = std::ldexp(1.0, -20);
  std::vector<Triangle> box = box_triangles(0, 2, false);
  for (auto& t : box)
    for (auto& p : t)
      for (auto& c : p) c = base + c * side / 2;
  std::vector<Point> points;
  for (const Point& q : lattice(-1, 3))
    points.push_back({base + q[0] * side / 2, base + q[1] * side / 2, base + q[2] * side / 2});
  std::vector<std::vector<std::uint32_t>> asked(1);
  for (std::uint32_t i = 0; i < points.size(); ++i) asked[0].push_back(i);
  RayParity parity(points, asked);
  for (const Triangle& t : box) parity.add_triangle(0, t);
  const auto unit = lattice(-1, 3);
  parity.for_each_answer([&](std::uint32_t i, std::uint32_t, bool odd, bool on_surface) {
    const Where expected = in_box(unit[i]);
    EXPECT_EQ(on_surface, expected == Where::surface) << i;
    if (expected != Where::surface) {
      EXPECT_EQ(odd, expected == Where::inside) << i;
    }
  });
}

TEST(RayParity, PartsArePairedOnlyWithTheirPoints) {
  // Two boxes, each asked about its own points: a point inside box 1 is not counted for box 0.
  const auto a = box_triangles(0, 2, false);
  auto b = box_triangles(0, 2, true);
  for (auto& t : b)
    for (auto& p : t) p[2] += 10;
  const std::vector<Point> points{{1, 1, 1}, {1, 1, 11}, {1, 1, 5}};
  const std::vector<std::vector<std::uint32_t>> asked{{0, 2}, {1, 2}, {}};
  RayParity parity(points, asked);
  EXPECT_TRUE(parity.wanted(0));
  EXPECT_TRUE(parity.wanted(1));
  EXPECT_FALSE(parity.wanted(2));
  EXPECT_FALSE(parity.wanted(7));
  EXPECT_EQ(parity.pair_count(), 4u);
  for (const auto& t : a) parity.add_triangle(0, t);
  for (const auto& t : b) parity.add_triangle(1, t);
  parity.add_triangle(7, a[0]);  // a part nobody asked about: ignored
  std::vector<std::pair<std::uint32_t, std::uint32_t>> inside;
  parity.for_each_answer([&](std::uint32_t point, std::uint32_t part, bool odd, bool on_surface) {
    EXPECT_FALSE(on_surface);
    if (odd) inside.emplace_back(point, part);
  });
  EXPECT_EQ(inside, (std::vector<std::pair<std::uint32_t, std::uint32_t>>{{0, 0}, {1, 1}}));
}

}  // namespace
}  // namespace tetrapage
