// Shard decoding against payloads encoded here by hand from docs/SHARD-FORMAT.md (an encoder
// independent of the preprocess builder): the decoded triangles, ids and parts are the ones
// written, queries match brute force, and every truncation or corruption throws FormatError
// naming the field, or decodes to a shard whose queries stay in range.

#include "tetrapage/runtime/paging/Shard.h"
#include "tetrapage/runtime/paging/ShardArena.h"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <memory_resource>
#include <random>
#include <string>
#include <vector>

#include "tetrapage/formats/base/Error.h"

namespace tetrapage {
namespace {

using geometry::Box;
using geometry::Point;
using geometry::Triangle;

class Encoder {
 public:
  template <class T>
  void put(std::size_t at, T value) {
    if (bytes.size() < at + sizeof(T)) bytes.resize(at + sizeof(T));
    std::memcpy(bytes.data() + at, &value, sizeof(T));
  }
  template <class T>
  void append(T value) {
    put(bytes.size(), value);
  }
  void section(int s) {
    bytes.resize((bytes.size() + 7) / 8 * 8);
    put<std::uint64_t>(128 + 8 * std::size_t(s), bytes.size());
  }
  std::vector<std::byte> bytes = std::vector<std::byte>(192);
};

// Four float vertices relative to origin (100, 200, 300) (all exactly representable), two
// triangles, ids 7 and 9 (base 7), parts 3 and 5; either a 2x1x1 grid or an R-tree of a root
// over two leaves.
std::vector<std::byte> tiny_shard(ShardKind kind) {
  Encoder e;
  e.bytes[0] = std::byte{'T'};
  e.bytes[1] = std::byte{'P'};
  e.bytes[2] = std::byte{'S'};
  e.bytes[3] = std::byte{'H'};
  e.put<std::uint16_t>(4, 1);
  e.put<std::uint8_t>(6, std::uint8_t(kind));
  e.put<std::uint8_t>(7, 0);   // float32
  e.put<std::uint8_t>(8, 2);   // uint16 corners
  e.put<std::uint8_t>(9, 4);   // uint32 id offsets
  e.put<std::uint8_t>(10, 1);  // uint8 part indices
  e.put<std::uint8_t>(11, kind == ShardKind::grid ? 2 : 0);
  e.put<std::uint32_t>(12, 4);
  e.put<std::uint32_t>(16, 2);
  e.put<std::uint32_t>(20, 2);
  e.put<std::uint32_t>(24, kind == ShardKind::grid ? 2 : 3);
  e.put<std::uint32_t>(28, kind == ShardKind::grid ? 4 : 0);
  e.put<std::uint64_t>(32, 7);
  const double origin[3] = {100, 200, 300};
  for (int k = 0; k < 3; ++k) e.put<double>(40 + 8 * k, origin[k]);
  if (kind == ShardKind::grid) {
    const std::uint32_t cells[3] = {2, 1, 1};
    const double lo[3] = {99, 199, 300}, size[3] = {1, 2, 0.5};
    for (int k = 0; k < 3; ++k) {
      e.put<std::uint32_t>(64 + 4 * k, cells[k]);
      e.put<double>(80 + 8 * k, lo[k]);
      e.put<double>(104 + 8 * k, size[k]);
    }
  }
  e.section(0);
  const float vertices[4][3] = {{-1, -1, 0}, {-0.5f, 1, 0}, {0.25f, -1, 0}, {1, 1, 0.5f}};
  for (const auto& v : vertices)
    for (float c : v) e.append(c);
  e.section(1);
  for (std::uint16_t i : {0, 1, 2, 1, 2, 3}) e.append(i);
  e.section(2);
  e.append<std::uint32_t>(0);
  e.append<std::uint32_t>(2);
  e.section(3);
  e.append<std::uint32_t>(3);
  e.append<std::uint32_t>(5);
  e.section(4);
  e.append<std::uint8_t>(0);
  e.append<std::uint8_t>(1);
  e.section(5);
  if (kind == ShardKind::grid) {
    // Cells x in [99, 100] and [100, 101]: both triangles cross x = 100.
    for (std::uint32_t o : {0u, 2u, 4u}) e.append(o);
  } else {
    auto node = [&](std::array<float, 6> box, std::uint32_t first, std::uint32_t count) {
      for (float c : box) e.append(c);
      e.append(first);
      e.append(count);
    };
    node({-1, -1, 0, 1, 1, 0.5f}, 1, 2);
    node({-1, -1, 0, 0.25f, 1, 0}, 0, 1 | shard_format::kLeafFlag);
    node({-0.5f, -1, 0, 1, 1, 0.5f}, 1, 1 | shard_format::kLeafFlag);
  }
  e.section(6);
  if (kind == ShardKind::grid)
    for (std::uint16_t t : {0, 1, 0, 1}) e.append(t);
  e.section(7);
  return e.bytes;
}

class ShardTest : public ::testing::TestWithParam<ShardKind> {};

TEST_P(ShardTest, DecodesWhatWasEncoded) {
  const Shard shard = Shard::decode(tiny_shard(GetParam()));
  EXPECT_EQ(shard.kind(), GetParam());
  EXPECT_EQ(shard.precision(), StoredPrecision::float32);
  ASSERT_EQ(shard.triangle_count(), 2u);
  EXPECT_EQ(shard.triangle(0), (Triangle{Point{99, 199, 300}, Point{99.5, 201, 300},
                                         Point{100.25, 199, 300}}));
  EXPECT_EQ(shard.triangle(1), (Triangle{Point{99.5, 201, 300}, Point{100.25, 199, 300},
                                         Point{101, 201, 300.5}}));
  EXPECT_EQ(shard.triangle_id(0), 7u);
  EXPECT_EQ(shard.triangle_id(1), 9u);
  EXPECT_EQ(shard.component_id(0), 3u);
  EXPECT_EQ(shard.component_id(1), 5u);
  EXPECT_GT(shard.memory_bytes(), 0u);
}

TEST_P(ShardTest, QueriesMatchBruteForce) {
  const Shard shard = Shard::decode(tiny_shard(GetParam()));
  std::mt19937_64 engine(5);
  auto uniform = [&](double lo, double hi) {
    return lo + (hi - lo) * double(engine() >> 11) * 0x1.0p-53;
  };
  for (int q = 0; q < 2000; ++q) {
    Box box;
    box.lo = {uniform(98, 102), uniform(198, 202), uniform(299.5, 301)};
    box.hi = box.lo;
    if (q % 3) box.extend(Point{uniform(98, 102), uniform(198, 202), uniform(299.5, 301)});
    if (q % 7 == 0) box.hi[2] = box.lo[2] = 300;  // in the plane of triangle 0
    int seen[2] = {0, 0};
    shard.for_each_candidate(box, [&](std::uint32_t t) { ++seen[t]; });
    for (std::uint32_t t = 0; t < 2; ++t)
      EXPECT_EQ(seen[t], int(geometry::triangle_intersects_box(shard.triangle(t), box)))
          << "seed 5 query " << q << " triangle " << t;
  }
}

TEST_P(ShardTest, DecodesIntoAnArenaAlike) {
  const std::vector<std::byte> payload = tiny_shard(GetParam());
  ShardArena arena(std::size_t(4) << 20, 0);
  const Shard plain = Shard::decode(payload);
  Shard in_arena = Shard::decode(payload, "shard", DecodeChecks::full, &arena);
  ASSERT_EQ(in_arena.triangle_count(), plain.triangle_count());
  for (std::uint32_t t = 0; t < plain.triangle_count(); ++t) {
    EXPECT_EQ(in_arena.triangle(t), plain.triangle(t));
    EXPECT_EQ(in_arena.triangle_id(t), plain.triangle_id(t));
    EXPECT_EQ(in_arena.component_id(t), plain.component_id(t));
  }
  // A moved shard keeps its arrays (these tiny ones all go to the arena's upstream; the
  // flying tests decode real shards into an arena).
  const Shard moved = std::move(in_arena);
  EXPECT_EQ(moved.triangle(1), plain.triangle(1));
}

// Hands out memory from new/delete and counts the bytes it holds.
class CountingResource : public std::pmr::memory_resource {
 public:
  std::size_t held = 0;

 private:
  void* do_allocate(std::size_t bytes, std::size_t alignment) override {
    held += bytes;
    return std::pmr::new_delete_resource()->allocate(bytes, alignment);
  }
  void do_deallocate(void* p, std::size_t bytes, std::size_t alignment) override {
    held -= bytes;
    std::pmr::new_delete_resource()->deallocate(p, bytes, alignment);
  }
  bool do_is_equal(const std::pmr::memory_resource& other) const noexcept override { return this == &other; }
};

TEST_P(ShardTest, EveryArrayLivesInTheGivenMemory) {
  // A page-in decodes into the index's arena: every array of the shard must come from there.
  CountingResource memory;
  {
    const Shard shard = Shard::decode(tiny_shard(GetParam()), "shard", DecodeChecks::full, &memory);
    EXPECT_GT(memory.held, 0u);
    EXPECT_EQ(memory.held + sizeof(Shard), shard.memory_bytes());
  }
  EXPECT_EQ(memory.held, 0u);
}

TEST_P(ShardTest, EveryTruncationThrows) {
  const std::vector<std::byte> payload = tiny_shard(GetParam());
  for (std::size_t length = 0; length < payload.size(); ++length)
    EXPECT_THROW(Shard::decode(std::span(payload).first(length)), FormatError) << length;
}

TEST_P(ShardTest, ByteFlipsThrowOrDecodeToAUsableShard) {
  const std::vector<std::byte> payload = tiny_shard(GetParam());
  std::mt19937_64 engine(6);
  for (int trial = 0; trial < 10000; ++trial) {
    std::vector<std::byte> bad = payload;
    for (int f = 0; f < 1 + int(engine() % 3); ++f)
      bad[engine() % bad.size()] ^= std::byte(1u << (engine() % 8));
    // Half the trials with the structure checks only (a page-in's): still no crash or loop.
    const DecodeChecks checks = trial % 2 == 0 ? DecodeChecks::full : DecodeChecks::structure;
    try {
      const Shard shard = Shard::decode(bad, "shard", checks);
      const Box all{{-1e300, -1e300, -1e300}, {1e300, 1e300, 1e300}};
      std::vector<int> seen(shard.triangle_count(), 0);
      shard.for_each_candidate(all, [&](std::uint32_t t) {
        ASSERT_LT(t, shard.triangle_count()) << "seed 6 trial " << trial;
        ++seen[t];
      });
      for (int s : seen) EXPECT_LE(s, 1) << "seed 6 trial " << trial;
    } catch (const FormatError&) {
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Kinds, ShardTest, ::testing::Values(ShardKind::grid, ShardKind::rtree),
                         [](const auto& case_info) { return std::string(to_string(case_info.param)); });

TEST(Shard, NamesTheFieldAtFault) {
  auto message = [](std::vector<std::byte> bytes) {
    try {
      Shard::decode(bytes, "m.tpi shard 2");
    } catch (const FormatError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  auto bad = tiny_shard(ShardKind::grid);
  bad[6] = std::byte{7};
  EXPECT_EQ(message(bad).rfind("m.tpi shard 2: kind = 7", 0), 0u) << message(bad);
  bad = tiny_shard(ShardKind::grid);
  std::uint32_t three = 3;  // a reference to a third triangle of two
  std::uint64_t at;
  std::memcpy(&at, bad.data() + 128 + 8 * 6, 8);
  std::memcpy(bad.data() + at + 2, &three, 2);
  EXPECT_NE(message(bad).find("reference 1 = 3"), std::string::npos) << message(bad);
  bad = tiny_shard(ShardKind::rtree);
  std::memcpy(&at, bad.data() + 128 + 8 * 5, 8);
  float shrunk = 0.5f;  // the root no longer encloses leaf 2
  std::memcpy(bad.data() + at + 12, &shrunk, 4);
  EXPECT_NE(message(bad).find("does not enclose"), std::string::npos) << message(bad);
  bad = tiny_shard(ShardKind::rtree);
  float lowered = 0.25f;  // leaf 2's top below its triangle 1's corner at z 0.5
  std::memcpy(bad.data() + at + 2 * 32 + 20, &lowered, 4);
  EXPECT_NE(message(bad).find("box of R-tree leaf 2"), std::string::npos) << message(bad);
  EXPECT_NE(message(bad).find("does not enclose its triangle 1"), std::string::npos) << message(bad);
  // A stored vertex that is not finite is named (by either kind of checks).
  for (const DecodeChecks checks : {DecodeChecks::full, DecodeChecks::structure}) {
    std::vector<std::byte> nan = tiny_shard(ShardKind::rtree);
    std::uint64_t vertices;
    std::memcpy(&vertices, nan.data() + 128, 8);
    const float not_a_number = std::numeric_limits<float>::quiet_NaN();
    std::memcpy(nan.data() + vertices + 3 * 4 * 2 + 4, &not_a_number, 4);  // vertex 2's y
    try {
      Shard::decode(nan, "m.tpi shard 2", checks);
      ADD_FAILURE() << "a NaN vertex decoded";
    } catch (const FormatError& e) {
      EXPECT_NE(std::string(e.what()).find("stored vertex = 2"), std::string::npos) << e.what();
    }
  }
  // A page-in's checks leave the boxes to the writer and the checksums: the same payload
  // decodes, and every count and index is still checked.
  const Shard unchecked = Shard::decode(bad, "m.tpi shard 2", DecodeChecks::structure);
  EXPECT_EQ(unchecked.triangle_count(), 2u);
  bad[6] = std::byte{7};
  EXPECT_THROW(Shard::decode(bad, "m.tpi shard 2", DecodeChecks::structure), FormatError);
}

TEST(ShardKind, NamesRoundTrip) {
  for (ShardKind k : {ShardKind::grid, ShardKind::rtree})
    EXPECT_EQ(parse_shard_kind(to_string(k)), k);
  for (StoredPrecision p : {StoredPrecision::float32, StoredPrecision::float64})
    EXPECT_EQ(parse_stored_precision(to_string(p)), p);
  EXPECT_THROW(parse_shard_kind("octree"), InputError);
  EXPECT_THROW(parse_stored_precision("half"), InputError);
}

}  // namespace
}  // namespace tetrapage
