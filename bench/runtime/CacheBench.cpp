// Shard cache micro benchmarks: the cost of a hit, of a miss with eviction (a free loader, so
// only the cache's bookkeeping is timed), hits from several threads, and a simulated flight
// whose loads take real time, with and without the prefetcher: the worst step is what an
// embedded caller's frame time sees.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <cstdint>
#include <memory>
#include <thread>
#include <vector>

#include "tetrapage/formats/base/SpinThenBlock.h"
#include "tetrapage/runtime/paging/ShardCache.h"

namespace {

using namespace std::chrono_literals;

struct FakeShard {
  std::uint32_t id;
  std::uint64_t bytes;
  std::uint64_t memory_bytes() const { return bytes; }
};
using Cache = tetrapage::ShardCache<FakeShard>;

std::unique_ptr<Cache> make_cache(std::uint64_t budget, std::size_t shards,
                                  std::chrono::microseconds load_time,
                                  tetrapage::ShardCacheOptions options) {
  return std::make_unique<Cache>(
      budget,
      [load_time](std::uint32_t id) {
        if (load_time.count() > 0) std::this_thread::sleep_for(load_time);
        return std::make_shared<const FakeShard>(FakeShard{id, 1000});
      },
      shards, [](std::uint32_t) { return std::uint64_t(1000); }, options);
}

tetrapage::ShardCacheOptions without_prefetcher() {
  tetrapage::ShardCacheOptions options;
  options.prefetch_threads = 0;
  return options;
}

void BM_AcquireHit(benchmark::State& state) {
  auto cache = make_cache(64 * 1000, 64, 0us, without_prefetcher());
  for (std::uint32_t s = 0; s < 64; ++s) cache->acquire(s);
  std::uint32_t next = 0;
  for (auto _ : state) {
    auto pin = cache->acquire(next);
    benchmark::DoNotOptimize(pin->id);
    next = (next + 1) & 63;
  }
}
BENCHMARK(BM_AcquireHit);

// Cycling over twice the budget: every acquisition misses and evicts.
void BM_AcquireMissEvict(benchmark::State& state) {
  auto cache = make_cache(64 * 1000, 128, 0us, without_prefetcher());
  std::uint32_t next = 0;
  for (auto _ : state) {
    auto pin = cache->acquire(next);
    benchmark::DoNotOptimize(pin->id);
    next = (next + 1) & 127;
  }
  state.counters["evictions"] = double(cache->counters().evictions);
}
BENCHMARK(BM_AcquireMissEvict);

Cache* shared_cache = nullptr;
void BM_AcquireHitThreads(benchmark::State& state) {
  if (state.thread_index() == 0) {
    shared_cache = make_cache(64 * 1000, 64, 0us, without_prefetcher()).release();
    for (std::uint32_t s = 0; s < 64; ++s) shared_cache->acquire(s);
  }
  auto next = std::uint32_t(state.thread_index() * 7);
  for (auto _ : state) {
    auto pin = shared_cache->acquire(next & 63);
    benchmark::DoNotOptimize(pin->id);
    ++next;
  }
  if (state.thread_index() == 0) {
    delete shared_cache;
    shared_cache = nullptr;
  }
}
BENCHMARK(BM_AcquireHitThreads)->Threads(1)->Threads(2)->UseRealTime();

// A flight along a line of shards: each step pins a window of 4 consecutive shards and moves
// one shard on; a load takes 200 us. With prefetch, the next 4 shards are hinted each step.
void BM_SimulatedFlight(benchmark::State& state) {
  const bool prefetch = state.range(0) != 0;
  tetrapage::ShardCacheOptions options;
  options.prefetch_threads = prefetch ? 1 : 0;
  options.protected_recent = 8;
  constexpr std::uint32_t kShards = 4096, kWindow = 4;
  auto cache = make_cache(16 * 1000, kShards, 200us, options);
  std::uint32_t position = 0;
  double worst_us = 0;
  std::vector<double> steps_us;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    {
      std::vector<Cache::Pin> pins;
      for (std::uint32_t k = 0; k < kWindow; ++k)
        pins.push_back(cache->acquire((position + k) % kShards));
      if (prefetch) {
        std::uint32_t hints[kWindow];
        for (std::uint32_t k = 0; k < kWindow; ++k) hints[k] = (position + kWindow + k) % kShards;
        cache->prefetch(hints);
      }
    }
    const double us =
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
    worst_us = std::max(worst_us, us);
    steps_us.push_back(us);
    // The rest of the frame (phase I and II) before the object moves on.
    std::this_thread::sleep_for(300us);
    position = (position + 1) % kShards;
  }
  std::sort(steps_us.begin(), steps_us.end());
  const tetrapage::ShardCacheCounters c = cache->counters();
  state.counters["step_p50_us"] = steps_us[steps_us.size() / 2];
  state.counters["step_p99_us"] =
      steps_us[std::min(steps_us.size() - 1, steps_us.size() * 99 / 100)];
  state.counters["step_max_us"] = worst_us;
  state.counters["hit_rate"] =
      double(c.hits) / double(std::max<std::uint64_t>(1, c.hits + c.misses));
  state.counters["prefetch_hits"] = double(c.prefetch_hits);
  state.counters["page_in_p50_us"] = c.page_in_p50_us;
  state.counters["peak_bytes"] = double(c.peak_resident_bytes);
}
BENCHMARK(BM_SimulatedFlight)
    ->Arg(0)
    ->Arg(1)
    ->Iterations(2000)
    ->UseRealTime()
    ->Unit(benchmark::kMicrosecond);

// A turn handed back and forth between two threads: through a condition variable (each side
// sleeps until woken), or polled (SpinThenBlock.h). What a hand-off between the flying thread
// and the prefetcher costs, twice; a page-in from the page cache is about 18 us on the 10M
// scene.
void BM_HandOff(benchmark::State& state) {
  const bool polled = state.range(0) != 0;
  std::mutex mutex;
  std::condition_variable turned;
  std::atomic<int> turn{0};  // 1: the other thread's, 0: this one's, -1: stop
  auto wait_for = [&](auto done) {
    if (polled) {
      tetrapage::spin_until(done, std::chrono::hours(1));
    } else {
      std::unique_lock lock(mutex);
      turned.wait(lock, done);
    }
  };
  auto hand = [&](int to) {
    {
      const std::lock_guard lock(mutex);
      turn.store(to);
    }
    turned.notify_one();
  };
  std::thread other([&] {
    for (;;) {
      wait_for([&] { return turn.load() != 0; });
      if (turn.load() < 0) return;
      hand(0);
    }
  });
  for (auto _ : state) {
    hand(1);
    wait_for([&] { return turn.load() == 0; });
  }
  hand(-1);
  other.join();
  state.SetLabel(polled ? "polled round trip" : "condition variable round trip");
}
BENCHMARK(BM_HandOff)->Arg(0)->Arg(1)->UseRealTime()->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
