// The object BVH answers exactly what the brute-force reference answers (every triangle
// tested), in every accuracy mode, for random objects and poses; bad objects are rejected.

#include "tetrapage/runtime/geometry/ObjectBVH.h"

#include <algorithm>

#include "GeometryTestSupport.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/runtime/geometry/FloatRounding.h"
#include "tetrapage/runtime/geometry/TriangleTriangle.h"

namespace tetrapage::geometry {
namespace {

using namespace testing;

// A closed, bumpy sphere (a latitude/longitude grid) or a random triangle soup; in lattice
// coordinates scaled by a power of two so that exact contacts can be built on it.
TriangleSoup random_object(Generator& g, bool sphere, int size) {
  TriangleSoup object;
  object.part_names = {"object"};
  if (sphere) {
    const int rings = size, segments = 2 * size;
    const double pi = 3.14159265358979323846;
    for (int r = 0; r <= rings; ++r)
      for (int s = 0; s < segments; ++s) {
        const double theta = pi * r / rings, phi = 2 * pi * s / segments;
        const double radius = 1000 * (1 + 0.1 * g.uniform(-1, 1));
        object.vertices.push_back({std::round(radius * std::sin(theta) * std::cos(phi)),
                                   std::round(radius * std::sin(theta) * std::sin(phi)),
                                   std::round(radius * std::cos(theta))});
      }
    auto id = [segments](int r, int s) { return std::uint32_t(r * segments + (s % segments)); };
    for (int r = 0; r < rings; ++r)
      for (int s = 0; s < segments; ++s) {
        object.triangles.push_back({id(r, s), id(r + 1, s), id(r + 1, s + 1)});
        object.triangles.push_back({id(r, s), id(r + 1, s + 1), id(r, s + 1)});
      }
  } else {
    for (int t = 0; t < size * size; ++t) {
      const Point center = lattice_point(g, 1000);
      const auto base = std::uint32_t(object.vertices.size());
      for (int v = 0; v < 3; ++v) {
        const Point d = lattice_point(g, 100);
        object.vertices.push_back({center[0] + d[0], center[1] + d[1], center[2] + d[2]});
      }
      object.triangles.push_back({base, base + 1, base + 2});
    }
  }
  object.part_of.assign(object.triangles.size(), 0);
  return object;
}

// Environment triangles in the object's frame: random ones near the object, and ones touching
// an object triangle exactly (a vertex on it), some nudged.
Triangle random_query(Generator& g, const ObjectBVH& bvh) {
  const Box bounds = bvh.bounds();
  auto near = [&] {
    Point p;
    for (int k = 0; k < 3; ++k) p[k] = std::floor(g.uniform(bounds.lo[k] - 200, bounds.hi[k] + 200));
    return p;
  };
  if (g.coin()) {
    const Point c = near();
    const double size = g.log_uniform(0, 3);
    Triangle t;
    for (auto& v : t)
      v = {c[0] + std::floor(size * g.uniform(-1, 1)), c[1] + std::floor(size * g.uniform(-1, 1)),
           c[2] + std::floor(size * g.uniform(-1, 1))};
    return t;
  }
  const Triangle& target = bvh.triangle(std::uint32_t(g.integer(0, std::int64_t(bvh.triangle_count()) - 1)));
  Triangle t{dyadic_point_on(g, target, int(g.integer(0, 2))), near(), near()};
  if (g.coin()) t[0] = nudge(g, t[0]);
  return t;
}

TEST(ObjectBVH, QueriesMatchBruteForceInEveryMode) {
  const Accuracy modes[] = {Accuracy::exact(), Accuracy::double_eps(), Accuracy::float_eps(),
                            Accuracy::within(5.0), Accuracy::within(0.0)};
  Disagreements disagreements("BVH vs brute force");
  std::uint64_t queries = 0, hits = 0;
  for (int object_seed = 0; object_seed < 12; ++object_seed) {
    Generator g{std::uint64_t(object_seed)};
    const TriangleSoup object = random_object(g, object_seed % 2 == 0, 8 + 4 * (object_seed % 3));
    const ObjectBVH bvh(object);
    EXPECT_EQ(bvh.triangle_count(), object.triangle_count());
    EXPECT_LE(bvh.depth(), 100u);
    for (int q = 0; q < 300; ++q) {
      const std::uint64_t seed = std::uint64_t(object_seed) * 100000 + std::uint64_t(q);
      Generator qg(seed);
      const Triangle query = random_query(qg, bvh);
      for (const Accuracy& mode : modes) {
        std::vector<std::uint32_t> fast, slow;
        bvh.all_hits(query, mode, fast);
        bvh.all_hits_brute_force(query, mode, slow);
        std::sort(fast.begin(), fast.end());
        const auto first = bvh.first_hit(query, mode);
        const bool first_ok = first.has_value() == !slow.empty() &&
                              (!first || std::binary_search(slow.begin(), slow.end(), *first));
        ++queries;
        hits += !slow.empty();
        if (fast != slow || !first_ok)
          disagreements.add(seed, to_string(mode) + " query " + hex(query) + ": " +
                                      std::to_string(fast.size()) + " hits, brute force " +
                                      std::to_string(slow.size()));
      }
    }
  }
  disagreements.expect_none(queries);
  EXPECT_GT(hits, queries / 10);
  EXPECT_LT(hits, queries - queries / 10);
}

TEST(ObjectBVH, ExactHitsAreExactIntersections) {
  Generator g{77};
  const TriangleSoup object = random_object(g, true, 10);
  const ObjectBVH bvh(object);
  Disagreements disagreements("BVH exact hits");
  for (std::uint64_t q = 0; q < 2000; ++q) {
    Generator qg(q);
    const Triangle query = random_query(qg, bvh);
    std::vector<std::uint32_t> hits;
    bvh.all_hits(query, Accuracy::exact(), hits);
    for (std::uint32_t h : hits)
      if (!CGAL::do_intersect(to_epeck(query), to_epeck(bvh.triangle(h))))
        disagreements.add(q, "false hit " + std::to_string(h));
  }
  disagreements.expect_none(2000);
}

TEST(ObjectBVH, PrunesMostTriangles) {
  Generator g{5};
  const TriangleSoup object = random_object(g, true, 40);  // 6400 triangles
  const ObjectBVH bvh(object);
  ObjectBVH::QueryCounters counters;
  for (std::uint64_t q = 0; q < 500; ++q) {
    Generator qg(q);
    bvh.first_hit(random_query(qg, bvh), Accuracy::exact(), &counters);
  }
  // Small queries against a 6400-triangle object: a few dozen tests each, not thousands.
  EXPECT_LT(counters.triangle_tests, 500u * 200u);
  EXPECT_GT(counters.nodes_visited, 0u);
}

TEST(ObjectBVH, BoxQueriesWithAFilterVisitWhatBruteForceKeeps) {
  // Boxes around random queries, with a filter that keeps boxes reaching above a random plane
  // z = c (any filter the caller passes must be honoured for the triangles; it is asked about
  // the triangles' own boxes and the nodes' boxes, which hold them).
  Disagreements disagreements("BVH box query with a filter");
  std::uint64_t visited_total = 0, nodes_filtered = 0, nodes_plain = 0;
  for (int object_seed = 0; object_seed < 6; ++object_seed) {
    Generator g{std::uint64_t(100 + object_seed)};
    const TriangleSoup object = random_object(g, object_seed % 2 == 0, 10);
    const ObjectBVH bvh(object);
    for (std::uint64_t q = 0; q < 300; ++q) {
      Generator qg(std::uint64_t(object_seed) * 1000 + q);
      const Box box = box_of(random_query(qg, bvh));
      const double c = qg.uniform(bvh.bounds().lo[2], bvh.bounds().hi[2]);
      auto above = [c](const Box& b) { return b.hi[2] >= c; };
      std::vector<std::uint32_t> visited, plain, expected;
      // The filter is asked of the nodes too (a node's box holds its triangles'): it prunes them.
      ObjectBVH::QueryCounters filtered_counters, plain_counters;
      bvh.for_each_in_box(
          box, above, [&](std::uint32_t t) { return visited.push_back(t), true; },
          &filtered_counters);
      bvh.for_each_in_box(
          box, [&](std::uint32_t t) { return plain.push_back(t), true; }, &plain_counters);
      nodes_filtered += filtered_counters.nodes_visited;
      nodes_plain += plain_counters.nodes_visited;
      for (std::uint32_t t = 0; t < bvh.triangle_count(); ++t) {
        const Box own = box_of(bvh.triangle(t));
        if (boxes_overlap(own, box) && own.hi[2] >= c) expected.push_back(t);
      }
      std::sort(visited.begin(), visited.end());
      std::sort(plain.begin(), plain.end());
      std::vector<std::uint32_t> plain_kept;
      for (std::uint32_t t : plain)
        if (box_of(bvh.triangle(t)).hi[2] >= c) plain_kept.push_back(t);
      visited_total += visited.size();
      if (visited != expected || plain_kept != expected)
        disagreements.add(q, std::to_string(visited.size()) + " visited, " +
                                 std::to_string(expected.size()) + " expected, seed " +
                                 std::to_string(object_seed));
    }
  }
  disagreements.expect_none(1800);
  EXPECT_GT(visited_total, 100u) << "the queries must reach triangles";
  EXPECT_LT(nodes_filtered, nodes_plain) << "the filter asked of the nodes must prune some";
}

TEST(FloatRounding, BelowAndAboveAreTheNearestFloatsOnTheirSide) {
  // Against std::nextafter, on random doubles of every magnitude, zero, exact floats and the
  // ends of float's range.
  Generator g{31};
  std::vector<double> values{0.0, -0.0, 1.0, -1.0, 0x1p-149, -0x1p-149, 1e-46, -1e-46,
                             double(std::numeric_limits<float>::max()), 1e39, -1e39, 1e300};
  for (int i = 0; i < 20000; ++i) values.push_back(g.uniform(-1, 1) * std::ldexp(1.0, int(g.integer(-160, 140))));
  for (const double x : values) {
    const float below = float_below(x), above = float_above(x);
    EXPECT_LE(double(below), x) << x;
    EXPECT_GE(double(above), x) << x;
    if (std::fabs(x) <= double(std::numeric_limits<float>::max())) {
      const float f = float(x);
      const float expected_below = double(f) > x ? std::nextafter(f, -INFINITY) : f;
      const float expected_above = double(f) < x ? std::nextafter(f, INFINITY) : f;
      EXPECT_EQ(below, expected_below) << x;
      EXPECT_EQ(above, expected_above) << x;
    }
  }
}

TEST(ObjectBVH, RejectsBadObjectsNamingTheElement) {
  const std::vector<Vec3> vertices{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  EXPECT_THROW(ObjectBVH(vertices, std::vector<TriangleIndices>{}), InputError);
  try {
    ObjectBVH(vertices, std::vector<TriangleIndices>{{0, 1, 2}, {0, 1, 7}});
    ADD_FAILURE() << "accepted an out-of-range index";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("triangle 1"), std::string::npos) << e.what();
  }
  const std::vector<Vec3> bad{{0, 0, 0}, {1, std::nan(""), 0}, {0, 1, 0}};
  try {
    ObjectBVH(bad, std::vector<TriangleIndices>{{0, 1, 2}});
    ADD_FAILURE() << "accepted a NaN vertex";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("vertex 1"), std::string::npos) << e.what();
  }
}

TEST(ObjectBVH, BoxQueriesOnObjectsOfOneToTwentyTrianglesVisitWhatBruteForceKeeps) {
  // The wide nodes of small hierarchies: a root that is a leaf, roots with two or three
  // children, partly filled nodes. Each triangle visited once, none missed.
  Disagreements disagreements("BVH box query on a small object");
  std::uint64_t visited_total = 0;
  for (std::uint32_t size = 1; size <= 20; ++size) {
    Generator g{std::uint64_t(500 + size)};
    TriangleSoup object;
    for (std::uint32_t t = 0; t < size; ++t) {
      const auto first = std::uint32_t(object.vertices.size());
      const Vec3 at{g.uniform(-10, 10), g.uniform(-10, 10), g.uniform(-10, 10)};
      for (int c = 0; c < 3; ++c)
        object.vertices.push_back(
            {at[0] + g.uniform(-2, 2), at[1] + g.uniform(-2, 2), at[2] + g.uniform(-2, 2)});
      object.triangles.push_back({first, first + 1, first + 2});
    }
    const ObjectBVH bvh(object);
    for (std::uint64_t q = 0; q < 200; ++q) {
      Box box;
      for (int k = 0; k < 3; ++k) {
        const double a = g.uniform(-14, 14), b = g.uniform(-14, 14);
        box.lo[k] = std::min(a, b), box.hi[k] = std::max(a, b);
      }
      std::vector<std::uint32_t> visited, expected;
      bvh.for_each_in_box(box, [&](std::uint32_t t) { return visited.push_back(t), true; });
      for (std::uint32_t t = 0; t < size; ++t)
        if (boxes_overlap(box_of(bvh.triangle(t)), box)) expected.push_back(t);
      std::sort(visited.begin(), visited.end());
      visited_total += visited.size();
      if (visited != expected)
        disagreements.add(q, std::to_string(visited.size()) + " visited, " +
                                 std::to_string(expected.size()) + " expected, " +
                                 std::to_string(size) + " triangles");
    }
  }
  disagreements.expect_none(4000);
  EXPECT_GT(visited_total, 1000u) << "the queries must reach triangles";
}

TEST(ObjectBVH, HandlesDegenerateLayouts) {
  // Every triangle at the same place (no split possible), and a long line of triangles.
  TriangleSoup same;
  same.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  for (int i = 0; i < 1000; ++i) same.triangles.push_back({0, 1, 2});
  const ObjectBVH stacked(same);
  std::vector<std::uint32_t> hits;
  EXPECT_EQ(stacked.all_hits({Point{0, 0, -1}, Point{0, 0, 1}, Point{1, 1, 1}}, Accuracy::exact(), hits),
            1000u);
  TriangleSoup line;
  for (int i = 0; i < 5000; ++i) {
    const auto base = std::uint32_t(line.vertices.size());
    const double x = std::ldexp(double(i), 20);  // exponentially spread would overflow: linear
    line.vertices.insert(line.vertices.end(), {{x, 0, 0}, {x + 1, 0, 0}, {x, 1, 0}});
    line.triangles.push_back({base, base + 1, base + 2});
  }
  const ObjectBVH spread(line);
  EXPECT_LE(spread.depth(), 100u);
  EXPECT_TRUE(spread.first_hit({Point{0.5, 0.2, -1}, Point{0.5, 0.2, 1}, Point{0.6, 0.3, 0}}).has_value());
}

}  // namespace
}  // namespace tetrapage::geometry
