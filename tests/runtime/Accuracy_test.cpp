// The accuracy modes: parsing, and the properties each mode promises. The epsilon modes agree
// with the exact answer away from contact; clearance never misses a contact; exact is exact.

#include "tetrapage/runtime/geometry/Accuracy.h"

#include "GeometryTestSupport.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/runtime/geometry/EpsilonTests.h"
#include "tetrapage/runtime/geometry/SegmentTriangle.h"
#include "tetrapage/runtime/geometry/TriangleBox.h"
#include "tetrapage/runtime/geometry/TriangleTriangle.h"

namespace tetrapage::geometry {
namespace {

using namespace testing;

TEST(Accuracy, ParsesAndPrintsEveryMode) {
  EXPECT_EQ(parse_accuracy("exact").mode, AccuracyMode::exact);
  EXPECT_EQ(parse_accuracy("double_eps").mode, AccuracyMode::double_eps);
  EXPECT_EQ(parse_accuracy("float_eps").mode, AccuracyMode::float_eps);
  EXPECT_EQ(parse_accuracy("float_eps:1e-4").relative_epsilon, 1e-4);
  const Accuracy clearance = parse_accuracy("clearance:0.25");
  EXPECT_EQ(clearance.mode, AccuracyMode::clearance);
  EXPECT_EQ(clearance.clearance, 0.25);
  for (const char* text : {"exact", "double_eps", "float_eps", "float_eps:0.0001", "clearance:0.25",
                           "double_eps:1e-09"})
    EXPECT_EQ(parse_accuracy(to_string(parse_accuracy(text))).mode, parse_accuracy(text).mode) << text;
  EXPECT_EQ(to_string(parse_accuracy("clearance:0.25")), "clearance:0.25");
  EXPECT_EQ(Accuracy{}.mode, AccuracyMode::exact);  // exact is the default
  EXPECT_DOUBLE_EQ(Accuracy::double_eps().effective_epsilon(), epsilon::kDefaultDoubleEpsilon);
}

TEST(Accuracy, RejectsInvalidTextNamingIt) {
  for (const char* text : {"", "exactly", "clearance", "clearance:", "clearance:-1", "clearance:nan",
                           "clearance:inf", "float_eps:x", "exact:1", "clearance:1x"}) {
    try {
      parse_accuracy(text);
      ADD_FAILURE() << "accepted '" << text << "'";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("'") + text), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(Accuracy::within(-1.0), InputError);
  EXPECT_THROW(Accuracy::within(std::nan("")), InputError);
}

// A robustly crossing pair (b pierces a's interior at a wide angle) or a robustly separated one
// (b lifted off a's plane by at least a tenth of its size), at any scale, offset and rotation.
struct RobustPair {
  Triangle a, b;
  bool crossing;
};

RobustPair robust_pair(Generator& g) {
  const double scale = g.log_uniform(-6, 6);
  const double offset = g.coin() ? 0.0 : g.log_uniform(3, 6) * (g.coin() ? 1 : -1);
  const Rotation rotation = random_rotation(g);
  const bool crossing = g.coin();
  // a: a large triangle in z = 0 around the origin; b: vertical, through x in [-0.2, 0.2].
  Triangle a{Point{-2, -2, 0}, Point{2, -2, 0}, Point{0, 2, 0}};
  const double lift = crossing ? 0.0 : g.uniform(0.6, 2.0) * (g.coin() ? 1 : -1);
  const double x = g.uniform(-0.2, 0.2);
  Triangle b{Point{x, -0.5, lift - 0.5}, Point{x + 0.1, 0.5, lift - 0.5}, Point{x, 0, lift + 0.5}};
  for (auto* t : {&a, &b})
    for (auto& v : *t) {
      const Point p = rotation(v);
      v = {offset + scale * p[0], offset + scale * p[1], offset + scale * p[2]};
    }
  return {a, b, crossing};
}

TEST(Accuracy, EveryModeAgreesWithExactAwayFromContact) {
  constexpr std::uint64_t kCases = 100000;
  Disagreements disagreements("modes away from contact");
  const Accuracy modes[] = {Accuracy::exact(), Accuracy::double_eps(), Accuracy::float_eps()};
  for (std::uint64_t c = 0; c < kCases; ++c) {
    Generator g(c);
    const RobustPair p = robust_pair(g);
    for (const Accuracy& mode : modes)
      if (triangles_collide(p.a, p.b, mode) != p.crossing)
        disagreements.add(c, to_string(mode) + " a " + hex(p.a) + " b " + hex(p.b));
    // The same pairs through segment/triangle: an edge of b against a.
    const Segment edge{p.b[0], p.b[2]};  // the vertical edge pierces a when crossing
    for (const Accuracy& mode : modes)
      if (segment_collides_with_triangle(edge, p.a, mode) != p.crossing)
        disagreements.add(c, "segment " + to_string(mode));
  }
  disagreements.expect_none(kCases);
}

TEST(Accuracy, ExactModeIsTheExactTest) {
  constexpr std::uint64_t kCases = 50000;
  Disagreements disagreements("exact mode");
  for (std::uint64_t c = 0; c < kCases; ++c) {
    Generator g(c);
    const ExactTransform transform = random_exact_transform(g);
    const Triangle a = transform(lattice_triangle(g, 6));
    const Triangle b{dyadic_point_on(g, a, int(g.integer(0, 3))), transform(lattice_point(g, 6)),
                     transform(lattice_point(g, 6))};
    if (triangles_collide(a, b, Accuracy::exact()) != triangles_intersect(a, b))
      disagreements.add(c, hex(a) + " " + hex(b));
  }
  disagreements.expect_none(kCases);
}

TEST(Accuracy, ClearanceNeverMissesAContact) {
  constexpr std::uint64_t kCases = 50000;
  Disagreements disagreements("clearance");
  std::uint64_t touching = 0;
  for (std::uint64_t c = 0; c < kCases; ++c) {
    Generator g(c);
    const ExactTransform transform = random_exact_transform(g);
    const Triangle a = lattice_triangle(g, 1 << 20);
    // Touching exactly: a vertex, an edge point or an interior point of a, seen by b's vertex.
    const Triangle b{dyadic_point_on(g, a, int(g.integer(0, 2))), lattice_point(g, 1 << 20),
                     lattice_point(g, 1 << 20)};
    const Triangle ta = transform(a), tb = transform(b);
    const double d = c % 2 ? 0.0 : g.log_uniform(-12, 3);
    const Box box_b = box_of(tb);
    if (!triangles_intersect(ta, tb)) continue;  // a sliver lost exactness in the transform
    ++touching;
    if (!triangles_collide(ta, tb, Accuracy::within(d)) ||
        !segment_collides_with_triangle({tb[0], tb[1]}, ta, Accuracy::within(d)) ||
        !triangle_collides_with_box(ta, box_b, Accuracy::within(d)))
      disagreements.add(c, "d " + std::to_string(d) + " " + hex(ta) + " " + hex(tb));
  }
  disagreements.expect_none(touching);
  EXPECT_GT(touching, kCases * 9 / 10);
}

}  // namespace
}  // namespace tetrapage::geometry
