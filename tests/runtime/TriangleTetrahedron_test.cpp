// Exact triangle/solid tetrahedron overlap (for binning) against CGAL's exact kernel.

#include "tetrapage/runtime/geometry/TriangleTetrahedron.h"

#include "GeometryTestSupport.h"
#include "tetrapage/runtime/geometry/PointTetrahedron.h"

namespace tetrapage::geometry {
namespace {

using namespace testing;

struct Case {
  Triangle t;
  Tetrahedron tetrahedron;
};

Case tetrahedron_case(Generator& g, int family) {
  const std::int64_t range = g.coin() ? 6 : (std::int64_t(1) << 20);
  Tetrahedron k;
  for (auto& v : k) v = lattice_point(g, range);
  const auto& f = kTetrahedronFaces[g.integer(0, 3)];
  const Triangle face{k[f[0]], k[f[1]], k[f[2]]};
  auto outside = [&] {  // lattice points around the tetrahedron
    Point p;
    for (int c = 0; c < 3; ++c)
      p[c] = std::floor(g.uniform(-2.0, 2.0) * double(range));
    return p;
  };
  Triangle t;
  switch (family) {
    case 0: t = {outside(), outside(), outside()}; break;
    case 1:  // a vertex on the boundary: a face point, an edge point, a vertex
      t = {dyadic_point_on(g, face, int(g.integer(0, 2))), outside(), outside()};
      break;
    case 2:  // in a face plane
      t = {dyadic_point_on(g, face, 3), dyadic_point_on(g, face, 3), dyadic_point_on(g, face, 3)};
      break;
    case 3: {  // around a point of a tetrahedron edge (the edge pierces the triangle there)
      const Point x = dyadic_point_on(g, face, 1);
      const Point u = lattice_point(g, range), v = lattice_point(g, range);
      t = {Point{x[0] + u[0], x[1] + u[1], x[2] + u[2]}, Point{x[0] + v[0], x[1] + v[1], x[2] + v[2]},
           Point{x[0] - u[0] - v[0], x[1] - u[1] - v[1], x[2] - u[2] - v[2]}};
      break;
    }
    case 4: {  // inside, or one vertex inside
      auto inner = [&] {
        const Point on_face = dyadic_point_on(g, face, 0);
        const Point& apex = k[g.integer(0, 3)];
        return dyadic_combination(on_face, apex, apex, g.integer(0, 255), 0, 8);
      };
      t = {inner(), g.coin() ? inner() : outside(), inner()};
      break;
    }
    default: {  // the above, nudged
      Case c = tetrahedron_case(g, int(g.integer(0, 4)));
      const int v = int(g.integer(0, 2));
      c.t[v] = nudge(g, c.t[v]);
      return c;
    }
  }
  const ExactTransform transform = random_exact_transform(g);
  return {transform(t), transform(k)};
}

TEST(TriangleTetrahedron, MatchesEpeck) {
  constexpr int kFamilies = 6;
  constexpr std::uint64_t kCasesPerFamily = 40000;
  // Families of shared features always touch; misses must occur over the whole test.
  std::uint64_t all_tested = 0, all_hits = 0;
  for (int family = 0; family < kFamilies; ++family) {
    Disagreements disagreements("classify_triangle_tetrahedron family " + std::to_string(family));
    std::uint64_t tested = 0, hits = 0;
    for (std::uint64_t c = 0; c < kCasesPerFamily; ++c) {
      const std::uint64_t seed = 4000000 * std::uint64_t(family) + c;
      Generator g(seed);
      const Case k = tetrahedron_case(g, family);
      const auto et = to_epeck(k.tetrahedron);
      if (epeck_degenerate(k.t) || et.is_degenerate()) continue;
      const bool expected = CGAL::do_intersect(to_epeck(k.t), et);
      bool contained = true;
      for (const auto& v : k.t) contained = contained && !et.has_on_unbounded_side(to_epeck(v));
      const auto wanted = !expected ? TriangleTetrahedronContact::none
                                    : (contained ? TriangleTetrahedronContact::contained
                                                 : TriangleTetrahedronContact::intersects);
      const auto got = classify_triangle_tetrahedron(k.t, k.tetrahedron);
      // The other orientation of the same solid gives the same answer.
      const auto flipped = classify_triangle_tetrahedron(
          k.t, {k.tetrahedron[1], k.tetrahedron[0], k.tetrahedron[2], k.tetrahedron[3]});
      ++tested;
      hits += expected;
      if (got != wanted || flipped != wanted)
        disagreements.add(seed, "triangle " + hex(k.t) + " tetrahedron " + hex(k.tetrahedron) +
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

TEST(TriangleTetrahedron, DegenerateTetrahedronIsReported) {
  const Triangle t{Point{0, 0, 0}, Point{1, 0, 0}, Point{0, 1, 0}};
  const Tetrahedron flat{Point{0, 0, 0}, Point{1, 0, 0}, Point{0, 1, 0}, Point{1, 1, 0}};
  EXPECT_EQ(classify_triangle_tetrahedron(t, flat), TriangleTetrahedronContact::degenerate_tetrahedron);
  EXPECT_FALSE(triangle_intersects_tetrahedron(t, flat));
}

}  // namespace
}  // namespace tetrapage::geometry
