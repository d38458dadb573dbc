// The shard cache against a brute-force LRU model, and its promises under threads: the
// budget is never exceeded (measured by the fake shards themselves), pins hold, one load per
// shard, errors propagate and leave the cache consistent, deadlocks are reported, the
// prefetcher obeys its policy and winds down cleanly.

#include "tetrapage/runtime/paging/ShardCache.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <latch>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "tetrapage/formats/base/Error.h"

namespace tetrapage {
namespace {

using namespace std::chrono_literals;

// Bytes of fake shards alive right now, and the most ever alive at once.
struct LiveBytes {
  std::atomic<std::int64_t> bytes{0}, peak{0}, count{0};
  std::chrono::microseconds destroy_delay{0};  // a slow destructor widens the eviction window
  void add(std::int64_t delta) {
    const std::int64_t now = bytes.fetch_add(delta) + delta;
    count.fetch_add(delta > 0 ? 1 : -1);
    std::int64_t seen = peak.load();
    while (now > seen && !peak.compare_exchange_weak(seen, now)) {
    }
  }
};

// A decoded shard as far as the cache can tell: an id, a size, a payload to check for
// use after free (the sanitizers see reads of a freed payload).
class FakeShard {
 public:
  FakeShard(std::uint32_t id, std::uint64_t bytes, LiveBytes* live)
      : id_(id), bytes_(bytes), payload_(8, id), live_(live) {
    live_->add(std::int64_t(bytes_));
  }
  FakeShard(const FakeShard&) = delete;
  FakeShard& operator=(const FakeShard&) = delete;
  ~FakeShard() {
    if (live_->destroy_delay.count() > 0) std::this_thread::sleep_for(live_->destroy_delay);
    live_->add(-std::int64_t(bytes_));
  }

  std::uint64_t memory_bytes() const { return bytes_; }
  std::uint32_t id() const { return id_; }
  bool intact() const {
    return std::all_of(payload_.begin(), payload_.end(), [&](std::uint32_t v) { return v == id_; });
  }

 private:
  std::uint32_t id_;
  std::uint64_t bytes_;
  std::vector<std::uint32_t> payload_;
  LiveBytes* live_;
};

struct LoaderFailure : std::runtime_error {
  explicit LoaderFailure(std::uint32_t id)
      : std::runtime_error("disk error on shard " + std::to_string(id)) {}
};

using Cache = ShardCache<FakeShard>;

// The shards of a fake index: announced sizes, actual sizes, and a loader that counts its
// calls and can be slowed down, held at a gate or made to fail.
struct FakeIndex {
  explicit FakeIndex(std::vector<std::uint64_t> sizes)
      : announced(sizes), actual(std::move(sizes)), calls(announced.size()) {}

  std::vector<std::uint64_t> announced, actual;
  std::vector<std::atomic<int>> calls;
  LiveBytes live;
  std::chrono::microseconds delay{0};
  std::vector<bool> failing;
  std::atomic<int> in_flight{0};
  std::atomic<bool> gate_closed{false};

  Cache::Loader loader() {
    return [this](std::uint32_t id) -> std::shared_ptr<const FakeShard> {
      calls[id].fetch_add(1);
      in_flight.fetch_add(1);
      while (gate_closed.load()) std::this_thread::sleep_for(200us);
      if (delay.count() > 0) std::this_thread::sleep_for(delay);
      if (!failing.empty() && failing[id]) {
        in_flight.fetch_sub(1);
        throw LoaderFailure(id);
      }
      auto shard = std::make_shared<const FakeShard>(id, actual[id], &live);
      in_flight.fetch_sub(1);
      return shard;
    };
  }
  Cache::ExpectedBytes expected() {
    return [this](std::uint32_t id) { return announced[id]; };
  }
  std::unique_ptr<Cache> make(std::uint64_t budget, ShardCacheOptions options = {}) {
    return std::make_unique<Cache>(budget, loader(), announced.size(), expected(), options);
  }
  int total_calls() const {
    int sum = 0;
    for (const auto& c : calls) sum += c.load();
    return sum;
  }
};

ShardCacheOptions no_prefetcher() {
  ShardCacheOptions options;
  options.prefetch_threads = 0;
  return options;
}

std::vector<std::uint64_t> random_sizes(std::mt19937_64& random, std::size_t count,
                                        std::uint64_t lo, std::uint64_t hi) {
  std::uniform_int_distribution<std::uint64_t> size(lo, hi);
  std::vector<std::uint64_t> sizes(count);
  for (auto& s : sizes) s = size(random);
  return sizes;
}

// Polls `done` for up to a minute (a bound against hanging, not a timing requirement).
template <class Done>
bool eventually(Done done) {
  const auto give_up = std::chrono::steady_clock::now() + 60s;
  while (!done()) {
    if (std::chrono::steady_clock::now() > give_up) return false;
    std::this_thread::sleep_for(200us);
  }
  return true;
}

// Resident bytes by the cache's own account against the shards it reports resident, and
// against the fake shards alive. Call on a settled cache only.
void expect_consistent(const Cache& cache, const FakeIndex& index) {
  const ShardCacheCounters c = cache.counters();
  std::uint64_t sum = 0, count = 0;
  for (std::uint32_t s = 0; s < cache.shard_count(); ++s)
    if (cache.contains(s)) {
      sum += index.actual[s];
      ++count;
    }
  EXPECT_EQ(c.reserved_bytes, 0u);
  EXPECT_EQ(c.resident_bytes, sum);
  EXPECT_EQ(c.resident_shards, count);
  EXPECT_EQ(std::uint64_t(index.live.bytes.load()), sum);
  EXPECT_EQ(std::uint64_t(index.live.count.load()), count);
  EXPECT_LE(c.resident_bytes, c.budget_bytes);
}

// The brute-force reference: resident set, pins, and the unpinned shards in LRU order.
struct LruModel {
  std::uint64_t budget = 0, used = 0;
  std::map<std::uint32_t, int> pins;  // resident shards -> pin count
  std::vector<std::uint32_t> order;   // unpinned resident shards, least recently used first
  std::uint64_t hits = 0, misses = 0, evictions = 0;

  void acquire(std::uint32_t id, const std::vector<std::uint64_t>& sizes) {
    if (auto it = pins.find(id); it != pins.end()) {
      ++hits;
      if (it->second++ == 0) order.erase(std::find(order.begin(), order.end(), id));
      return;
    }
    ++misses;
    while (used + sizes[id] > budget) {
      ASSERT_FALSE(order.empty()) << "the model never blocks";
      used -= sizes[order.front()];
      pins.erase(order.front());
      order.erase(order.begin());
      ++evictions;
    }
    used += sizes[id];
    pins[id] = 1;
  }
  void release(std::uint32_t id) {
    if (--pins[id] == 0) order.push_back(id);
  }
};

TEST(ShardCache, MatchesBruteForceLruModel) {
  for (const std::uint64_t seed : {1u, 2u, 3u, 4u}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    std::mt19937_64 random(seed);
    FakeIndex index(random_sizes(random, 40, 1, 100));
    // Up to 3 pins of at most 100 bytes plus one load: never blocks.
    const std::uint64_t budget = 400 + seed * 37;
    auto cache = index.make(budget, no_prefetcher());
    LruModel model;
    model.budget = budget;
    std::vector<Cache::Pin> held;
    std::vector<int> model_loads(40, 0);
    for (int step = 0; step < 3000; ++step) {
      if (held.size() < 3 && (held.empty() || random() % 2 == 0)) {
        const auto id = std::uint32_t(random() % 40);
        if (!model.pins.contains(id)) ++model_loads[id];
        model.acquire(id, index.actual);
        held.push_back(cache->acquire(id));
        ASSERT_EQ(held.back()->id(), id);
      } else {
        const std::size_t which = random() % held.size();
        model.release(held[which].id());
        held.erase(held.begin() + std::ptrdiff_t(which));
      }
      for (std::uint32_t s = 0; s < 40; ++s) {
        ASSERT_EQ(cache->contains(s), model.pins.contains(s)) << "shard " << s << " step " << step;
        ASSERT_EQ(index.calls[s].load(), model_loads[s]) << "shard " << s << " step " << step;
      }
    }
    const ShardCacheCounters c = cache->counters();
    EXPECT_EQ(c.hits, model.hits);
    EXPECT_EQ(c.misses, model.misses);
    EXPECT_EQ(c.evictions, model.evictions);
    EXPECT_EQ(c.page_ins, model.misses);
    EXPECT_EQ(c.resident_bytes, model.used);
    // Per shard: each page-in is a load of that shard (the loader's own call count).
    const auto per_shard = cache->page_ins_per_shard();
    ASSERT_EQ(per_shard.size(), 40u);
    for (std::uint32_t s = 0; s < 40; ++s) EXPECT_EQ(per_shard[s], std::uint32_t(model_loads[s])) << "shard " << s;
    cache->reset_counters();
    for (const auto n : cache->page_ins_per_shard()) EXPECT_EQ(n, 0u);
    held.clear();
    expect_consistent(*cache, index);
  }
}

TEST(ShardCache, EvictsLeastRecentlyUsedFirst) {
  FakeIndex index(std::vector<std::uint64_t>(10, 100));
  auto cache = index.make(300, no_prefetcher());
  for (std::uint32_t s : {0u, 1u, 2u}) cache->acquire(s);
  cache->acquire(0);  // 1 becomes the least recently used
  cache->acquire(3);
  EXPECT_TRUE(cache->contains(0));
  EXPECT_FALSE(cache->contains(1));
  EXPECT_TRUE(cache->contains(2));
  EXPECT_TRUE(cache->contains(3));
  EXPECT_EQ(cache->counters().evictions, 1u);
  expect_consistent(*cache, index);
}

TEST(ShardCache, PinnedShardIsNeverEvicted) {
  FakeIndex index(std::vector<std::uint64_t>(20, 100));
  auto cache = index.make(300, no_prefetcher());
  const Cache::Pin pinned = cache->acquire(0);
  for (int round = 0; round < 5; ++round)
    for (std::uint32_t s = 1; s < 20; ++s) {
      const Cache::Pin pin = cache->acquire(s);
      ASSERT_TRUE(cache->contains(0));
      ASSERT_TRUE(pinned->intact());
    }
  EXPECT_EQ(index.calls[0].load(), 1);
  EXPECT_EQ(cache->counters().pinned_bytes, 100u);
}

TEST(ShardCache, PinsMoveAndReleaseOnce) {
  FakeIndex index(std::vector<std::uint64_t>(4, 100));
  auto cache = index.make(300, no_prefetcher());
  Cache::Pin a = cache->acquire(1);
  Cache::Pin b = std::move(a);
  EXPECT_FALSE(a);
  ASSERT_TRUE(b);
  EXPECT_EQ(b.id(), 1u);
  EXPECT_EQ(cache->counters().pinned_bytes, 100u);
  Cache::Pin c = cache->acquire(2);
  c = std::move(b);  // releases 2, takes over 1
  EXPECT_EQ(cache->counters().pinned_bytes, 100u);
  c.reset();
  EXPECT_EQ(cache->counters().pinned_bytes, 0u);
  EXPECT_TRUE(cache->contains(1));
  EXPECT_TRUE(cache->contains(2));
}

TEST(ShardCache, WaitsForOtherThreadsPins) {
  FakeIndex index(std::vector<std::uint64_t>(10, 100));
  auto cache = index.make(300, no_prefetcher());
  std::vector<Cache::Pin> held;
  for (std::uint32_t s : {0u, 1u, 2u}) held.push_back(cache->acquire(s));
  std::atomic<bool> done{false};
  std::thread other([&] {
    const Cache::Pin pin = cache->acquire(3);
    done = true;
  });
  ASSERT_TRUE(eventually([&] { return cache->counters().pin_waits == 1; }));
  std::this_thread::sleep_for(5ms);
  EXPECT_FALSE(done.load()) << "loaded over pinned shards";
  for (std::uint32_t s : {0u, 1u, 2u}) EXPECT_TRUE(cache->contains(s));
  held.erase(held.begin() + 1);  // release shard 1 only
  other.join();
  EXPECT_TRUE(done.load());
  EXPECT_TRUE(cache->contains(0));
  EXPECT_FALSE(cache->contains(1));
  EXPECT_TRUE(cache->contains(2));
  EXPECT_TRUE(cache->contains(3));
  EXPECT_LE(index.live.peak.load(), 300);
}

TEST(ShardCache, ShardLargerThanBudgetIsAnInputError) {
  FakeIndex index({100, 5000, 100});
  auto cache = index.make(4096);
  try {
    cache->acquire(1);
    FAIL() << "no exception";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("shard 1"), std::string::npos) << message;
    EXPECT_NE(message.find("5000"), std::string::npos) << message;
    EXPECT_NE(message.find("4096"), std::string::npos) << message;
  }
  EXPECT_EQ(index.calls[1].load(), 0);
  const std::uint32_t hint[] = {1};
  cache->prefetch(hint);
  cache->wait_prefetch_idle();
  EXPECT_EQ(cache->counters().prefetch_dropped, 1u);
  EXPECT_EQ(index.calls[1].load(), 0);
  EXPECT_TRUE(cache->acquire(2));  // still usable
}

TEST(ShardCache, OwnPinsBlockingTheLoadThrowInsteadOfWaiting) {
  FakeIndex index({100, 100, 100, 100, 250});
  ShardCacheOptions options = no_prefetcher();
  options.pin_wait_timeout = 60s;  // a wait would hang the test: it must throw at once
  auto cache = index.make(300, options);
  {
    std::vector<Cache::Pin> query;
    for (std::uint32_t s : {0u, 1u, 2u}) query.push_back(cache->acquire(s));
    try {
      cache->acquire(3);
      FAIL() << "no exception";
    } catch (const InputError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("shard 3"), std::string::npos) << message;
      EXPECT_NE(message.find("working set"), std::string::npos) << message;
    }
    query.pop_back();  // 200 pinned: shard 4 (250) still cannot fit
    EXPECT_THROW(cache->acquire(4), InputError);
    EXPECT_EQ(cache->counters().pin_waits, 0u);
    EXPECT_TRUE(cache->acquire(3));  // 2 is unpinned: evicted
  }
  EXPECT_TRUE(cache->acquire(4));  // the query is over: everything can go
  EXPECT_EQ(index.calls[3].load(), 1);
  EXPECT_EQ(index.calls[4].load(), 1);
  expect_consistent(*cache, index);
}

TEST(ShardCache, ThreadsWaitingOnEachOthersPinsAreADeadlockError) {
  FakeIndex index({150, 150, 100, 100});
  ShardCacheOptions options = no_prefetcher();
  options.pin_wait_timeout = 60s;  // detection, not the timeout, must end the wait
  auto cache = index.make(300, options);
  std::latch both_pinned(2);
  std::atomic<int> deadlock_errors{0}, successes{0};
  auto query = [&](std::uint32_t first, std::uint32_t second) {
    Cache::Pin a = cache->acquire(first);
    both_pinned.arrive_and_wait();
    try {
      Cache::Pin b = cache->acquire(second);
      EXPECT_EQ(b->id(), second);
      ++successes;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("deadlock"), std::string::npos) << e.what();
      ++deadlock_errors;
    }
  };
  std::thread t1(query, 0, 2), t2(query, 1, 3);
  t1.join();
  t2.join();
  EXPECT_EQ(deadlock_errors.load(), 1);
  EXPECT_EQ(successes.load(), 1);
  EXPECT_EQ(cache->counters().pinned_bytes, 0u);
  expect_consistent(*cache, index);
}

TEST(ShardCache, TimesOutWhenPinsAreNotReleased) {
  FakeIndex index({200, 200});
  ShardCacheOptions options = no_prefetcher();
  options.pin_wait_timeout = 20ms;
  auto cache = index.make(300, options);
  std::atomic<bool> release{false};
  std::atomic<bool> pinned{false};
  std::thread holder([&] {  // holds its pin while not waiting in the cache: no deadlock seen
    const Cache::Pin pin = cache->acquire(0);
    pinned = true;
    while (!release.load()) std::this_thread::sleep_for(1ms);
  });
  ASSERT_TRUE(eventually([&] { return pinned.load(); }));
  try {
    cache->acquire(1);
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("waited"), std::string::npos) << e.what();
  }
  release = true;
  holder.join();
  EXPECT_TRUE(cache->acquire(1));
  expect_consistent(*cache, index);
}

// The waiters sleep at once, poll and then sleep, or get the shard while they poll (the
// load takes 20 ms).
class ConcurrentAcquires : public ::testing::TestWithParam<std::chrono::microseconds> {};

TEST_P(ConcurrentAcquires, OfOneShardLoadItOnce) {
  FakeIndex index(std::vector<std::uint64_t>(10, 100));
  index.delay = 20ms;
  ShardCacheOptions options = no_prefetcher();
  options.spin_before_sleep = GetParam();
  auto cache = index.make(1000, options);
  constexpr int kThreads = 8;
  std::latch start(kThreads);
  std::vector<const FakeShard*> seen(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t] {
      start.arrive_and_wait();
      const Cache::Pin pin = cache->acquire(7);
      seen[std::size_t(t)] = &*pin;
    });
  for (auto& t : threads) t.join();
  EXPECT_EQ(index.calls[7].load(), 1);
  for (const FakeShard* s : seen) EXPECT_EQ(s, seen[0]);
  const ShardCacheCounters c = cache->counters();
  EXPECT_EQ(c.page_ins, 1u);
  EXPECT_EQ(c.hits + c.misses, std::uint64_t(kThreads));
  EXPECT_GE(c.misses, 1u);
}

INSTANTIATE_TEST_SUITE_P(ShardCache, ConcurrentAcquires, ::testing::Values(0us, 200us, 50ms),
                         [](const auto& case_info) { return std::to_string(case_info.param.count()) + "us"; });

TEST(ShardCache, LoaderExceptionPropagatesAndLeavesTheCacheConsistent) {
  FakeIndex index(std::vector<std::uint64_t>(6, 100));
  index.failing = {false, false, false, true, false, false};
  index.delay = 2ms;
  auto cache = index.make(300, no_prefetcher());
  const Cache::Pin keep = cache->acquire(0);
  EXPECT_THROW(cache->acquire(3), LoaderFailure);
  // Concurrent requests: each one fails (a waiter retries the load and fails in turn).
  std::latch start(4);
  std::atomic<int> failures{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&] {
      start.arrive_and_wait();
      try {
        cache->acquire(3);
      } catch (const LoaderFailure&) {
        ++failures;
      }
    });
  for (auto& t : threads) t.join();
  EXPECT_EQ(failures.load(), 4);
  EXPECT_GE(index.calls[3].load(), 2);
  const ShardCacheCounters c = cache->counters();
  EXPECT_EQ(c.load_failures, std::uint64_t(index.calls[3].load()));
  EXPECT_EQ(c.reserved_bytes, 0u);
  EXPECT_FALSE(cache->contains(3));
  EXPECT_TRUE(keep->intact());
  // The whole budget is usable again: no reservation leaked.
  index.failing[3] = false;
  {
    const Cache::Pin b = cache->acquire(3), d = cache->acquire(4);
    EXPECT_EQ(cache->counters().resident_bytes, 300u);
  }
  expect_consistent(*cache, index);
}

TEST(ShardCache, LoaderReturningNothingIsAnError) {
  Cache cache(
      1000, [](std::uint32_t) { return std::shared_ptr<const FakeShard>(); }, 3,
      [](std::uint32_t) { return std::uint64_t(10); }, no_prefetcher());
  EXPECT_THROW(cache.acquire(1), Error);
  EXPECT_EQ(cache.counters().reserved_bytes, 0u);
  EXPECT_EQ(cache.counters().load_failures, 1u);
}

TEST(ShardCache, ActualSizeReplacesTheAnnouncedOne) {
  FakeIndex index({100, 100, 100, 100});
  index.actual = {60, 150, 100, 100};  // 0 smaller than announced, 1 larger
  auto cache = index.make(300, no_prefetcher());
  cache->acquire(0);
  EXPECT_EQ(cache->counters().resident_bytes, 60u);
  cache->acquire(1);  // 60 + 150 fits
  EXPECT_EQ(cache->counters().resident_bytes, 210u);
  expect_consistent(*cache, index);
  {
    const Cache::Pin a = cache->acquire(2), b = cache->acquire(3);  // evicts 0 and 1
    // 200 pinned: 1 would need 150 once loaded, announced 100: no room for the difference.
    try {
      cache->acquire(1);
      FAIL() << "no exception";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("shard 1"), std::string::npos) << e.what();
    }
    EXPECT_EQ(cache->counters().reserved_bytes, 0u);
    EXPECT_LE(index.live.peak.load(), 300 + 50) << "only the undersold difference may exceed";
  }
  expect_consistent(*cache, index);
}

TEST(ShardCache, ArgumentsAreChecked) {
  FakeIndex index({10, 10});
  EXPECT_THROW(Cache(0, index.loader(), 2, index.expected()), InputError);
  EXPECT_THROW(Cache(100, Cache::Loader{}, 2, index.expected()), InputError);
  EXPECT_THROW(Cache(100, index.loader(), 2, Cache::ExpectedBytes{}), InputError);
  auto cache = index.make(100);
  EXPECT_THROW(cache->acquire(2), InputError);
  EXPECT_THROW(cache->contains(2), InputError);
  const std::uint32_t hints[] = {0, 2};
  EXPECT_THROW(cache->prefetch(hints), InputError);
  cache->wait_prefetch_idle();
  EXPECT_EQ(index.total_calls(), 0) << "nothing of a rejected hint list is queued";
}

TEST(ShardCache, ExplicitSizeOfForTypesWithoutMemoryBytes) {
  struct Plain {
    std::uint64_t size;
  };
  ShardCache<Plain>::SizeOf size_of = [](const Plain& p) { return p.size; };
  EXPECT_THROW(ShardCache<Plain>(
                   100, [](std::uint32_t) { return std::make_shared<const Plain>(Plain{10}); }, 2,
                   [](std::uint32_t) { return std::uint64_t(10); }),
               InputError);
  ShardCache<Plain> cache(
      100, [](std::uint32_t s) { return std::make_shared<const Plain>(Plain{10 + s}); }, 2,
      [](std::uint32_t) { return std::uint64_t(20); }, no_prefetcher(), size_of);
  EXPECT_EQ(cache.acquire(1)->size, 11u);
  EXPECT_EQ(cache.counters().resident_bytes, 11u);
}

TEST(ShardCache, PrefetchedShardIsAHitLater) {
  FakeIndex index(std::vector<std::uint64_t>(10, 100));
  auto cache = index.make(1000);
  const std::uint32_t hints[] = {4, 5};
  cache->prefetch(hints);
  cache->wait_prefetch_idle();
  ShardCacheCounters c = cache->counters();
  EXPECT_EQ(c.prefetch_loads, 2u);
  EXPECT_EQ(c.prefetched_unused, 2u);
  const Cache::Pin pin = cache->acquire(4);
  c = cache->counters();
  EXPECT_EQ(c.hits, 1u);
  EXPECT_EQ(c.misses, 0u);
  EXPECT_EQ(c.prefetch_hits, 1u);
  EXPECT_EQ(c.prefetched_unused, 1u);
  EXPECT_EQ(c.page_ins, 2u);
  EXPECT_EQ(index.calls[4].load(), 1);
  cache->acquire(4);  // a second use is no longer a prefetch hit
  EXPECT_EQ(cache->counters().prefetch_hits, 1u);
}

TEST(ShardCache, PrefetchEvictsOnlyShardsOutsideTheRecentAcquisitions) {
  FakeIndex index(std::vector<std::uint64_t>(10, 100));
  ShardCacheOptions options;
  options.protected_recent = 2;
  auto cache = index.make(300, options);
  for (std::uint32_t s : {0u, 1u, 2u}) cache->acquire(s);
  // 0 was used before the last 2 acquisitions: it may make room for 9; then nothing may.
  const std::uint32_t hints[] = {9, 8};
  cache->prefetch(hints);
  cache->wait_prefetch_idle();
  EXPECT_FALSE(cache->contains(0));
  EXPECT_TRUE(cache->contains(1));
  EXPECT_TRUE(cache->contains(2));
  EXPECT_TRUE(cache->contains(9));
  EXPECT_FALSE(cache->contains(8));
  const ShardCacheCounters c = cache->counters();
  EXPECT_EQ(c.prefetch_loads, 1u);
  EXPECT_EQ(c.prefetch_dropped, 1u);
  EXPECT_EQ(index.calls[8].load(), 0);
  // Pinned shards are never evicted by the prefetcher, however old.
  std::vector<Cache::Pin> pins;
  for (std::uint32_t s : {1u, 2u, 9u}) pins.push_back(cache->acquire(s));
  for (std::uint32_t s = 0; s < 10; ++s) cache->prefetch(std::span(&s, 1));
  cache->wait_prefetch_idle();
  for (std::uint32_t s : {1u, 2u, 9u}) EXPECT_TRUE(cache->contains(s));
  EXPECT_EQ(cache->counters().resident_bytes, 300u);
  pins.clear();
  expect_consistent(*cache, index);
}

TEST(ShardCache, StaleHintsAreDroppedOldestFirst) {
  FakeIndex index(std::vector<std::uint64_t>(12, 10));
  ShardCacheOptions options;
  options.prefetch_queue_limit = 4;
  auto cache = index.make(1000, options);
  index.gate_closed = true;
  const std::uint32_t first[] = {0};
  cache->prefetch(first);
  ASSERT_TRUE(eventually([&] { return index.in_flight.load() == 1; }));
  const std::uint32_t later[] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
  cache->prefetch(later);
  EXPECT_EQ(cache->counters().prefetch_dropped, 6u);
  index.gate_closed = false;
  cache->wait_prefetch_idle();
  for (std::uint32_t s = 0; s <= 10; ++s)
    EXPECT_EQ(cache->contains(s), s == 0 || s >= 7) << "shard " << s;
  EXPECT_EQ(cache->counters().prefetch_hints, 11u);
}

TEST(ShardCache, PrefetchFailureIsCountedAndTheAcquireRetries) {
  FakeIndex index(std::vector<std::uint64_t>(4, 10));
  index.failing = {false, true, false, false};
  auto cache = index.make(1000);
  const std::uint32_t hints[] = {1, 2};
  cache->prefetch(hints);
  cache->wait_prefetch_idle();
  const ShardCacheCounters c = cache->counters();
  EXPECT_EQ(c.prefetch_dropped, 1u);
  EXPECT_EQ(c.prefetch_loads, 1u);
  EXPECT_EQ(c.load_failures, 1u);
  EXPECT_EQ(c.reserved_bytes, 0u);
  EXPECT_THROW(cache->acquire(1), LoaderFailure);
  EXPECT_EQ(index.calls[1].load(), 2);
}

// Many threads, random shards of random sizes, several pins per query, prefetch hints and
// occasional slow loads: the fake shards alive never exceed the budget.
TEST(ShardCache, BudgetHoldsUnderConcurrentQueriesAndPrefetch) {
  const std::uint64_t seed = 2024;
  SCOPED_TRACE("seed " + std::to_string(seed));
  std::mt19937_64 random(seed);
  FakeIndex index(random_sizes(random, 80, 1, 2000));
  const std::uint64_t budget = 12000;
  ShardCacheOptions options;
  options.prefetch_threads = 2;
  options.prefetch_queue_limit = 16;
  options.protected_recent = 8;
  options.pin_wait_timeout = 60s;  // only a missed deadlock would reach it
  index.delay = 50us;              // widens the windows between reserve and install
  index.live.destroy_delay = 20us;
  auto cache = index.make(budget, options);

  constexpr int kThreads = 4;
  std::atomic<int> deadlocks{0}, other_errors{0}, torn{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t] {
      std::mt19937_64 mine(seed * 100 + std::uint64_t(t));
      for (int query = 0; query < 600; ++query) {
        std::vector<Cache::Pin> pins;
        const int wanted = 1 + int(mine() % 4);  // own pins + 1 load <= budget
        try {
          for (int k = 0; k < wanted; ++k) {
            const auto id = std::uint32_t(mine() % 80);
            pins.push_back(cache->acquire(id));
            if (pins.back()->id() != id || !pins.back()->intact()) ++torn;
          }
        } catch (const InputError& e) {
          const std::string message = e.what();
          if (message.find("deadlock") != std::string::npos ||
              message.find("working set") != std::string::npos)
            ++deadlocks;
          else
            ++other_errors;
        }
        for (const auto& pin : pins)
          if (!pin->intact()) ++torn;
        if (mine() % 4 == 0) {
          std::uint32_t hints[4];
          for (auto& h : hints) h = std::uint32_t(mine() % 80);
          cache->prefetch(hints);
        }
      }
    });
  for (auto& t : threads) t.join();
  cache->wait_prefetch_idle();

  const ShardCacheCounters c = cache->counters();
  EXPECT_EQ(torn.load(), 0);
  EXPECT_EQ(other_errors.load(), 0);
  EXPECT_LE(std::uint64_t(index.live.peak.load()), budget);
  EXPECT_LE(c.peak_resident_bytes, budget);
  EXPECT_GT(c.evictions, 0u);
  EXPECT_GT(c.prefetch_loads, 0u);
  EXPECT_EQ(c.pinned_bytes, 0u);
  EXPECT_EQ(c.page_ins, std::uint64_t(index.total_calls()) - c.load_failures);
  expect_consistent(*cache, index);
  std::printf(
      "hits %llu misses %llu page_ins %llu evictions %llu prefetch loads %llu hits %llu "
      "dropped %llu deadlock errors %d peak %llu of %llu\n",
      (unsigned long long)c.hits, (unsigned long long)c.misses, (unsigned long long)c.page_ins,
      (unsigned long long)c.evictions, (unsigned long long)c.prefetch_loads,
      (unsigned long long)c.prefetch_hits, (unsigned long long)c.prefetch_dropped, deadlocks.load(),
      (unsigned long long)c.peak_resident_bytes, (unsigned long long)budget);
  cache.reset();
  EXPECT_EQ(index.live.count.load(), 0);
}

TEST(ShardCache, DestructionJoinsABusyPrefetcher) {
  for (int round = 0; round < 5; ++round) {
    FakeIndex index(std::vector<std::uint64_t>(200, 10));
    index.delay = 1ms;
    ShardCacheOptions options;
    options.prefetch_threads = 2;
    options.prefetch_queue_limit = 1000;
    auto cache = index.make(2000, options);
    std::vector<std::uint32_t> hints(200);
    for (std::uint32_t s = 0; s < 200; ++s) hints[s] = s;
    cache->prefetch(hints);
    {
      const Cache::Pin pin = cache->acquire(199);
      EXPECT_TRUE(pin->intact());
    }
    if (round % 2 == 1) {
      ASSERT_TRUE(eventually([&] { return index.in_flight.load() > 0; }));
    }
    cache.reset();
    EXPECT_EQ(index.in_flight.load(), 0);
    EXPECT_EQ(index.live.count.load(), 0);
    const int calls = index.total_calls();
    std::this_thread::sleep_for(3ms);
    EXPECT_EQ(index.total_calls(), calls) << "a loader ran after destruction";
  }
}

TEST(ShardCache, LatencyPercentilesAndReset) {
  FakeIndex index(std::vector<std::uint64_t>(20, 10));
  index.delay = 1ms;
  auto cache = index.make(100, no_prefetcher());
  for (std::uint32_t s = 0; s < 20; ++s) cache->acquire(s);
  ShardCacheCounters c = cache->counters();
  EXPECT_EQ(c.latency_samples, 20u);
  EXPECT_GE(c.page_in_p50_us, 1000.0);  // the loader sleeps at least 1 ms
  EXPECT_LE(c.page_in_p50_us, c.page_in_p99_us);
  EXPECT_LE(c.page_in_p99_us, c.page_in_max_us);
  EXPECT_EQ(c.bytes_loaded, 200u);
  EXPECT_EQ(c.peak_resident_bytes, 100u);
  cache->reset_counters();
  c = cache->counters();
  EXPECT_EQ(c.hits + c.misses + c.page_ins + c.bytes_loaded + c.evictions + c.latency_samples, 0u);
  EXPECT_EQ(c.page_in_max_us, 0.0);
  EXPECT_EQ(c.resident_bytes, 100u);
  EXPECT_EQ(c.peak_resident_bytes, 100u);
}

}  // namespace
}  // namespace tetrapage
