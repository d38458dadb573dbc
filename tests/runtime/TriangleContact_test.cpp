// The contact geometry of two triangles against CGAL's exact-construction kernel: the same
// kind of intersection (none, point, segment, polygon with the same number of corners), every
// constructed point within the stated bound of the exact one (compared exactly), polygons in
// order about the first normal, segments along n1 x n2, and normals equal to the exact unit
// normals; on generic, touching, coplanar and degenerate pairs at scales 2^-30 (~1e-9), 1,
// 2^30 (~1e9) and for unit triangles 1e6 away from the origin.

#include "tetrapage/runtime/geometry/TriangleContact.h"

#include <CGAL/intersections.h>

#include <algorithm>
#include <span>

#include "GeometryTestSupport.h"
#include "tetrapage/runtime/geometry/TriangleTriangle.h"

namespace tetrapage::geometry {
namespace {

using namespace testing;
using FT = Epeck::FT;
using EPoint = Epeck::Point_3;
using EVector = Epeck::Vector_3;

struct Pair {
  Triangle a, b;
};

// ---- The oracle ---------------------------------------------------------------------------

// A degenerate triangle is the segment its extreme vertices span (lexicographic order is the
// order along the line), or a point.
std::vector<EPoint> hull_of_degenerate(const Triangle& t) {
  auto less = [](const Point& x, const Point& y) { return x < y; };  // lexicographic
  const auto [lo, hi] = std::minmax_element(t.begin(), t.end(), less);
  if (*lo == *hi) return {to_epeck(*lo)};
  return {to_epeck(*lo), to_epeck(*hi)};
}

// The corners of the exact intersection, in CGAL's order; empty when they do not meet.
struct ExactPoints {
  std::vector<EPoint> points;
  void operator()(const EPoint& p) { points = {p}; }
  void operator()(const Epeck::Segment_3& s) { points = {s.source(), s.target()}; }
  void operator()(const Epeck::Triangle_3& t) { points = {t[0], t[1], t[2]}; }
  void operator()(const std::vector<EPoint>& polygon) {
    for (const EPoint& p : polygon)  // merge repeats, should CGAL report any
      if (std::find(points.begin(), points.end(), p) == points.end()) points.push_back(p);
  }
};

template <class A, class B>
std::vector<EPoint> exact_intersection(const A& a, const B& b) {
  ExactPoints visitor;
  if (const auto result = CGAL::intersection(a, b)) boost::apply_visitor(visitor, *result);
  return visitor.points;
}

// Pieces given by one or two exact points (a point or a segment) against a piece or a triangle.
std::vector<EPoint> piece_intersection(const std::vector<EPoint>& p, const Triangle& other) {
  if (!epeck_degenerate(other)) {
    const auto t = to_epeck(other);
    if (p.size() == 1) return t.has_on(p[0]) ? p : std::vector<EPoint>{};
    return exact_intersection(Epeck::Segment_3(p[0], p[1]), t);
  }
  const std::vector<EPoint> q = hull_of_degenerate(other);
  if (p.size() == 1 && q.size() == 1) return p[0] == q[0] ? p : std::vector<EPoint>{};
  if (p.size() == 1) return Epeck::Segment_3(q[0], q[1]).has_on(p[0]) ? p : std::vector<EPoint>{};
  if (q.size() == 1) return Epeck::Segment_3(p[0], p[1]).has_on(q[0]) ? q : std::vector<EPoint>{};
  return exact_intersection(Epeck::Segment_3(p[0], p[1]), Epeck::Segment_3(q[0], q[1]));
}

std::vector<EPoint> oracle(const Pair& pair) {
  if (epeck_degenerate(pair.a)) return piece_intersection(hull_of_degenerate(pair.a), pair.b);
  if (epeck_degenerate(pair.b)) return piece_intersection(hull_of_degenerate(pair.b), pair.a);
  return exact_intersection(to_epeck(pair.a), to_epeck(pair.b));
}

EVector exact_normal(const Triangle& t) {
  const auto e = to_epeck(t);
  return CGAL::cross_product(e[1] - e[0], e[2] - e[0]);
}

// The exact normal, normalised in double (each step within a few u).
Vec3 reference_unit_normal(const Triangle& t) {
  const EVector n = exact_normal(t);
  // CGAL::to_double of a lazy number is its interval's approximation: round the exact value.
  Vec3 v{CGAL::to_double(CGAL::exact(n.x())), CGAL::to_double(CGAL::exact(n.y())),
         CGAL::to_double(CGAL::exact(n.z()))};
  const double largest = std::max({std::fabs(v[0]), std::fabs(v[1]), std::fabs(v[2])});
  if (largest == 0) return {0, 0, 0};
  for (double& x : v) x /= largest;
  const double length = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  for (double& x : v) x /= length;
  return v;
}

// ---- The comparison -----------------------------------------------------------------------

double largest_coordinate(const Pair& pair) {
  double m = 0;
  for (const auto* t : {&pair.a, &pair.b})
    for (const Point& p : *t)
      for (double x : p) m = std::max(m, std::fabs(x));
  return m;
}

// Exactly: every coordinate of `got` within `bound` of `exact`.
bool within(const Point& got, const EPoint& exact, double bound) {
  for (int k = 0; k < 3; ++k)
    if (CGAL::abs(FT(got[k]) - exact[k]) > FT(bound)) return false;
  return true;
}

double error_of(const Point& got, const EPoint& exact) {
  double e = 0;
  for (int k = 0; k < 3; ++k)
    e = std::max(e, std::fabs(got[k] - CGAL::to_double(CGAL::exact(exact[k]))));
  return e;
}

struct Statistics {
  std::array<std::uint64_t, 4> shapes{};    // by ContactShape
  std::array<std::uint64_t, 7> polygons{};  // by corner count
  std::uint64_t coplanar = 0, degenerate = 0;
  std::uint64_t loosely_ordered = 0;  // polygons ordered only up to corners within the bound
  double worst_relative_error = 0;    // over M
};

// The computed points equal the exact corners in order, up to a cyclic shift when
// `any_shift` (a polygon's start, or a segment's direction), each within the bound.
bool match_in_order(const ContactGeometry& got, const std::vector<EPoint>& exact, bool any_shift,
                    double bound) {
  const std::size_t n = exact.size();
  if (n == 0) return got.count == 0;
  for (std::size_t shift = 0; shift < (any_shift ? n : 1); ++shift) {
    bool all = true;
    for (std::size_t i = 0; i < n && all; ++i)
      all = within(got.points[i], exact[(shift + i) % n], bound);
    if (all) return true;
  }
  return false;
}

// Polygon corners closer together than the error bound may come in either order (their
// computed positions may be in either order too). So when the strict order fails: some
// matching within the bound, and every turn counterclockwise that involves no two such
// corners.
bool match_polygon_loosely(const ContactGeometry& got, const std::vector<EPoint>& exact,
                           const EVector& normal, double bound) {
  auto close = [&](const EPoint& x, const EPoint& y) {
    return error_of({CGAL::to_double(CGAL::exact(x.x())), CGAL::to_double(CGAL::exact(x.y())),
                     CGAL::to_double(CGAL::exact(x.z()))},
                    y) <= 2 * bound;
  };
  std::vector<std::size_t> index(exact.size());
  for (std::size_t i = 0; i < index.size(); ++i) index[i] = i;
  do {
    bool ok = true;
    for (std::size_t i = 0; i < index.size() && ok; ++i)
      ok = within(got.points[i], exact[index[i]], bound);
    for (std::size_t i = 0; i < index.size() && ok; ++i) {
      const EPoint& p = exact[index[i]];
      const EPoint& q = exact[index[(i + 1) % index.size()]];
      const EPoint& r = exact[index[(i + 2) % index.size()]];
      if (close(p, q) || close(q, r) || close(p, r)) continue;
      ok = CGAL::scalar_product(CGAL::cross_product(q - p, r - p), normal) > 0;
    }
    if (ok) return true;
  } while (std::next_permutation(index.begin(), index.end()));
  return false;
}

// The corners of a convex polygon counterclockwise about `normal`: by angle seen from one of
// them (all others lie within a half-turn), compared exactly.
std::vector<EPoint> counterclockwise(std::vector<EPoint> corners, const EVector& normal) {
  const EPoint origin = corners[0];
  std::sort(corners.begin() + 1, corners.end(), [&](const EPoint& x, const EPoint& y) {
    return CGAL::scalar_product(CGAL::cross_product(x - origin, y - origin), normal) > 0;
  });
  return corners;
}

ContactShape expected_shape(std::size_t corners) {
  return corners == 0   ? ContactShape::none
         : corners == 1 ? ContactShape::point
         : corners == 2 ? ContactShape::segment
                        : ContactShape::polygon;
}

bool normal_matches(const Vec3& got, const Vec3& expected) {
  for (int k = 0; k < 3; ++k)
    if (!(std::fabs(got[k] - expected[k]) <= 1e-12)) return false;
  return true;
}

// Everything about one pair; an empty string when all holds.
std::string check_pair(const Pair& pair, Statistics& stats) {
  const ContactGeometry got = contact_geometry(pair.a, pair.b);
  const std::vector<EPoint> exact = oracle(pair);
  const bool degenerate = epeck_degenerate(pair.a) || epeck_degenerate(pair.b);
  stats.degenerate += degenerate;
  ++stats.shapes[std::size_t(got.shape)];
  if (got.shape == ContactShape::polygon) ++stats.polygons[std::min<std::size_t>(got.count, 6)];
  if ((got.shape != ContactShape::none) != triangles_intersect(pair.a, pair.b))
    return "disagrees with triangles_intersect";
  if (got.shape != expected_shape(exact.size()) || got.count != exact.size())
    return "shape " + std::to_string(int(got.shape)) + " count " + std::to_string(got.count) +
           ", exact has " + std::to_string(exact.size()) + " corners";
  if (contact_geometry(pair.b, pair.a).shape != got.shape) return "not symmetric";
  if (!normal_matches(got.first_normal, reference_unit_normal(pair.a)) ||
      !normal_matches(got.second_normal, reference_unit_normal(pair.b)))
    return "normal off";
  const auto na = exact_normal(pair.a), nb = exact_normal(pair.b);
  const bool coplanar = !degenerate && CGAL::cross_product(na, nb) == CGAL::NULL_VECTOR &&
                        CGAL::coplanar(to_epeck(pair.a[0]), to_epeck(pair.a[1]),
                                       to_epeck(pair.a[2]), to_epeck(pair.b[0]));
  stats.coplanar += coplanar;
  if (got.coplanar != coplanar) return "coplanar flag wrong";
  for (std::size_t i = 0; i < got.count; ++i)
    if (!is_finite(got.points[i])) return "a point is not finite";
  const double bound = kContactPointRelativeError * largest_coordinate(pair);
  std::vector<EPoint> ordered = exact;
  bool any_shift = true;
  if (got.shape == ContactShape::segment && !coplanar && !degenerate) {
    // Along d = n1 x n2, decided exactly.
    if (CGAL::scalar_product(ordered[1] - ordered[0], CGAL::cross_product(na, nb)) < 0)
      std::swap(ordered[0], ordered[1]);
    any_shift = false;
  } else if (got.shape == ContactShape::polygon) {
    ordered = counterclockwise(ordered, na);
  }
  const bool strict = match_in_order(got, ordered, any_shift, bound);
  const bool loose =
      !strict && got.shape == ContactShape::polygon && match_polygon_loosely(got, exact, na, bound);
  stats.loosely_ordered += loose;
  if (!strict && !loose)
    return got.shape == ContactShape::polygon || !any_shift
               ? "points out of order or farther than the bound from the exact ones"
               : "a point is farther than the bound from the exact one";
  for (const Point& p : std::span(got.points.data(), got.count)) {
    double nearest = INFINITY;
    for (const EPoint& e : exact) nearest = std::min(nearest, error_of(p, e));
    stats.worst_relative_error =
        std::max(stats.worst_relative_error, nearest / largest_coordinate(pair));
  }
  return {};
}

// ---- The inputs ---------------------------------------------------------------------------

struct Scale {
  const char* name;
  int exponent;   // lattice unit 2^exponent
  double offset;  // added to every coordinate (a multiple of the unit)
  double generic_scale;
};

constexpr Scale kScales[] = {
    {"1e-9", -30, 0, 1e-9},
    {"1", 0, 0, 1},
    {"1e9", 30, 0, 1e9},
    {"unit at 1e6", -3, 1e6, 1},  // lattice range 8 times 2^-3: unit triangles
};

constexpr int kFamilies = 11;
const char* const kFamilyNames[kFamilies] = {"generic",
                                             "shared vertex",
                                             "shared edge",
                                             "vertex on triangle",
                                             "edge through point",
                                             "edge in plane",
                                             "coplanar overlap",
                                             "coplanar edge touch",
                                             "degenerate",
                                             "near touching",
                                             "near coplanar"};

Pair generic_pair(Generator& g, const Scale& scale) {
  const Rotation rotation = random_rotation(g);
  Pair pair;
  for (auto* t : {&pair.a, &pair.b})
    for (auto& v : *t) {
      const Point p = rotation({g.uniform(-1, 1), g.uniform(-1, 1), g.uniform(-0.2, 0.2)});
      for (int k = 0; k < 3; ++k) v[k] = scale.offset + scale.generic_scale * p[k];
    }
  return pair;
}

// b in a's plane on the far side of a's edge (e, e + 1), sharing part of that edge's line.
Triangle across_edge(Generator& g, const Triangle& a, int e) {
  const Point &p = a[e], &q = a[(e + 1) % 3], &r = a[(e + 2) % 3];
  const std::int64_t n = 256;
  return {dyadic_combination(p, q, r, g.integer(-n, 2 * n), 0, 8),
          dyadic_combination(p, q, r, g.integer(-n, 2 * n), 0, 8),
          dyadic_combination(p, q, r, g.integer(-n, 2 * n), -g.integer(1, n), 8)};
}

Triangle family_second(Generator& g, const Triangle& a, int family, std::int64_t range) {
  const int r = int(g.integer(0, 2));
  switch (family) {
    case 1:
      return {a[r], lattice_point(g, range), lattice_point(g, range)};
    case 2:
      return {a[(r + 1) % 3], a[r], g.coin() ? lattice_point(g, range) : dyadic_point_on(g, a, 3)};
    case 3:
    case 9:
      return {dyadic_point_on(g, a, r), lattice_point(g, range), lattice_point(g, range)};
    case 4: {
      const Point x = dyadic_point_on(g, a, r), w = lattice_point(g, range);
      return {Point{x[0] + w[0], x[1] + w[1], x[2] + w[2]},
              Point{x[0] - w[0], x[1] - w[1], x[2] - w[2]}, lattice_point(g, range)};
    }
    case 5:
      return {dyadic_point_on(g, a, int(g.integer(0, 3))), dyadic_point_on(g, a, 3),
              lattice_point(g, range)};
    case 6:
      return {dyadic_point_on(g, a, int(g.integer(0, 3))), dyadic_point_on(g, a, 3),
              dyadic_point_on(g, a, 3)};
    case 7:
      return across_edge(g, a, r);
    case 10:
      return family_second(g, a, 6, range);  // nudged in contact_pair
    default: {  // degenerate: collinear (a segment) or a repeated vertex (a point)
      const int source = int(g.integer(0, 2));  // anywhere, through a point of a, in a's plane
      Triangle b = source == 0   ? lattice_triangle(g, range)
                   : source == 1 ? family_second(g, a, 4, range)
                                 : family_second(g, a, 6, range);
      b[2] = g.integer(0, 3) ? dyadic_combination(b[0], b[1], b[1], g.integer(-256, 512), 0, 8)
                             : b[g.integer(0, 1)];
      if (g.integer(0, 3) == 0) b[1] = b[0];
      return b;
    }
  }
}

Pair contact_pair(Generator& g, int family, const Scale& scale) {
  if (family == 0) return generic_pair(g, scale);
  const std::int64_t range = scale.offset != 0 || g.coin() ? 8 : (std::int64_t(1) << 20);
  ExactTransform transform = random_exact_transform(g);
  transform.exponent = scale.exponent;
  transform.offset = {scale.offset, -scale.offset, scale.offset};
  const Triangle a = lattice_triangle(g, range);
  Triangle b = family_second(g, a, family, range);
  Pair pair{transform(a), transform(b)};
  if (family == 9) pair.b[0] = nudge(g, pair.b[0]);
  // Near coplanar: each cut of the other's plane is ill-conditioned, and the points are placed
  // by the exact fallback.
  if (family == 10) {
    const int v = int(g.integer(0, 2));
    pair.b[v] = nudge(g, pair.b[v]);
  }
  if (g.coin()) std::swap(pair.a, pair.b);
  return pair;
}

std::string describe(const Pair& p) {
  return "a " + hex(p.a) + " b " + hex(p.b);
}

void check_family(int family, std::uint64_t cases) {
  for (const Scale& scale : kScales) {
    Disagreements disagreements(std::string(kFamilyNames[family]) + " at scale " + scale.name);
    Statistics stats;
    for (std::uint64_t c = 0; c < cases; ++c) {
      const std::uint64_t seed = 1000000 * std::uint64_t(family) + c;
      Generator g(seed);
      const Pair pair = contact_pair(g, family, scale);
      const std::string problem = check_pair(pair, stats);
      if (!problem.empty()) disagreements.add(seed, problem + ": " + describe(pair));
    }
    disagreements.expect_none(cases);
    // The family must produce what it is built for, or the test proves nothing.
    const auto& s = stats.shapes;
    const std::uint64_t met = cases - s[0];
    switch (family) {
      case 0:
        EXPECT_GT(s[2], cases / 20) << scale.name;
        break;
      case 1:
      case 3:
      case 4:
        EXPECT_GT(s[1], cases / 20) << scale.name;
        break;
      case 2:
      case 5:
        EXPECT_GT(s[2], cases / 20) << scale.name;
        break;
      case 6:
        EXPECT_GT(s[3], cases / 10) << scale.name;
        for (int corners = 3; corners <= 6; ++corners)
          EXPECT_GT(stats.polygons[corners], 0u) << scale.name << " corners " << corners;
        EXPECT_GT(stats.coplanar, cases / 2) << scale.name;
        break;
      case 7:
        EXPECT_GT(s[2], cases / 10) << scale.name;
        break;
      case 8:
        EXPECT_GT(s[1], cases / 50) << scale.name;
        EXPECT_GT(s[2], cases / 50) << scale.name;
        EXPECT_GT(stats.degenerate, cases / 2) << scale.name;
        break;
      case 10:
        EXPECT_GT(s[2], cases / 10) << scale.name;
        EXPECT_GT(s[0], cases / 50) << scale.name;
        break;
      default:
        EXPECT_GT(met, cases / 50) << scale.name;
        EXPECT_GT(s[0], cases / 50) << scale.name;
    }
    std::printf(
        "  %-20s %-12s none %6llu point %6llu segment %6llu polygon %6llu (loosely "
        "ordered %llu)  worst %.2e M\n",
        kFamilyNames[family], scale.name, (unsigned long long)s[0], (unsigned long long)s[1],
        (unsigned long long)s[2], (unsigned long long)s[3],
        (unsigned long long)stats.loosely_ordered, stats.worst_relative_error);
  }
}

constexpr std::uint64_t kCases = 2500;

TEST(TriangleContactGeometry, GenericPairsMatchEpeck) {
  check_family(0, 4 * kCases);
}
TEST(TriangleContactGeometry, SharedVertexMatchesEpeck) {
  check_family(1, kCases);
}
TEST(TriangleContactGeometry, SharedEdgeMatchesEpeck) {
  check_family(2, kCases);
}
TEST(TriangleContactGeometry, VertexOnTriangleMatchesEpeck) {
  check_family(3, kCases);
}
TEST(TriangleContactGeometry, EdgeThroughPointMatchesEpeck) {
  check_family(4, kCases);
}
TEST(TriangleContactGeometry, EdgeInPlaneMatchesEpeck) {
  check_family(5, kCases);
}
TEST(TriangleContactGeometry, CoplanarOverlapMatchesEpeck) {
  check_family(6, kCases);
}
TEST(TriangleContactGeometry, CoplanarEdgeTouchMatchesEpeck) {
  check_family(7, kCases);
}
TEST(TriangleContactGeometry, DegenerateTrianglesMatchEpeck) {
  check_family(8, kCases);
}
TEST(TriangleContactGeometry, NearTouchingMatchesEpeck) {
  check_family(9, kCases);
}
TEST(TriangleContactGeometry, NearCoplanarMatchesEpeck) {
  check_family(10, kCases);
}

// ---- Small cases with answers by hand -----------------------------------------------------

TEST(TriangleContactGeometry, StarOfDavidGivesAHexagonInOrder) {
  const Triangle up{{{0, 0, 0}, {6, 0, 0}, {3, 6, 0}}};
  const Triangle down{{{0, 4, 0}, {3, -2, 0}, {6, 4, 0}}};
  const ContactGeometry c = contact_geometry(up, down);
  ASSERT_EQ(c.shape, ContactShape::polygon);
  ASSERT_EQ(c.count, 6);
  EXPECT_TRUE(c.coplanar);
  EXPECT_EQ(c.first_normal, (Vec3{0, 0, 1}));
  EXPECT_EQ(c.second_normal, (Vec3{0, 0, 1}));
  const std::array<Point, 6> expected{
      {{2, 0, 0}, {4, 0, 0}, {5, 2, 0}, {4, 4, 0}, {2, 4, 0}, {1, 2, 0}}};
  // Counterclockwise about +z: a rotation of the expected cycle.
  const auto start = std::find_if(c.points.begin(), c.points.end(), [&](const Point& p) {
    return std::fabs(p[0] - 2) < 1e-14 && std::fabs(p[1]) < 1e-14;
  });
  ASSERT_NE(start, c.points.end());
  const std::size_t s = std::size_t(start - c.points.begin());
  for (std::size_t i = 0; i < 6; ++i)
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(c.points[(s + i) % 6][k], expected[i][k], 1e-14) << i;
}

TEST(TriangleContactGeometry, CrossingGivesTheSegmentAlongN1xN2) {
  const Triangle a{{{0, 0, 0}, {4, 0, 0}, {0, 4, 0}}};    // normal +z
  const Triangle b{{{1, 1, -1}, {1, 1, 1}, {1, -3, 1}}};  // in the plane x = 1
  const ContactGeometry c = contact_geometry(a, b);
  ASSERT_EQ(c.shape, ContactShape::segment);
  EXPECT_FALSE(c.coplanar);
  // b meets z = 0 on x = 1 for y in [-1, 1]; a on x = 1 has y in [0, 3]: the cut is y in [0, 1].
  const Vec3 d{c.first_normal[1] * c.second_normal[2] - c.first_normal[2] * c.second_normal[1],
               c.first_normal[2] * c.second_normal[0] - c.first_normal[0] * c.second_normal[2],
               c.first_normal[0] * c.second_normal[1] - c.first_normal[1] * c.second_normal[0]};
  const Point lo{1, d[1] > 0 ? 0.0 : 1.0, 0}, hi{1, d[1] > 0 ? 1.0 : 0.0, 0};
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(c.points[0][k], lo[k], 1e-15);
    EXPECT_NEAR(c.points[1][k], hi[k], 1e-15);
  }
}

TEST(TriangleContactGeometry, TouchingAtAVertexAndDegenerateInputs) {
  const Triangle a{{{0, 0, 0}, {4, 0, 0}, {0, 4, 0}}};
  const ContactGeometry vertex = contact_geometry(a, {{{1, 1, 0}, {2, 2, 5}, {0, 3, 5}}});
  ASSERT_EQ(vertex.shape, ContactShape::point);
  EXPECT_EQ(vertex.points[0], (Point{1, 1, 0}));  // an input vertex: exact
  // A segment (collinear corners) through a, and a point on it.
  const ContactGeometry stick = contact_geometry({{{1, 1, -2}, {1, 1, 2}, {1, 1, 0.5}}}, a);
  ASSERT_EQ(stick.shape, ContactShape::point);
  EXPECT_EQ(stick.points[0], (Point{1, 1, 0}));
  EXPECT_EQ(stick.first_normal, (Vec3{0, 0, 0}));
  const ContactGeometry lying = contact_geometry({{{-1, 1, 0}, {5, 1, 0}, {5, 1, 0}}}, a);
  ASSERT_EQ(lying.shape, ContactShape::segment);
  const ContactGeometry dot = contact_geometry({{{1, 1, 0}, {1, 1, 0}, {1, 1, 0}}}, a);
  ASSERT_EQ(dot.shape, ContactShape::point);
  const ContactGeometry off = contact_geometry({{{1, 1, 1}, {1, 1, 1}, {1, 1, 1}}}, a);
  EXPECT_EQ(off.shape, ContactShape::none);
  const ContactGeometry sticks =
      contact_geometry({{{0, 0, 0}, {2, 2, 2}, {2, 2, 2}}}, {{{2, 0, 0}, {0, 2, 2}, {1, 1, 1}}});
  ASSERT_EQ(sticks.shape, ContactShape::point);
  EXPECT_EQ(sticks.points[0], (Point{1, 1, 1}));
}

}  // namespace
}  // namespace tetrapage::geometry
