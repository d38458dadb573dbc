// Exact triangle/triangle intersection against CGAL's exact-construction kernel, on random and
// adversarial pairs: shared vertices and edges, touching contacts built exactly (dyadic points
// on lattice triangles), coplanar and near-coplanar pairs, slivers, needles, scales from 1e-9
// to 1e9 and offsets up to 1e9.

#include "tetrapage/runtime/geometry/TriangleTriangle.h"

#include "GeometryTestSupport.h"

namespace tetrapage::geometry {
namespace {

using namespace testing;

struct Pair {
  Triangle a, b;
};

constexpr int kFamilies = 11;

Pair triangle_pair(Generator& g, int family) {
  const std::int64_t range = g.coin() ? 8 : (std::int64_t(1) << 20);
  if (family == 0) {  // generic: random doubles, rotated, any scale, any offset
    const double scale = g.log_uniform(-9, 9);
    const double offset = g.coin() ? 0.0 : g.log_uniform(6, 9) * (g.coin() ? 1 : -1);
    const Rotation rotation = random_rotation(g);
    Pair pair;
    for (auto* t : {&pair.a, &pair.b})
      for (auto& v : *t) {
        const Point p = rotation({g.uniform(-1, 1), g.uniform(-1, 1), g.uniform(-0.2, 0.2)});
        v = {offset + scale * p[0], offset + scale * p[1], offset + scale * p[2]};
      }
    return pair;
  }
  const ExactTransform transform = random_exact_transform(g);
  Triangle a = lattice_triangle(g, range);
  Triangle b;
  const int rotation = int(g.integer(0, 2));
  switch (family) {
    case 1:  // a shared vertex
      b = {a[rotation], lattice_point(g, range), lattice_point(g, range)};
      break;
    case 2:  // a shared edge; the third vertex sometimes in the plane
      b = {a[rotation], a[(rotation + 1) % 3],
           g.coin() ? lattice_point(g, range) : dyadic_point_on(g, a, 3)};
      if (g.coin()) std::swap(b[0], b[1]);
      break;
    case 3:  // a vertex of b on a: interior, edge or vertex
      b = {dyadic_point_on(g, a, int(g.integer(0, 2))), lattice_point(g, range),
           lattice_point(g, range)};
      break;
    case 4: {  // an edge of b through a point of a (an edge point, an interior point, a vertex)
      const Point x = dyadic_point_on(g, a, int(g.integer(0, 2)));
      const Point w = lattice_point(g, range);
      Point p, q;
      for (int k = 0; k < 3; ++k) {
        p[k] = x[k] + w[k];
        q[k] = x[k] - w[k];
      }
      b = {p, q, lattice_point(g, range)};
      break;
    }
    case 5:  // an edge of b in a's plane, the third vertex off it (edge contact or crossing)
      b = {dyadic_point_on(g, a, int(g.integer(0, 3))), dyadic_point_on(g, a, 3),
           lattice_point(g, range)};
      break;
    case 6:  // coplanar
    case 7:  // near-coplanar (nudged below)
      b = {dyadic_point_on(g, a, int(g.integer(0, 3))), dyadic_point_on(g, a, 3),
           dyadic_point_on(g, a, 3)};
      break;
    case 8: {  // near-touching: families 3 and 4, nudged below
      b = {dyadic_point_on(g, a, int(g.integer(0, 2))), lattice_point(g, range),
           lattice_point(g, range)};
      break;
    }
    case 9:  // slivers and needles against each other
      b = lattice_triangle(g, range);
      b[0] = dyadic_point_on(g, a, int(g.integer(0, 3)));
      break;
    default:  // random lattice triangles, small lattices give many coincidences
      b = lattice_triangle(g, range);
  }
  Pair pair{transform(a), transform(b)};
  if (family == 7 || family == 8 || (family >= 1 && g.integer(0, 3) == 0)) {
    auto& t = g.coin() ? pair.a : pair.b;
    const int v = int(g.integer(0, 2));
    t[v] = nudge(g, t[v]);
  }
  if (g.coin()) std::swap(pair.a, pair.b);
  return pair;
}

bool straddles(const std::array<CGAL::Orientation, 3>& s) {
  bool positive = false, negative = false;
  for (auto x : s) {
    positive = positive || x == CGAL::POSITIVE;
    negative = negative || x == CGAL::NEGATIVE;
  }
  return positive && negative;
}

// The oracle: do_intersect for the answer; the dimension of CGAL's constructed intersection
// and the exact sides for the class.
TriangleContact epeck_contact(const Triangle& a, const Triangle& b) {
  const auto ea = to_epeck(a), eb = to_epeck(b);
  if (!CGAL::do_intersect(ea, eb)) return TriangleContact::none;
  std::array<CGAL::Orientation, 3> sa, sb;
  for (int i = 0; i < 3; ++i) {
    sa[i] = CGAL::orientation(eb[0], eb[1], eb[2], ea[i]);
    sb[i] = CGAL::orientation(ea[0], ea[1], ea[2], eb[i]);
  }
  if (sb[0] == CGAL::ZERO && sb[1] == CGAL::ZERO && sb[2] == CGAL::ZERO)
    return TriangleContact::coplanar;
  const auto result = CGAL::intersection(ea, eb);
  if (!result) return TriangleContact::none;  // cannot happen after do_intersect
  if (boost::get<Epeck::Point_3>(&*result)) return TriangleContact::point;
  if (boost::get<Epeck::Segment_3>(&*result))
    return straddles(sa) && straddles(sb) ? TriangleContact::crossing : TriangleContact::edge;
  return TriangleContact::degenerate_triangle;  // a polygon: impossible when not coplanar
}

std::string describe(const Pair& p) { return "a " + hex(p.a) + " b " + hex(p.b); }

void check_boolean(int first_family, int last_family, std::uint64_t cases_per_family) {
  // Families of shared features always touch; misses must occur over the whole test.
  std::uint64_t all_tested = 0, all_intersecting = 0;
  for (int family = first_family; family <= last_family; ++family) {
    Disagreements disagreements("triangles_intersect family " + std::to_string(family));
    std::uint64_t tested = 0, intersecting = 0;
    for (std::uint64_t c = 0; c < cases_per_family; ++c) {
      const std::uint64_t seed = 7000000 * std::uint64_t(family) + c;
      Generator g(seed);
      const Pair pair = triangle_pair(g, family);
      if (epeck_degenerate(pair.a) || epeck_degenerate(pair.b)) continue;
      const bool expected = CGAL::do_intersect(to_epeck(pair.a), to_epeck(pair.b));
      const bool got = triangles_intersect(pair.a, pair.b);
      const bool symmetric = triangles_intersect(pair.b, pair.a);
      // Any vertex order is the same question.
      const bool rotated = triangles_intersect({pair.a[1], pair.a[2], pair.a[0]},
                                               {pair.b[0], pair.b[2], pair.b[1]});
      ++tested;
      intersecting += expected;
      if (got != expected || symmetric != expected || rotated != expected)
        disagreements.add(seed, describe(pair) + " expected " + std::to_string(expected));
    }
    disagreements.expect_none(tested);
    // Every family must hit; the misses are checked over the whole test below.
    EXPECT_GT(intersecting, tested / 1000) << "family " << family;
    all_tested += tested;
    all_intersecting += intersecting;
  }
  EXPECT_LT(all_intersecting, all_tested - all_tested / 100);
}

TEST(TriangleTriangle, GenericAndSharedFeaturesMatchEpeck) { check_boolean(0, 2, 130000); }
TEST(TriangleTriangle, TouchingContactsMatchEpeck) { check_boolean(3, 5, 130000); }
TEST(TriangleTriangle, CoplanarAndNearCoplanarMatchEpeck) { check_boolean(6, 8, 130000); }
TEST(TriangleTriangle, SliversNeedlesAndSmallLatticesMatchEpeck) { check_boolean(9, 10, 130000); }

TEST(TriangleTriangle, ClassificationMatchesEpeckIntersection) {
  constexpr std::uint64_t kCasesPerFamily = 6000;
  Disagreements disagreements("classify_triangles");
  std::uint64_t tested = 0;
  std::array<std::uint64_t, 6> seen{};
  for (int family = 0; family < kFamilies; ++family)
    for (std::uint64_t c = 0; c < kCasesPerFamily; ++c) {
      const std::uint64_t seed = 9000000 * std::uint64_t(family) + c;
      Generator g(seed);
      const Pair pair = triangle_pair(g, family);
      if (epeck_degenerate(pair.a) || epeck_degenerate(pair.b)) continue;
      const TriangleContact expected = epeck_contact(pair.a, pair.b);
      const TriangleContact got = classify_triangles(pair.a, pair.b);
      ++tested;
      ++seen[std::size_t(expected)];
      if (got != expected)
        disagreements.add(seed, describe(pair) + " expected " + std::to_string(int(expected)) +
                                    " got " + std::to_string(int(got)));
    }
  disagreements.expect_none(tested);
  for (int k = 0; k < 5; ++k) EXPECT_GT(seen[std::size_t(k)], 100u) << "class " << k << " rarely seen";
}

// Degenerate triangles are the union of their edges: the oracle tests those segments (and a
// repeated vertex as a point) with CGAL.
bool epeck_degenerate_meet(const Triangle& a, const Triangle& b) {
  auto pieces_meet = [](const Triangle& degenerate, const Triangle& other) {
    const bool other_degenerate = epeck_degenerate(other);
    for (int i = 0; i < 3; ++i) {
      const auto p = to_epeck(degenerate[i]), q = to_epeck(degenerate[(i + 1) % 3]);
      if (p == q) {
        if (!other_degenerate ? to_epeck(other).has_on(p) : false) return true;
        for (int j = 0; j < 3 && other_degenerate; ++j) {
          const auto r = to_epeck(other[j]), s = to_epeck(other[(j + 1) % 3]);
          if (r == s ? r == p : Epeck::Segment_3(r, s).has_on(p)) return true;
        }
        continue;
      }
      const Epeck::Segment_3 segment(p, q);
      if (!other_degenerate) {
        if (CGAL::do_intersect(segment, to_epeck(other))) return true;
        continue;
      }
      for (int j = 0; j < 3; ++j) {
        const auto r = to_epeck(other[j]), s = to_epeck(other[(j + 1) % 3]);
        if (r == s ? segment.has_on(r) : CGAL::do_intersect(segment, Epeck::Segment_3(r, s)))
          return true;
      }
    }
    return false;
  };
  return epeck_degenerate(a) ? pieces_meet(a, b) : pieces_meet(b, a);
}

TEST(TriangleTriangle, DegenerateTrianglesAreTheirEdges) {
  constexpr std::uint64_t kCases = 60000;
  Disagreements disagreements("degenerate triangles");
  std::uint64_t tested = 0, meeting = 0;
  for (std::uint64_t c = 0; c < kCases; ++c) {
    Generator g(c);
    const ExactTransform transform = random_exact_transform(g);
    const std::int64_t range = c % 2 ? 4 : 1000;
    Triangle a = lattice_triangle(g, range), b = lattice_triangle(g, range);
    // Make a (and sometimes b) degenerate: collinear, or a repeated vertex.
    a[2] = c % 3 ? dyadic_combination(a[0], a[1], a[1], g.integer(-256, 512), 0, 8) : a[0];
    if (c % 5 == 0) b[2] = dyadic_combination(b[0], b[1], b[1], g.integer(-256, 512), 0, 8);
    if (c % 4 == 0) b[0] = dyadic_point_on(g, {a[0], a[1], a[1]}, 1);  // touch a's segment
    const Pair pair{transform(a), transform(b)};
    const bool expected = epeck_degenerate_meet(pair.a, pair.b);
    const bool got = triangles_intersect(pair.a, pair.b);
    const TriangleContact contact = classify_triangles(pair.b, pair.a);
    ++tested;
    meeting += expected;
    if (got != expected ||
        (contact == TriangleContact::degenerate_triangle) != expected)
      disagreements.add(c, describe(pair) + " expected " + std::to_string(expected));
  }
  disagreements.expect_none(tested);
  EXPECT_GT(meeting, tested / 20);
}

}  // namespace
}  // namespace tetrapage::geometry
