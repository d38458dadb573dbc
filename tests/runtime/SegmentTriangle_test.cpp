// Exact segment/triangle intersection and its classification against CGAL's exact kernel:
// segments through interiors, edges and vertices, ending on the triangle, lying in its plane,
// and a few units in the last place away from each of those.

#include "tetrapage/runtime/geometry/SegmentTriangle.h"

#include "GeometryTestSupport.h"

namespace tetrapage::geometry {
namespace {

using namespace testing;

struct Case {
  Segment s;
  Triangle t;
};

Case segment_case(Generator& g, int family) {
  const std::int64_t range = g.coin() ? 8 : (std::int64_t(1) << 20);
  if (family == 0) {  // generic
    const double scale = g.log_uniform(-9, 9);
    const double offset = g.coin() ? 0.0 : g.log_uniform(6, 9) * (g.coin() ? 1 : -1);
    Case c;
    for (auto& v : c.t)
      for (double& x : v) x = offset + scale * g.uniform(-1, 1);
    for (auto& v : c.s)
      for (double& x : v) x = offset + scale * g.uniform(-1, 1);
    return c;
  }
  const ExactTransform transform = random_exact_transform(g);
  const Triangle t = lattice_triangle(g, range);
  Segment s;
  const int where = int(g.integer(0, 2));  // through the interior, an edge or a vertex
  switch (family) {
    case 1: {  // through a point of the triangle: p = x + w, q = x - k w
      const Point x = dyadic_point_on(g, t, where);
      const Point w = lattice_point(g, range);
      const double k = double(g.integer(1, 3));
      for (int i = 0; i < 3; ++i) {
        s[0][i] = x[i] + w[i];
        s[1][i] = x[i] - k * w[i];
      }
      break;
    }
    case 2:  // ending on the triangle
      s = {dyadic_point_on(g, t, where), lattice_point(g, range)};
      break;
    case 3:  // in the triangle's plane
      s = {dyadic_point_on(g, t, 3), dyadic_point_on(g, t, 3)};
      break;
    default:  // families 1-3 again, then nudged
      return segment_case(g, int(g.integer(1, 3)));
  }
  Case c{transform(s), transform(t)};
  if (family == 4 || g.integer(0, 7) == 0) {
    Point& p = g.coin() ? c.s[g.integer(0, 1)] : c.t[g.integer(0, 2)];
    p = nudge(g, p);
  }
  return c;
}

// The oracle for the classified answer, from CGAL's constructed intersection.
SegmentTriangleHit epeck_hit(const Segment& s, const Triangle& t) {
  const auto es = to_epeck(s);
  const auto et = to_epeck(t);
  if (!CGAL::do_intersect(es, et)) return {};
  if (CGAL::orientation(et[0], et[1], et[2], es[0]) == CGAL::ZERO &&
      CGAL::orientation(et[0], et[1], et[2], es[1]) == CGAL::ZERO)
    return {SegmentTriangleContact::coplanar, 0, false};
  const auto result = CGAL::intersection(es, et);
  const auto* x = boost::get<Epeck::Point_3>(&*result);
  if (!x) return {SegmentTriangleContact::degenerate_triangle, 0, false};  // impossible here
  const bool at_endpoint = *x == es[0] || *x == es[1];
  for (std::uint8_t v = 0; v < 3; ++v)
    if (*x == et[v]) return {SegmentTriangleContact::vertex, v, at_endpoint};
  for (std::uint8_t e = 0; e < 3; ++e)
    if (Epeck::Segment_3(et[e], et[(e + 1) % 3]).has_on(*x))
      return {SegmentTriangleContact::edge, e, at_endpoint};
  return {SegmentTriangleContact::interior, 0, at_endpoint};
}

TEST(SegmentTriangle, MatchesEpeckOnAdversarialInputs) {
  constexpr int kFamilies = 5;
  constexpr std::uint64_t kCasesPerFamily = 120000;
  for (int family = 0; family < kFamilies; ++family) {
    Disagreements disagreements("segment_intersects_triangle family " + std::to_string(family));
    std::uint64_t tested = 0, hits = 0;
    for (std::uint64_t c = 0; c < kCasesPerFamily; ++c) {
      const std::uint64_t seed = 5000000 * std::uint64_t(family) + c;
      Generator g(seed);
      const Case k = segment_case(g, family);
      if (epeck_degenerate(k.t) || k.s[0] == k.s[1]) continue;
      const bool expected = CGAL::do_intersect(to_epeck(k.s), to_epeck(k.t));
      const bool got = segment_intersects_triangle(k.s, k.t);
      const bool reversed = segment_intersects_triangle({k.s[1], k.s[0]}, {k.t[2], k.t[1], k.t[0]});
      ++tested;
      hits += expected;
      if (got != expected || reversed != expected)
        disagreements.add(seed, "segment " + hex(k.s) + " triangle " + hex(k.t));
    }
    disagreements.expect_none(tested);
    EXPECT_GT(hits, tested / 50) << "family " << family;
    EXPECT_LT(hits, tested - tested / 50) << "family " << family;
  }
}

TEST(SegmentTriangle, ClassificationMatchesEpeckIntersection) {
  constexpr std::uint64_t kCases = 40000;
  Disagreements disagreements("classify_segment_triangle");
  std::uint64_t tested = 0;
  std::array<std::uint64_t, 5> seen{};
  for (std::uint64_t c = 0; c < kCases; ++c) {
    Generator g(c);
    const Case k = segment_case(g, int(c % 5));
    if (epeck_degenerate(k.t) || k.s[0] == k.s[1]) continue;
    const SegmentTriangleHit expected = epeck_hit(k.s, k.t);
    const SegmentTriangleHit got = classify_segment_triangle(k.s, k.t);
    ++tested;
    ++seen[std::size_t(expected.contact)];
    const bool one_point = expected.contact == SegmentTriangleContact::interior ||
                           expected.contact == SegmentTriangleContact::edge ||
                           expected.contact == SegmentTriangleContact::vertex;
    if (got.contact != expected.contact ||
        (one_point && (got.feature != expected.feature || got.at_endpoint != expected.at_endpoint)))
      disagreements.add(c, "segment " + hex(k.s) + " triangle " + hex(k.t) + " expected " +
                               std::to_string(int(expected.contact)) + "/" +
                               std::to_string(expected.feature) + "/" +
                               std::to_string(expected.at_endpoint) + " got " +
                               std::to_string(int(got.contact)) + "/" +
                               std::to_string(got.feature) + "/" + std::to_string(got.at_endpoint));
  }
  disagreements.expect_none(tested);
  for (int k = 0; k < 5; ++k) EXPECT_GT(seen[std::size_t(k)], 200u) << "class " << k << " rarely seen";
}

TEST(SegmentTriangle, DegenerateInputsAreHandledExactly) {
  // A point segment is a point; a collinear triangle is its edges.
  constexpr std::uint64_t kCases = 30000;
  Disagreements disagreements("degenerate segment/triangle");
  for (std::uint64_t c = 0; c < kCases; ++c) {
    Generator g(c);
    const ExactTransform transform = random_exact_transform(g);
    Triangle t = lattice_triangle(g, 6);
    Segment s{dyadic_point_on(g, t, int(g.integer(0, 3))), lattice_point(g, 6)};
    bool expected = false;
    if (c % 2 == 0) {  // point segment against a proper triangle
      s[1] = s[0];
      if (epeck_degenerate(t)) continue;
      expected = to_epeck(transform(t)).has_on(to_epeck(transform(s[0])));
    } else {  // a proper segment against a collinear triangle
      t[2] = dyadic_combination(t[0], t[1], t[1], g.integer(-128, 384), 0, 7);
      if (s[0] == s[1]) continue;
      const auto es = to_epeck(transform(s));
      for (int e = 0; e < 3; ++e) {
        const auto p = to_epeck(transform(t[e])), q = to_epeck(transform(t[(e + 1) % 3]));
        expected = expected || (p == q ? es.has_on(p) : CGAL::do_intersect(es, Epeck::Segment_3(p, q)));
      }
    }
    if (segment_intersects_triangle(transform(s), transform(t)) != expected)
      disagreements.add(c, "segment " + hex(transform(s)) + " triangle " + hex(transform(t)));
  }
  disagreements.expect_none(kCases);
}

}  // namespace
}  // namespace tetrapage::geometry
