// Triangle/triangle distance: the bounds bracket CGAL's exact squared distance, and
// within_distance never misses a pair within d, touching pairs included.

#include "tetrapage/runtime/geometry/TriangleDistance.h"

#include "GeometryTestSupport.h"
#include "tetrapage/runtime/geometry/TriangleTriangle.h"

namespace tetrapage::geometry {
namespace {

using namespace testing;

struct Pair {
  Triangle a, b;
};

Pair distance_case(Generator& g, int family) {
  if (family == 0) {  // generic: separated by a random gap, any scale and offset
    const double scale = g.log_uniform(-9, 9);
    const double offset = g.coin() ? 0.0 : g.log_uniform(6, 9) * (g.coin() ? 1 : -1);
    const Rotation rotation = random_rotation(g);
    const double gap = g.log_uniform(-6, 0);
    Pair pair;
    for (auto* t : {&pair.a, &pair.b})
      for (auto& v : *t) {
        Point p{g.uniform(-1, 1), g.uniform(-1, 1), g.uniform(-1, 1)};
        if (t == &pair.b) p[2] += 2 + gap;
        p = rotation(p);
        v = {offset + scale * p[0], offset + scale * p[1], offset + scale * p[2]};
      }
    return pair;
  }
  const std::int64_t range = g.coin() ? 8 : (std::int64_t(1) << 20);
  const ExactTransform transform = random_exact_transform(g);
  const Triangle a = lattice_triangle(g, range);
  Triangle b;
  switch (family) {
    case 1:  // touching: a vertex of b on a
      b = {dyadic_point_on(g, a, int(g.integer(0, 2))), lattice_point(g, range), lattice_point(g, range)};
      break;
    case 2: {  // parallel: b in a's plane shifted along a lattice vector
      const Point shift = lattice_point(g, range);
      for (int v = 0; v < 3; ++v) {
        const Point p = dyadic_point_on(g, a, 3);
        b[v] = {p[0] + shift[0], p[1] + shift[1], p[2] + shift[2]};
      }
      break;
    }
    default:  // random lattice pairs
      b = lattice_triangle(g, range);
  }
  Pair pair{transform(a), transform(b)};
  if (family == 1 && g.coin()) pair.b[0] = nudge(g, pair.b[0]);
  return pair;
}

TEST(TriangleDistance, BoundsBracketTheExactDistance) {
  constexpr std::uint64_t kCases = 24000;
  Disagreements disagreements("triangle_distance bounds");
  std::uint64_t tested = 0, generic = 0, loose = 0;
  for (std::uint64_t c = 0; c < kCases; ++c) {
    Generator g(c);
    const int family = int(c % 4);
    const Pair pair = distance_case(g, family);
    if (epeck_degenerate(pair.a) || epeck_degenerate(pair.b)) continue;
    const Epeck::FT exact = CGAL::squared_distance(to_epeck(pair.a), to_epeck(pair.b));
    const TriangleDistance d = triangle_distance(pair.a, pair.b);
    const Epeck::FT lower(d.lower_bound), upper(d.upper_bound);
    ++tested;
    const bool ordered = d.lower_bound <= d.distance && d.distance <= d.upper_bound;
    const bool bracketed = lower * lower <= exact && exact <= upper * upper;
    const bool zero_iff_touching = (exact == 0) == (d.upper_bound == 0);
    // within_distance never misses: at (an upper rounding of) the true distance, it says yes.
    const double at_least_true =
        std::nextafter(std::sqrt(CGAL::to_interval(exact).second), INFINITY);
    const bool never_misses = within_distance(pair.a, pair.b, at_least_true) &&
                              (exact != 0 || within_distance(pair.a, pair.b, 0.0));
    if (!ordered || !bracketed || !zero_iff_touching || !never_misses)
      disagreements.add(c, "a " + hex(pair.a) + " b " + hex(pair.b) + " lower " +
                               std::to_string(d.lower_bound) + " distance " +
                               std::to_string(d.distance) + " upper " + std::to_string(d.upper_bound) +
                               " exact^2 " + std::to_string(CGAL::to_double(exact)));
    if (family == 0) {
      ++generic;
      // Tightness on generic pairs: the bounds are within a millionth of the distance.
      loose += d.upper_bound - d.lower_bound > 1e-6 * d.distance;
    }
  }
  disagreements.expect_none(tested);
  EXPECT_LT(loose, generic / 100) << loose << " loose bounds in " << generic << " generic pairs";
}

TEST(TriangleDistance, WithinDistanceRejectsClearlyFartherPairs) {
  // Not a correctness requirement (within_distance may say yes slightly beyond d), but the
  // clearance mode is useless if it says yes far beyond d: check at half the lower bound.
  constexpr std::uint64_t kCases = 20000;
  std::uint64_t separated = 0, accepted = 0;
  for (std::uint64_t c = 0; c < kCases; ++c) {
    Generator g(c);
    const Pair pair = distance_case(g, 0);
    const TriangleDistance d = triangle_distance(pair.a, pair.b);
    if (!(d.lower_bound > 0)) continue;
    ++separated;
    accepted += within_distance(pair.a, pair.b, 0.5 * d.lower_bound);
    EXPECT_TRUE(within_distance(pair.a, pair.b, d.upper_bound)) << "seed " << c;
  }
  EXPECT_GT(separated, kCases / 2);
  EXPECT_EQ(accepted, 0u);
}

// triangle_outside_ball prunes phase I's candidates for round objects: it must never call a
// triangle outside a ball that it reaches (CGAL's exact squared distance), and must prune
// what lies clearly outside, or it is useless.
TEST(TriangleOutsideBall, NeverPrunesATriangleThatReachesTheBall) {
  constexpr std::uint64_t kCases = 30000;
  Disagreements disagreements("triangle_outside_ball");
  std::uint64_t tested = 0, clearly_outside = 0, pruned_clearly_outside = 0;
  for (std::uint64_t c = 0; c < kCases; ++c) {
    Generator g(c);
    const int family = int(c % 4);
    const Triangle t = distance_case(g, family).a;
    // The centre: near the triangle's plane, on it (a vertex, an edge, inside), or anywhere.
    Point centre;
    switch (int(g.integer(0, 3))) {
      case 0: centre = dyadic_point_on(g, t, int(g.integer(0, 3))); break;
      case 1: centre = nudge(g, dyadic_point_on(g, t, int(g.integer(0, 3)))); break;
      case 2: centre = distance_case(g, family).b[0]; break;
      default: {
        const Point p = dyadic_point_on(g, t, 3);
        const double away = g.log_uniform(-9, 9);
        centre = {p[0] + away * g.uniform(-1, 1), p[1] + away * g.uniform(-1, 1), p[2] + away * g.uniform(-1, 1)};
      }
    }
    if (epeck_degenerate(t)) {
      // Segments and points are never pruned (no plane to take the distance from).
      if (triangle_outside_ball(t, centre, 0.0)) disagreements.add(c, "degenerate " + hex(t) + " pruned");
      continue;
    }
    const Epeck::FT exact = CGAL::squared_distance(to_epeck(centre), to_epeck(t));
    const double distance = std::sqrt(CGAL::to_double(exact));
    ++tested;
    // Radii at the exact distance (rounded either way), just inside and outside it.
    for (const double radius : {std::nextafter(distance, 0.0), distance, std::nextafter(distance, INFINITY),
                                distance * (1 - 1e-12), distance * (1 + 1e-12), 0.5 * distance, 0.99 * distance,
                                2 * distance}) {
      const bool outside = triangle_outside_ball(t, centre, radius);
      if (outside && !(Epeck::FT(radius) * Epeck::FT(radius) < exact))
        disagreements.add(c, "t " + hex(t) + " centre " + hex(centre) + " radius " + std::to_string(radius) +
                                 " pruned, exact distance^2 " + std::to_string(CGAL::to_double(exact)));
    }
    // Well-shaped triangles outside a ball, by more than the margin (a millionth of the sizes),
    // are pruned.
    double longest = 0;
    for (int k = 0; k < 3; ++k)
      longest = std::max(longest, std::sqrt(CGAL::to_double(CGAL::squared_distance(to_epeck(t[k]), to_epeck(t[(k + 1) % 3])))));
    if (family == 0 && distance > 1e-3 * longest) {
      ++clearly_outside;
      pruned_clearly_outside += triangle_outside_ball(t, centre, 0.99 * distance);
    }
  }
  disagreements.expect_none(tested);
  EXPECT_GT(clearly_outside, kCases / 8);
  EXPECT_GT(pruned_clearly_outside, clearly_outside * 9 / 10)
      << pruned_clearly_outside << " of " << clearly_outside << " triangles outside 0.99 of their distance pruned";
  // Non-finite input is never pruned.
  const Triangle unit{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}};
  EXPECT_FALSE(triangle_outside_ball(unit, {NAN, 5, 5}, 1.0));
  EXPECT_FALSE(triangle_outside_ball(unit, {5, 5, 5}, NAN));
  EXPECT_FALSE(triangle_outside_ball({{{0, 0, 0}, {1, 0, 0}, {INFINITY, 1, 0}}}, {5, 5, 5}, 1.0));
  EXPECT_TRUE(triangle_outside_ball(unit, {5, 5, 5}, 1.0));
  EXPECT_FALSE(triangle_outside_ball(unit, {0.25, 0.25, 0.5}, 0.5));
}

}  // namespace
}  // namespace tetrapage::geometry
