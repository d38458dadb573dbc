// Shards built from adversarial regions, queried against brute force: every stored triangle
// that meets the query box exactly (the kernel's triangle/box test, applied to every triangle)
// is visited exactly once, and nothing else; the stored vertices round as reported; ids and
// parts survive; corrupted payloads throw FormatError and never crash.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <numeric>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/preprocess/ShardBuilder.h"
#include "tetrapage/preprocess/ShardCostModel.h"
#include "tetrapage/runtime/geometry/TriangleBox.h"
#include "tetrapage/runtime/paging/Shard.h"
#include "tetrapage/tools/Random.h"

namespace tetrapage {
namespace {

using geometry::Box;
using geometry::Point;
using geometry::Triangle;

struct Region {
  std::string name;
  std::vector<Triangle> triangles;
  std::vector<std::uint64_t> ids;
  std::vector<std::uint32_t> parts;
  ShardTriangles view() const { return {triangles, ids, parts}; }
};

Point random_point(Random& r, const Point& centre, double size) {
  return {centre[0] + r.uniform(-size, size), centre[1] + r.uniform(-size, size),
          centre[2] + r.uniform(-size, size)};
}

// Small triangles spread over a cube of half side `size` around `centre`.
Region soup(std::uint64_t seed, std::size_t n, const Point& centre, double size,
            double triangle_size) {
  Random r(seed);
  Region region;
  region.name = "soup(seed " + std::to_string(seed) + ", " + std::to_string(n) + ", size " +
                std::to_string(size) + ", at " + std::to_string(centre[0]) + ")";
  for (std::size_t i = 0; i < n; ++i) {
    const Point c = random_point(r, centre, size);
    region.triangles.push_back({random_point(r, c, triangle_size),
                                random_point(r, c, triangle_size),
                                random_point(r, c, triangle_size)});
    region.ids.push_back(1'000'000'000'000ull + r.below(1u << 20));
    region.parts.push_back(std::uint32_t(r.below(3)) * 1000);
  }
  return region;
}

// Adversarial families: slivers, coplanar, one triangle, duplicates, long diagonals.
std::vector<Region> regions() {
  std::vector<Region> out;
  out.push_back(soup(1, 300, {0, 0, 0}, 1, 0.1));
  out.push_back(soup(2, 200, {1e6, -1e6, 1e6}, 10, 1));
  out.push_back(soup(3, 200, {1e9, 1e9, -1e9}, 1000, 50));
  out.push_back(soup(4, 200, {0, 0, 0}, 1e-9, 1e-10));
  out.push_back(soup(5, 200, {0, 0, 0}, 1e9, 1e8));
  out.push_back(soup(6, 100, {3e-9, 1e9, 0}, 1e-3, 1e-4));  // tiny region far out
  {
    Random r(7);
    Region slivers{"slivers", {}, {}, {}};
    for (int i = 0; i < 150; ++i) {
      const Point a = random_point(r, {0, 0, 0}, 1), b = random_point(r, {0, 0, 0}, 1);
      const double s = r.uniform();
      const Point c{a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1]) + 1e-12,
                    a[2] + s * (b[2] - a[2])};
      slivers.triangles.push_back({a, b, c});
      slivers.ids.push_back(std::uint64_t(i));
      slivers.parts.push_back(7);
    }
    out.push_back(slivers);
  }
  {
    Random r(8);
    Region plane{"coplanar z=0.25", {}, {}, {}};
    for (int i = 0; i < 200; ++i) {
      Triangle t;
      for (auto& p : t) p = {r.uniform(-1, 1), r.uniform(-1, 1), 0.25};
      plane.triangles.push_back(t);
      plane.ids.push_back(std::uint64_t(5 * i));
      plane.parts.push_back(std::uint32_t(i));  // many parts
    }
    out.push_back(plane);
  }
  out.push_back({"one triangle", {{Point{1, 2, 3}, Point{4, 2, 3}, Point{1, 7, 3.5}}}, {42}, {0}});
  {
    Region dup{"duplicates", {}, {}, {}};
    for (int i = 0; i < 300; ++i) {
      dup.triangles.push_back({Point{0.1, 0.2, 0.3}, Point{0.5, 0.2, 0.3}, Point{0.1, 0.9, 0.35}});
      dup.ids.push_back(std::uint64_t(i) << 40);  // ids needing 8 bytes
      dup.parts.push_back(1);
    }
    out.push_back(dup);
  }
  {
    Random r(9);
    Region diag{"long diagonals", {}, {}, {}};
    for (int i = 0; i < 100; ++i) {
      const double s = r.uniform(-1, 1);
      diag.triangles.push_back({Point{-1, -1, s}, Point{1, 1, s}, Point{1, 1, s + 0.01}});
      diag.ids.push_back(std::uint64_t(i));
      diag.parts.push_back(0);
    }
    out.push_back(diag);
  }
  return out;
}

// Query boxes: random ones at several scales, boxes touching a stored vertex at one point,
// degenerate boxes (points, segments, flat) at vertices and edge points, far outside, and
// covering everything.
std::vector<Box> query_boxes(const Shard& shard, std::uint64_t seed) {
  Random r(seed);
  std::vector<Box> boxes;
  const Box b = shard.bounds();
  const Point size = b.size();
  double scale = std::max({size[0], size[1], size[2]});
  if (scale == 0) scale = std::max(1e-300, std::fabs(b.lo[0]) * 1e-12);
  auto at = [&](const Point& p, double half) {
    Box q;
    for (int k = 0; k < 3; ++k) {
      q.lo[k] = p[k] - half * r.uniform();
      q.hi[k] = p[k] + half * r.uniform();
    }
    return q;
  };
  for (int i = 0; i < 60; ++i) {
    Point p;
    for (int k = 0; k < 3; ++k) p[k] = r.uniform(b.lo[k] - 0.1 * scale, b.hi[k] + 0.1 * scale);
    boxes.push_back(at(p, scale * std::pow(10.0, -r.uniform(0, 3))));
  }
  for (int i = 0; i < 40; ++i) {
    const Triangle t = shard.triangle(std::uint32_t(r.below(shard.triangle_count())));
    const Point v = t[r.below(3)];
    Box touch;  // a corner exactly on the vertex, extending away along random directions
    for (int k = 0; k < 3; ++k) {
      const double d = scale * 0.01;
      if (r.below(2)) {
        touch.lo[k] = v[k];
        touch.hi[k] = v[k] + d;
      } else {
        touch.lo[k] = v[k] - d;
        touch.hi[k] = v[k];
      }
    }
    boxes.push_back(touch);
    boxes.push_back(Box{v, v});  // a point box on the vertex
    Point mid;                   // an edge point (rounded: may miss, the oracle decides)
    for (int k = 0; k < 3; ++k) mid[k] = 0.5 * (t[0][k] + t[1][k]);
    boxes.push_back(Box{mid, mid});
    Box flat = at(v, scale * 0.05);
    const int axis = int(r.below(3));
    flat.hi[axis] = flat.lo[axis];
    boxes.push_back(flat);
  }
  Box far;
  far.lo = {b.hi[0] + scale * 10, b.lo[1], b.lo[2]};
  far.hi = {b.hi[0] + scale * 20, b.hi[1], b.hi[2]};
  boxes.push_back(far);
  Box all;
  all.lo = {b.lo[0] - scale, b.lo[1] - scale, b.lo[2] - scale};
  all.hi = {b.hi[0] + scale, b.hi[1] + scale, b.hi[2] + scale};
  boxes.push_back(all);
  boxes.push_back(b);  // exactly the bounds
  constexpr double inf = std::numeric_limits<double>::infinity();
  boxes.push_back(Box{{-inf, -inf, -inf}, {inf, inf, inf}});
  boxes.push_back(Box{});  // empty
  return boxes;
}

// Compares one shard's answers with brute force; returns the number of disagreements.
int check_queries(const Shard& shard, const std::vector<Box>& boxes, const std::string& what) {
  int failures = 0;
  for (std::size_t q = 0; q < boxes.size(); ++q) {
    const Box& box = boxes[q];
    std::vector<int> seen(shard.triangle_count(), 0);
    shard.for_each_candidate(box, [&](std::uint32_t t) {
      ASSERT_LT(t, shard.triangle_count());
      ++seen[t];
    });
    for (std::uint32_t t = 0; t < shard.triangle_count(); ++t) {
      const Triangle tri = shard.triangle(t);
      // A triangle meets the box iff it meets the box clipped to its own box (finite even
      // when the query is not).
      const Box own = geometry::box_of(tri);
      Box clipped;
      for (int k = 0; k < 3; ++k) {
        clipped.lo[k] = std::max(box.lo[k], own.lo[k]);
        clipped.hi[k] = std::min(box.hi[k], own.hi[k]);
      }
      const bool expected =
          geometry::boxes_overlap(own, box) && geometry::triangle_intersects_box(tri, clipped);
      if (seen[t] != int(expected)) {
        if (++failures <= 5)
          ADD_FAILURE() << what << " query " << q << " box [" << box.lo[0] << "," << box.lo[1]
                        << "," << box.lo[2] << "]-[" << box.hi[0] << "," << box.hi[1] << ","
                        << box.hi[2] << "] triangle " << t << " visited " << seen[t]
                        << " times, expected " << expected;
      }
      if (seen[t] && !geometry::boxes_overlap(geometry::box_of(tri), box)) ++failures;
    }
  }
  return failures;
}

using Config = std::tuple<ShardKind, StoredPrecision>;
class ShardBuilderTest : public ::testing::TestWithParam<Config> {};

TEST_P(ShardBuilderTest, QueriesMatchBruteForceOnAdversarialRegions) {
  const auto [kind, precision] = GetParam();
  for (const Region& region : regions()) {
    for (const ShardLayout& layout :
         {ShardLayout{}, ShardLayout{{0, 0, 0}, 8.0, 2, 2}, ShardLayout{{3, 1, 5}, 1, 16, 16}}) {
      const std::string what = region.name + " as " + std::string(to_string(kind)) + "/" +
                               std::string(to_string(precision)) + " leaf " +
                               std::to_string(layout.rtree_leaf_size);
      const BuiltShard built = build_shard(region.view(), kind, precision, layout);
      const Shard shard = Shard::decode(built.payload, what);
      ASSERT_EQ(shard.triangle_count(), region.triangles.size()) << what;
      ASSERT_EQ(shard.kind(), kind);
      ASSERT_EQ(shard.precision(), precision);
      EXPECT_EQ(check_queries(shard, query_boxes(shard, 11), what), 0) << what << " seed 11";
    }
  }
}

TEST_P(ShardBuilderTest, BoxCandidatesHonourAFilterOnLeavesAndInnerNodes) {
  // for_each_box_candidate (and its variant that also asks inner R-tree nodes) visits, once,
  // every triangle that meets both the query and a filter box (a conservative filter: it
  // keeps every node or cell whose box overlaps the filter's), and nothing whose box misses
  // the query.
  const auto [kind, precision] = GetParam();
  int failures = 0;
  std::size_t inner_asked = 0;
  for (const Region& region : regions()) {
    for (const ShardLayout& layout : {ShardLayout{}, ShardLayout{{0, 0, 0}, 8.0, 2, 2}}) {
      const std::string what = region.name + " as " + std::string(to_string(kind)) + "/" +
                               std::string(to_string(precision)) + " leaf " + std::to_string(layout.rtree_leaf_size);
      const Shard shard = Shard::decode(build_shard(region.view(), kind, precision, layout).payload, what);
      const std::vector<Box> boxes = query_boxes(shard, 13);
      for (std::size_t q = 0; q + 1 < boxes.size(); q += 2) {
        const Box& box = boxes[q];
        const Box& filter = boxes[q + 1];
        for (const bool inner : {false, true}) {
          std::vector<int> seen(shard.triangle_count(), 0);
          auto accept = [&](const Box& node, std::uint32_t triangles) {
            if (triangles == 0) ++inner_asked;
            return geometry::boxes_overlap(node, filter);
          };
          auto visit = [&](std::uint32_t t, const Triangle& triangle) {
            ++seen[t];
            if (triangle != shard.triangle(t) && ++failures <= 5) {
              ADD_FAILURE() << what << ": triangle " << t;
            }
          };
          if (inner)
            shard.for_each_box_candidate_pruning_inner_nodes(box, accept, visit);
          else
            shard.for_each_box_candidate(box, accept, visit);
          Box both;
          for (int k = 0; k < 3; ++k) {
            both.lo[k] = std::max(box.lo[k], filter.lo[k]);
            both.hi[k] = std::min(box.hi[k], filter.hi[k]);
          }
          for (std::uint32_t t = 0; t < shard.triangle_count(); ++t) {
            const Box own = geometry::box_of(shard.triangle(t));
            const bool must = geometry::boxes_overlap(both, both) && geometry::triangle_intersects_box(shard.triangle(t), both);
            const bool may = geometry::boxes_overlap(own, box);
            if ((seen[t] > 1 || (must && seen[t] == 0) || (!may && seen[t] > 0)) && ++failures <= 5) {
              ADD_FAILURE() << what << " query " << q << (inner ? " (inner nodes)" : "") << ": triangle " << t
                            << " visited " << seen[t] << " times";
            }
          }
        }
      }
    }
  }
  EXPECT_EQ(failures, 0);
  if (kind == ShardKind::rtree) {
    EXPECT_GT(inner_asked, 0u) << "the filter was never asked of an inner node";
  }
}

TEST_P(ShardBuilderTest, StoredVerticesIdsAndPartsRoundTrip) {
  const auto [kind, precision] = GetParam();
  for (const Region& region : regions()) {
    const std::string what = region.name + " as " + std::string(to_string(kind));
    const BuiltShard built = build_shard(region.view(), kind, precision);
    const Shard shard = Shard::decode(built.payload, what);
    // Match each stored triangle to its input by id and part (a multiset: ids may repeat).
    std::multimap<std::pair<std::uint64_t, std::uint32_t>, std::size_t> inputs;
    for (std::size_t i = 0; i < region.ids.size(); ++i)
      inputs.emplace(std::pair{region.ids[i], region.parts[i]}, i);
    double max_distance = 0;
    for (std::uint32_t t = 0; t < shard.triangle_count(); ++t) {
      const auto it = inputs.find({shard.triangle_id(t), shard.component_id(t)});
      ASSERT_NE(it, inputs.end()) << what << " triangle " << t << " id " << shard.triangle_id(t);
      const Triangle& in = region.triangles[it->second];
      const Triangle stored = shard.triangle(t);
      for (int c = 0; c < 3; ++c) {
        double squared = 0;
        for (int k = 0; k < 3; ++k)
          squared += (in[c][k] - stored[c][k]) * (in[c][k] - stored[c][k]);
        max_distance = std::max(max_distance, std::sqrt(squared));
      }
      inputs.erase(it);
    }
    EXPECT_TRUE(inputs.empty()) << what;
    EXPECT_EQ(built.max_rounding_distance, max_distance) << what;
    if (precision == StoredPrecision::float64) {
      EXPECT_EQ(max_distance, 0.0) << what;
    } else {
      // Within float's resolution over the region, or double's at its magnitude.
      Box b;
      double magnitude = 0;
      for (const Triangle& tri : region.triangles)
        for (const Point& p : tri) {
          b.extend(p);
          for (int k = 0; k < 3; ++k) magnitude = std::max(magnitude, std::fabs(p[k]));
        }
      const Point s = b.size();
      const double bound =
          std::max(std::max({s[0], s[1], s[2]}) * 0x1p-23, magnitude * 0x1p-50) * std::sqrt(3.0);
      EXPECT_LE(max_distance, bound) << what;
    }
  }
}

TEST_P(ShardBuilderTest, ConcurrentQueriesAgreeWithSequentialOnes) {
  const auto [kind, precision] = GetParam();
  const Region region = soup(21, 2000, {0, 0, 0}, 1, 0.05);
  const Shard shard = Shard::decode(build_shard(region.view(), kind, precision).payload);
  const std::vector<Box> boxes = query_boxes(shard, 22);
  auto answers = [&] {
    std::vector<std::vector<std::uint32_t>> out;
    for (int repeat = 0; repeat < 20; ++repeat)
      for (const Box& box : boxes) {
        std::vector<std::uint32_t> found;
        shard.for_each_candidate(box, [&](std::uint32_t t) { found.push_back(t); });
        std::sort(found.begin(), found.end());
        out.push_back(std::move(found));
      }
    return out;
  };
  const auto expected = answers();
  std::vector<std::vector<std::vector<std::uint32_t>>> results(3);
  std::vector<std::thread> threads;
  for (auto& r : results) threads.emplace_back([&r, &answers] { r = answers(); });
  for (auto& t : threads) t.join();
  for (const auto& r : results) EXPECT_EQ(r, expected);
}

TEST_P(ShardBuilderTest, NestedQueriesReportEachTriangleOnce) {
  const auto [kind, precision] = GetParam();
  const Region region = soup(23, 500, {0, 0, 0}, 1, 0.2);
  const Shard shard = Shard::decode(build_shard(region.view(), kind, precision).payload);
  const Box box{{-0.3, -0.3, -0.3}, {0.3, 0.3, 0.3}};
  std::vector<int> outer(shard.triangle_count(), 0);
  shard.for_each_candidate(box, [&](std::uint32_t t) {
    ++outer[t];
    std::vector<int> inner(shard.triangle_count(), 0);
    shard.for_each_candidate(box, [&](std::uint32_t u) { ++inner[u]; });
    for (std::uint32_t u = 0; u < shard.triangle_count(); ++u)
      ASSERT_EQ(inner[u], int(geometry::triangle_intersects_box(shard.triangle(u), box)));
  });
  for (std::uint32_t t = 0; t < shard.triangle_count(); ++t)
    EXPECT_EQ(outer[t], int(geometry::triangle_intersects_box(shard.triangle(t), box))) << t;
}

TEST_P(ShardBuilderTest, TruncatedAndCorruptedPayloadsThrowOrDecode) {
  const auto [kind, precision] = GetParam();
  Region region = soup(31, 40, {5, 5, 5}, 1, 0.3);
  const std::vector<std::byte> payload = build_shard(region.view(), kind, precision).payload;
  for (std::size_t length = 0; length < payload.size(); ++length)
    EXPECT_THROW(Shard::decode(std::span(payload).first(length)), FormatError) << length;
  Random r(32);
  int decoded = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    std::vector<std::byte> bad = payload;
    const int flips = 1 + int(r.below(3));
    for (int f = 0; f < flips; ++f) {
      // Mostly the header and the structure, where a flip does the most damage.
      const std::size_t at = r.below(2) ? r.below(shard_format::kHeaderBytes) : r.below(bad.size());
      bad[at] ^= std::byte(1u << r.below(8));
    }
    try {
      const Shard shard = Shard::decode(bad);
      ++decoded;
      // A valid but different shard: queries must still terminate and stay in range.
      for (const Box& box : query_boxes(shard, 33))
        shard.for_each_candidate(box,
                                 [&](std::uint32_t t) { ASSERT_LT(t, shard.triangle_count()); });
    } catch (const FormatError&) {
    }
  }
  RecordProperty("decoded_after_flips", decoded);
}

INSTANTIATE_TEST_SUITE_P(KindsAndPrecisions, ShardBuilderTest,
                         ::testing::Combine(::testing::Values(ShardKind::grid, ShardKind::rtree),
                                            ::testing::Values(StoredPrecision::float32,
                                                              StoredPrecision::float64)),
                         [](const auto& case_info) {
                           return std::string(to_string(std::get<0>(case_info.param))) + "_" +
                                  std::string(to_string(std::get<1>(case_info.param)));
                         });

TEST(ShardBuilder, ErrorMessagesNameTheFieldAndValue) {
  const Region region = soup(41, 30, {0, 0, 0}, 1, 0.2);
  std::vector<std::byte> payload =
      build_shard(region.view(), ShardKind::grid, StoredPrecision::float32).payload;
  auto message = [](std::vector<std::byte> bytes) {
    try {
      Shard::decode(bytes, "test.tpi shard 3");
    } catch (const FormatError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  auto bad = payload;
  bad[0] = std::byte{'X'};
  EXPECT_NE(message(bad).find("test.tpi shard 3: magic"), std::string::npos) << message(bad);
  bad = payload;
  bad[4] = std::byte{9};
  EXPECT_NE(message(bad).find("version = 9"), std::string::npos) << message(bad);
  bad = payload;
  const std::uint16_t huge = 0xffff;  // a corner index beyond the vertices
  std::uint64_t triangles_at;
  std::memcpy(&triangles_at, bad.data() + 128 + 8, 8);
  std::memcpy(bad.data() + triangles_at, &huge, 2);
  EXPECT_NE(message(bad).find("corner 0 of triangle 0 = 65535"), std::string::npos) << message(bad);
}

TEST(ShardBuilder, RejectsBadInput) {
  Region region = soup(42, 10, {0, 0, 0}, 1, 0.2);
  EXPECT_THROW(build_shard({}, ShardKind::grid, StoredPrecision::float32), InputError);
  Region mismatched = region;
  mismatched.ids.pop_back();
  EXPECT_THROW(build_shard(mismatched.view(), ShardKind::grid, StoredPrecision::float32),
               InputError);
  Region nan = region;
  nan.triangles[3][1][2] = std::nan("");
  EXPECT_THROW(build_shard(nan.view(), ShardKind::rtree, StoredPrecision::float64), InputError);
  Region huge = region;
  huge.triangles[0][0][0] = 1e300;
  EXPECT_THROW(build_shard(huge.view(), ShardKind::rtree, StoredPrecision::float32), InputError);
  EXPECT_NO_THROW(build_shard(huge.view(), ShardKind::rtree, StoredPrecision::float64));
  // Node boxes beyond float range from the origin (the runtime keeps them as floats, clamped)
  // still find every triangle.
  const Shard wide =
      Shard::decode(build_shard(huge.view(), ShardKind::rtree, StoredPrecision::float64).payload);
  EXPECT_EQ(check_queries(wide, query_boxes(wide, 12), "1e300 corner"), 0);
  ShardLayout fanout;
  fanout.rtree_fanout = 17;
  EXPECT_THROW(build_shard(region.view(), ShardKind::rtree, StoredPrecision::float32, fanout),
               InputError);
}

TEST(ShardBuilder, UsesCompactWidthsWhereTheyFit) {
  // One part and close ids: no part indices, 4-byte ids, 2-byte indices and references.
  Region region = soup(43, 200, {0, 0, 0}, 1, 0.1);
  std::fill(region.parts.begin(), region.parts.end(), 5u);
  const BuiltShard built = build_shard(region.view(), ShardKind::grid, StoredPrecision::float32);
  EXPECT_EQ(std::uint8_t(built.payload[8]), 2);
  EXPECT_EQ(std::uint8_t(built.payload[9]), 4);
  EXPECT_EQ(std::uint8_t(built.payload[10]), 0);
  EXPECT_EQ(std::uint8_t(built.payload[11]), 2);
  const Shard shard = Shard::decode(built.payload);
  for (std::uint32_t t = 0; t < shard.triangle_count(); ++t) EXPECT_EQ(shard.component_id(t), 5u);
  EXPECT_LE(built.vertex_count, 3 * built.triangle_count);
}

TEST(ShardBuilder, RtreeLeavesAreMedianCutsAlongTheLongestSide) {
  // Tiny triangles with centres at distinct x (in shuffled input order) along a long thin box:
  // every cut is along x, so, in tree order, leaf k holds exactly the triangles of x ranks
  // 16k .. 16k + 15 (every leaf but the last full), each leaf's in input order. A selection
  // that cut anywhere else still answers queries right, which the brute-force tests cannot see.
  for (const std::size_t n :
       {std::size_t(17), std::size_t(389), std::size_t(2048), std::size_t(3001)}) {
    Random r(n);
    std::vector<std::size_t> rank_of(n);
    std::iota(rank_of.begin(), rank_of.end(), 0);
    for (std::size_t i = n; i > 1; --i)
      std::swap(rank_of[i - 1], rank_of[r.below(std::uint32_t(i))]);
    Region region;
    for (std::size_t i = 0; i < n; ++i) {
      const double x = double(rank_of[i]) - 0.25 * double(n);  // negative and positive centres
      const double y = r.uniform(-0.1, 0.1), z = r.uniform(-0.1, 0.1);
      region.triangles.push_back({Point{x, y, z}, Point{x + 0.01, y, z}, Point{x, y + 0.01, z}});
      region.ids.push_back(i);
      region.parts.push_back(0);
    }
    ShardLayout layout;
    layout.rtree_leaf_size = 16;
    const BuiltShard built =
        build_shard(region.view(), ShardKind::rtree, StoredPrecision::float64, layout);
    const Shard shard = Shard::decode(built.payload);
    ASSERT_EQ(shard.triangle_count(), n);
    for (std::uint32_t t = 0; t < n; ++t) {
      const std::size_t input = shard.triangle_id(t);
      EXPECT_EQ(rank_of[input] / 16, t / 16) << "n " << n << " stored triangle " << t;
      if (t % 16 != 0) {
        EXPECT_GT(input, shard.triangle_id(t - 1)) << "n " << n << " stored triangle " << t;
      }
    }
  }
}

TEST(ShardCostModel, BothKindsFindTheSameCandidatesAndTheChoiceIsTheCheaper) {
  for (const Region& region : {soup(51, 1500, {0, 0, 0}, 1, 0.02), regions()[7]}) {
    const ShardCostModel model;
    const ShardCostReport report = estimate_shard_costs(
        region.view(), 0.1, StoredPrecision::float32, model, GridTrials::always);
    // The model measures count-only queries: they must examine exactly the cells, nodes and
    // references a deciding query examines.
    for (const auto* estimate : {&report.grid, &report.rtree}) {
      const Shard shard = Shard::decode(estimate->built.payload);
      for (std::uint32_t t = 0; t < shard.triangle_count(); t += 97) {
        const geometry::Triangle tri = shard.triangle(t);
        geometry::Box box;
        for (int k = 0; k < 3; ++k) {
          box.lo[k] = tri[0][k] - 0.05;
          box.hi[k] = tri[0][k] + 0.05;
        }
        ShardQueryCounters counted, decided;
        shard.count_query(box, counted);
        shard.for_each_candidate(
            box, [](std::uint32_t) {}, decided);
        EXPECT_EQ(counted.visited, decided.visited);
        EXPECT_EQ(counted.references, decided.references);
        EXPECT_GT(decided.candidates, 0u);
      }
    }
    EXPECT_GT(report.grid.references_per_query, 0.0);
    EXPECT_GT(report.rtree.references_per_query, 0.0);
    EXPECT_GT(report.grid.payload_bytes, 0u);
    const ShardKind cheaper = report.rtree.total_seconds() < report.grid.total_seconds()
                                  ? ShardKind::rtree
                                  : ShardKind::grid;
    EXPECT_EQ(report.chosen, cheaper);
    EXPECT_EQ(choose_shard_kind(region.view(), 0.1, model), cheaper);
  }
  EXPECT_THROW(
      estimate_shard_costs(regions()[0].view(), -1, StoredPrecision::float32, ShardCostModel{}),
      InputError);
}

TEST(ShardCostModel, TheGridFloorIsBelowEveryGridAndSkippingByItChoosesTheSame) {
  // Regions where grids win and where they lose, several query sizes, both precisions, and a
  // model that pages rarely (the floor is then mostly its reference count).
  std::vector<Region> all = regions();
  for (std::uint64_t seed = 20; seed < 26; ++seed)
    all.push_back(soup(seed, 400 + 300 * (seed % 3), {0, 0, 0}, 1, seed % 2 == 0 ? 0.002 : 0.3));
  ShardCostModel rare_paging;
  rare_paging.queries_per_page_in = 1e6;
  int skipped = 0, grids = 0;
  for (const Region& region : all)
    for (const double extent : {0.0, 0.05, 0.5})
      for (const StoredPrecision precision : {StoredPrecision::float32, StoredPrecision::float64})
        for (const ShardCostModel& model : {ShardCostModel{}, rare_paging}) {
          if (precision == StoredPrecision::float32 &&
              region.name.find("1e+09") != std::string::npos)
            continue;
          const ShardCostReport always =
              estimate_shard_costs(region.view(), extent, precision, model, GridTrials::always);
          const ShardCostReport pruned =
              estimate_shard_costs(region.view(), extent, precision, model);
          ASSERT_TRUE(always.grid_measured);
          EXPECT_LE(always.grid_floor_seconds, always.grid.total_seconds() * (1 + 1e-12))
              << region.name;
          EXPECT_EQ(always.grid_floor_seconds, pruned.grid_floor_seconds) << region.name;
          EXPECT_EQ(pruned.chosen, always.chosen) << region.name << " extent " << extent;
          EXPECT_EQ(pruned.chosen_estimate().built.payload, always.chosen_estimate().built.payload)
              << region.name;
          skipped += !pruned.grid_measured;
          grids += always.chosen == ShardKind::grid;
        }
  EXPECT_GT(skipped, 0) << "the floor must skip some grids";
  EXPECT_GT(grids, 0) << "and some regions must choose a grid";
}

}  // namespace
}  // namespace tetrapage
