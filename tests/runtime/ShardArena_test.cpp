#include "tetrapage/runtime/paging/ShardArena.h"

#include <gtest/gtest.h>
#include <sys/mman.h>

#include <chrono>
#include <cstring>
#include <memory_resource>
#include <random>
#include <thread>
#include <vector>

namespace tetrapage {
namespace {

// An upstream that counts what it holds, to check that every block goes back where it came from.
class CountingResource final : public std::pmr::memory_resource {
 public:
  std::atomic<long> live{0};

 private:
  void* do_allocate(std::size_t bytes, std::size_t alignment) override {
    ++live;
    return std::pmr::new_delete_resource()->allocate(bytes, alignment);
  }
  void do_deallocate(void* p, std::size_t bytes, std::size_t alignment) override {
    --live;
    std::pmr::new_delete_resource()->deallocate(p, bytes, alignment);
  }
  bool do_is_equal(const std::pmr::memory_resource& other) const noexcept override {
    return this == &other;
  }
};

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kArenaOff = true;  // the arena leaves everything to malloc under AddressSanitizer
#else
constexpr bool kArenaOff = false;
#endif

TEST(ShardArena, BlockSizesWasteAtMostAnEighth) {
  for (std::size_t bytes = 1; bytes <= (std::size_t(5) << 20); bytes += 1 + bytes / 64) {
    const std::size_t block = ShardArena::block_bytes(bytes);
    ASSERT_GE(block, bytes) << bytes;
    if (bytes <= 512) {
      EXPECT_EQ(block, std::max<std::size_t>(64, (bytes + 63) / 64 * 64)) << bytes;
    } else if (bytes <= (std::size_t(4) << 20)) {
      EXPECT_LE(8 * block, 9 * bytes + 8 * 64) << bytes;  // an eighth, or one 64-byte step
      EXPECT_EQ(block % 64, 0u) << bytes;
    } else {
      EXPECT_EQ(block, bytes) << bytes;
    }
  }
}

// Many threads allocate blocks of random sizes, fill each with their own pattern, check
// it and free the blocks in random order: no two live blocks overlap, every block of the
// arena is 64-byte aligned, and each goes back to where it came from.
TEST(ShardArena, ConcurrentBlocksNeverOverlapAndAllComeBack) {
  CountingResource upstream;
  {
    ShardArena arena(std::size_t(6) << 20, std::size_t(1) << 20, &upstream);
    auto work = [&](unsigned seed) {
      std::mt19937_64 engine(seed);
      std::vector<std::pair<std::byte*, std::size_t>> live;
      for (int i = 0; i < 4000; ++i) {
        if (!live.empty() && engine() % 3 == 0) {
          const std::size_t k = engine() % live.size();
          auto [p, n] = live[k];
          for (std::size_t j = 0; j < n; j += 97)
            ASSERT_EQ(p[j], std::byte(seed + j)) << "seed " << seed << " block of " << n;
          arena.deallocate(p, n, 8);
          live[k] = live.back();
          live.pop_back();
          continue;
        }
        const std::size_t n = 1 + engine() % (engine() % 8 == 0 ? 300000 : 20000);
        auto* p = static_cast<std::byte*>(arena.allocate(n, 8));
        ASSERT_EQ(reinterpret_cast<std::uintptr_t>(p) % (arena.owns(p) ? 64 : 8), 0u);
        for (std::size_t j = 0; j < n; j += 97) p[j] = std::byte(seed + j);
        live.emplace_back(p, n);
      }
      for (auto [p, n] : live) arena.deallocate(p, n, 8);
    };
    std::vector<std::thread> threads;
    for (unsigned t = 0; t < 4; ++t) threads.emplace_back(work, 11 + t);
    for (auto& thread : threads) thread.join();
    if (!kArenaOff) {
      EXPECT_GT(arena.arena_blocks(), 0u);
      EXPECT_GT(arena.upstream_blocks(), 0u);  // the range used up
      EXPECT_LE(arena.frontier_bytes(), arena.capacity());
    }
  }
  EXPECT_EQ(upstream.live.load(), 0);
}

TEST(ShardArena, FreedBlocksAreReusedByTheirClass) {
  if (kArenaOff) GTEST_SKIP() << "the arena is off under AddressSanitizer";
  ShardArena arena(std::size_t(4) << 20, 0);
  void* a = arena.allocate(10000, 8);
  EXPECT_TRUE(arena.owns(a));
  const std::size_t frontier = arena.frontier_bytes();
  arena.deallocate(a, 10000, 8);
  // 9,500 and 10,000 bytes share a class (9,216 < n <= 10,240): the same block comes back.
  void* b = arena.allocate(9500, 8);
  EXPECT_EQ(a, b);
  EXPECT_EQ(arena.frontier_bytes(), frontier);
  // Another class takes fresh range.
  void* c = arena.allocate(20000, 8);
  EXPECT_NE(c, a);
  EXPECT_GT(arena.frontier_bytes(), frontier);
  arena.deallocate(b, 9500, 8);
  arena.deallocate(c, 20000, 8);
  // Tiny requests take 64-byte steps of the range; huge and over-aligned ones go upstream.
  void* tiny = arena.allocate(100, 8);
  void* huge = arena.allocate(std::size_t(5) << 20, 8);
  void* aligned = arena.allocate(4096, 4096);
  EXPECT_TRUE(arena.owns(tiny));
  EXPECT_FALSE(arena.owns(huge));
  EXPECT_FALSE(arena.owns(aligned));
  arena.deallocate(tiny, 100, 8);
  arena.deallocate(huge, std::size_t(5) << 20, 8);
  arena.deallocate(aligned, 4096, 4096);
}

// Whether this kernel can populate a range ahead (Linux 5.14 on): probed on a page of its own.
bool kernel_populates() {
  void* page = ::mmap(nullptr, 4096, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (page == MAP_FAILED) return false;
  const bool populates = ::madvise(page, 4096, 23 /* MADV_POPULATE_WRITE */) == 0;
  ::munmap(page, 4096);
  return populates;
}

TEST(ShardArena, PopulatesAheadOfItsFrontier) {
  if (kArenaOff) GTEST_SKIP() << "the arena is off under AddressSanitizer";
  if (!kernel_populates())
    GTEST_SKIP() << "this kernel cannot populate ahead (MADV_POPULATE_WRITE)";
  const std::size_t ahead = std::size_t(3) << 20;
  ShardArena arena(std::size_t(32) << 20, ahead);
  std::vector<void*> blocks;
  // The thread is woken when the frontier has used half its lead: the lead stays within
  // [ahead / 2, ahead], and a page.
  auto check_lead = [&] {
    const std::size_t frontier = arena.frontier_bytes();
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (arena.populates() && arena.populated_bytes() < frontier + ahead / 2 &&
           std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    EXPECT_TRUE(arena.populates());
    EXPECT_GE(arena.populated_bytes(), frontier + ahead / 2);
    EXPECT_LE(arena.populated_bytes(), frontier + ahead + 4096);  // not the whole range
  };
  // Blocks of 10,240 bytes: the frontier, and the target ahead of it, fall between pages,
  // and the thread populates from where it stopped each time.
  for (int round = 0; round < 3; ++round) {
    for (int i = 0; i < 1 + 150 * round; ++i) blocks.push_back(arena.allocate(10000, 8));
    check_lead();
  }
  for (void* p : blocks) arena.deallocate(p, 10000, 8);
}

// Past its limit (the shard budget) the range is never populated ahead: a page there becomes
// resident only when a block uses it. Resident pages counted by mincore().
// Bytes of the arena's range resident from `first` (its first block, at the range's start) on,
// by mincore.
std::size_t resident_bytes_from(void* first, const ShardArena& arena) {
  std::vector<unsigned char> pages(arena.capacity() / 4096);
  EXPECT_EQ(::mincore(first, arena.capacity(), pages.data()), 0);
  std::size_t count = 0;
  for (const unsigned char page : pages) count += page & 1;
  return count * 4096;
}

TEST(ShardArena, PopulatesNoFurtherThanItsLimit) {
  if (kArenaOff) GTEST_SKIP() << "the arena is off under AddressSanitizer";
  if (!kernel_populates())
    GTEST_SKIP() << "this kernel cannot populate ahead (MADV_POPULATE_WRITE)";
  const std::size_t limit = std::size_t(5) << 20, ahead = std::size_t(3) << 20;
  ShardArena arena(std::size_t(16) << 20, ahead, std::pmr::new_delete_resource(), limit);
  std::vector<void*> blocks;
  const auto resident_pages = [&] { return resident_bytes_from(blocks.front(), arena) / 4096; };
  const auto settle = [&] {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (arena.populated_bytes() < std::min(limit, arena.frontier_bytes() + ahead / 2) &&
           std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  };
  // Frontier at 4 MiB: populated up to the limit, not to 4 + 3 MiB.
  while (arena.frontier_bytes() < (std::size_t(4) << 20)) blocks.push_back(arena.allocate(65536, 64));
  settle();
  EXPECT_LE(arena.populated_bytes(), limit + 4096);
  EXPECT_LE(resident_pages() * 4096, limit + 4096);
  EXPECT_GE(resident_pages() * 4096, std::size_t(4) << 20);
  // Frontier at 9 MiB: past the limit only the pages blocks were written to are resident.
  while (arena.frontier_bytes() < (std::size_t(9) << 20)) {
    blocks.push_back(arena.allocate(65536, 64));
    std::memset(blocks.back(), 1, 65536);
  }
  settle();
  EXPECT_LE(resident_pages() * 4096, arena.frontier_bytes() + 4096);
  for (void* p : blocks) arena.deallocate(p, 65536, 64);
}

// Blocks of one size fill the limit and are freed; blocks of another size then take the range
// past it. The free blocks, and those freed past the limit, give their pages back: the range
// stays near its limit resident, and a block taken again from them holds what is written to it.
TEST(ShardArena, FreedBlocksGiveTheirPagesBackPastTheLimit) {
  if (kArenaOff) GTEST_SKIP() << "the arena is off under AddressSanitizer";
  const std::size_t limit = std::size_t(4) << 20, small = 65536, large = 100000;
  ShardArena arena(std::size_t(16) << 20, 0, std::pmr::new_delete_resource(), limit);
  const auto resident = [&](void* first) { return resident_bytes_from(first, arena); };
  const auto fill = [&](std::size_t bytes, std::size_t total, unsigned char pattern) {
    std::vector<void*> blocks;
    for (std::size_t sum = 0; sum < total; sum += bytes) {
      blocks.push_back(arena.allocate(bytes, 64));
      std::memset(blocks.back(), pattern, bytes);
    }
    return blocks;
  };
  std::vector<void*> smalls = fill(small, limit, 1);
  void* const first = smalls.front();
  for (void* p : smalls) arena.deallocate(p, small, 64);
  // Under the limit, freed blocks keep their pages for the next block of their size.
  EXPECT_GE(resident(first), limit);
  // Blocks of another size past the limit: the free blocks give their pages back first, so
  // that the range holds the limit (or the live blocks, when they hold more) and one block.
  std::vector<void*> larges = fill(large, limit, 2);
  const std::size_t live = larges.size() * ShardArena::block_bytes(large);
  EXPECT_GT(arena.frontier_bytes(), limit + live - ShardArena::block_bytes(large));
  EXPECT_LE(resident(first), std::max(limit, live) + ShardArena::block_bytes(large));
  EXPECT_LE(arena.resident_bytes(), std::max(limit, live) + ShardArena::block_bytes(large));
  for (void* p : larges) arena.deallocate(p, large, 64);
  // Each block keeps the partial pages at its two ends (its link in the list is outside it).
  const std::size_t kept = larges.size() * 2 * 4096;
  EXPECT_LE(resident(first), limit + kept) << "frontier " << arena.frontier_bytes();
  EXPECT_LE(resident(first), arena.resident_bytes());
  EXPECT_LE(arena.resident_bytes(), limit + kept);
  // Taken again, the blocks that gave their pages back read what is written to them.
  const std::size_t frontier = arena.frontier_bytes();
  larges = fill(large, limit, 3);
  for (void* p : larges) {
    const auto* bytes = static_cast<const unsigned char*>(p);
    for (std::size_t i = 0; i < large; i += 4093) ASSERT_EQ(bytes[i], 3) << i;
  }
  EXPECT_EQ(arena.frontier_bytes(), frontier) << "the blocks were reused";
  for (void* p : larges) arena.deallocate(p, large, 64);
  EXPECT_LE(resident(first), limit + kept);
}

// Blocks served upstream (here one over the largest class) count against the limit too: with
// one of them live, every block freed in the range gives its pages back.
TEST(ShardArena, BlocksUpstreamCountAgainstTheLimit) {
  if (kArenaOff) GTEST_SKIP() << "the arena is off under AddressSanitizer";
  const std::size_t limit = std::size_t(4) << 20, block = 65536, huge = std::size_t(5) << 20;
  ShardArena arena(std::size_t(16) << 20, 0, std::pmr::new_delete_resource(), limit);
  void* upstream = arena.allocate(huge, 64);
  ASSERT_FALSE(arena.owns(upstream));
  std::vector<void*> blocks;
  for (std::size_t sum = 0; sum < limit / 2; sum += block) {
    blocks.push_back(arena.allocate(block, 64));
    std::memset(blocks.back(), 1, block);
  }
  void* const first = blocks.front();
  EXPECT_GE(resident_bytes_from(first, arena), limit / 2);
  for (void* p : blocks) arena.deallocate(p, block, 64);
  EXPECT_LE(resident_bytes_from(first, arena), blocks.size() * 2 * 4096);
  arena.deallocate(upstream, huge, 64);
}

TEST(ShardArena, NoRangeLeavesEverythingUpstream) {
  CountingResource upstream;
  {
    ShardArena arena(0, std::size_t(1) << 20, &upstream);
    void* p = arena.allocate(10000, 8);
    EXPECT_FALSE(arena.owns(p));
    EXPECT_EQ(upstream.live.load(), 1);
    arena.deallocate(p, 10000, 8);
  }
  EXPECT_EQ(upstream.live.load(), 0);
}

}  // namespace
}  // namespace tetrapage
