#pragma once
/// @file ShardCache.h
/// The runtime's shard cache: decoded shards kept resident under a byte budget that is never
/// exceeded, least recently used first out, with pins that keep a shard alive while a query
/// reads it and a background prefetcher that loads the shards ahead of the motion.
///
/// The budget counts every byte the cache is responsible for: resident shards (pinned or
/// not), reservations for loads in flight (sized before loading by `expected_bytes`), and
/// evicted shards until their destructor has returned. So at every instant the bytes of
/// shards alive through the cache stay within the budget, which is what an embedded caller
/// with a hard memory limit needs.
///
/// Worst-case frame time: no lock is held while a loader runs or a shard is destroyed, so
/// queries on resident shards never wait behind a page-in or an eviction of another shard;
/// several threads load different shards at once and concurrent requests for one shard wait
/// for a single load. Waits poll for up to options.spin_before_sleep before they sleep.
///
/// Generic over the shard type (ShardCache<Shard> at run time, a fake type in the tests).

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <exception>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <stop_token>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/SpinThenBlock.h"
#include "tetrapage/runtime/paging/LatencyReservoir.h"
#include "tetrapage/runtime/paging/PinTable.h"
#include "tetrapage/runtime/paging/PrefetchQueue.h"

namespace tetrapage {

/// Knobs of a ShardCache.
struct ShardCacheOptions {
  /// Background loader threads; 0 disables prefetching (every hint is dropped).
  std::size_t prefetch_threads = 1;
  /// Hints waiting beyond this many are stale: the oldest are dropped first.
  std::size_t prefetch_queue_limit = 256;
  /// A prefetched shard may evict only unpinned shards last used before the most recent
  /// `protected_recent` acquisitions (so the current and the previous step stay resident);
  /// when that is not enough room the hint is dropped.
  std::uint64_t protected_recent = 64;
  /// How long acquire waits for other threads to release pins before it gives up.
  std::chrono::milliseconds pin_wait_timeout{5000};
  /// Page-in durations kept (a uniform reservoir sample) for the latency percentiles.
  std::size_t latency_reservoir = 4096;
  /// How long a thread waiting for the cache's lock, an acquire waiting for another thread's
  /// load of its shard, and a prefetch thread with nothing queued poll before they sleep. On a
  /// virtual machine a sleep and its wake-up cost about 25 us each way, more than a page-in
  /// from the page cache. While hints keep coming (a flight), the prefetch thread thus keeps
  /// its core busy; 0 makes every wait sleep at once.
  std::chrono::microseconds spin_before_sleep{200};
};

/// A snapshot of a ShardCache's counters (events since construction or the last reset) and
/// gauges (the state at the time of the snapshot).
struct ShardCacheCounters {
  std::uint64_t hits = 0;      ///< acquisitions that found the shard resident
  std::uint64_t misses = 0;    ///< acquisitions that did not (including waits for a load in flight)
  std::uint64_t page_ins = 0;  ///< loads completed, by acquire or by the prefetcher
  std::uint64_t load_failures = 0;  ///< loads whose loader (or size check) threw
  std::uint64_t bytes_loaded = 0;   ///< resident bytes of the shards loaded
  std::uint64_t evictions = 0;
  std::uint64_t pin_waits = 0;                ///< acquisitions that waited for pins to be released
  std::uint64_t prefetch_hints = 0;           ///< hints received by prefetch()
  std::uint64_t prefetch_loads = 0;           ///< loads done by the prefetcher (also in page_ins)
  std::uint64_t prefetch_hits = 0;            ///< first acquisitions of a prefetched shard
  std::uint64_t prefetch_dropped = 0;         ///< hints not loaded: stale, no room, too big, failed
  std::uint64_t prefetch_evicted_unused = 0;  ///< prefetched shards evicted before any use

  std::uint64_t budget_bytes = 0;
  std::uint64_t resident_bytes = 0;  ///< shards resident now
  std::uint64_t reserved_bytes = 0;  ///< reservations of loads in flight now
  std::uint64_t pinned_bytes = 0;    ///< resident shards pinned now
  std::uint64_t resident_shards = 0;
  std::uint64_t prefetched_unused = 0;    ///< prefetched shards resident and not yet acquired
  std::uint64_t peak_resident_bytes = 0;  ///< highest resident + reserved + being evicted

  std::uint64_t latency_samples = 0;  ///< page-ins timed (the reservoir holds at most its size)
  double page_in_p50_us = 0;
  double page_in_p99_us = 0;
  double page_in_max_us = 0;  ///< exact, not sampled
};

/// An LRU cache of decoded shards under a byte budget. Thread-safe: acquire, prefetch,
/// contains, counters and reset_counters may be called from any number of threads.
///
/// Requirements on ShardType: none, unless no `size_of` function is given, in which case
/// `std::uint64_t memory_bytes() const` must exist and give the resident bytes.
template <class ShardType>
class ShardCache {
 public:
  /// Loads and decodes one shard; called without any cache lock, possibly from several
  /// threads at once (for different shards). May throw; see acquire.
  using Loader = std::function<std::shared_ptr<const ShardType>(std::uint32_t shard)>;
  /// The resident bytes of a shard before it is loaded (the index's decoded size); an upper
  /// bound of size_of(loaded shard) keeps the budget exact without evicting twice.
  using ExpectedBytes = std::function<std::uint64_t(std::uint32_t shard)>;
  /// The resident bytes of a loaded shard.
  using SizeOf = std::function<std::uint64_t(const ShardType& shard)>;

  /// RAII handle on a resident shard: while it exists the shard is never evicted. Movable,
  /// not copyable. Must not outlive its cache. Pins are attributed to the thread that
  /// acquired them for the deadlock checks of acquire (moving one to another thread is
  /// allowed, but then acquire may report a deadlock that the other thread would resolve).
  class Pin {
   public:
    Pin() = default;
    Pin(const Pin&) = delete;
    Pin& operator=(const Pin&) = delete;
    Pin(Pin&& other) noexcept { take(other); }
    Pin& operator=(Pin&& other) noexcept {
      if (this != &other) {
        reset();
        take(other);
      }
      return *this;
    }
    ~Pin() { reset(); }

    /// The shard. Precondition: the pin holds one (operator bool).
    const ShardType& operator*() const { return *shard_; }
    const ShardType* operator->() const { return shard_; }
    const ShardType& shard() const { return *shard_; }
    /// The shard's id; meaningless when the pin is empty.
    std::uint32_t id() const { return id_; }
    explicit operator bool() const { return cache_ != nullptr; }
    /// Releases the shard now (the pin becomes empty).
    void reset() noexcept {
      if (cache_ != nullptr) cache_->release(id_, owner_);
      cache_ = nullptr;
      shard_ = nullptr;
    }

   private:
    friend class ShardCache;
    Pin(ShardCache* cache, std::uint32_t id, const ShardType* shard, std::thread::id owner)
        : cache_(cache), shard_(shard), id_(id), owner_(owner) {}
    void take(Pin& other) noexcept {
      cache_ = std::exchange(other.cache_, nullptr);
      shard_ = std::exchange(other.shard_, nullptr);
      id_ = other.id_;
      owner_ = other.owner_;
    }

    ShardCache* cache_ = nullptr;
    const ShardType* shard_ = nullptr;
    std::uint32_t id_ = 0;
    std::thread::id owner_;
  };

  /// Starts the prefetch threads. Shards are numbered 0 .. shard_count - 1.
  /// `size_of` may be left empty when ShardType has memory_bytes().
  /// @throw InputError if the budget is zero, shard_count does not fit 32-bit ids, loader or
  ///        expected_bytes is empty, or size_of is empty and ShardType has no memory_bytes().
  ShardCache(std::uint64_t budget_bytes, Loader loader, std::size_t shard_count,
             ExpectedBytes expected_bytes, ShardCacheOptions options = {}, SizeOf size_of = {});

  /// Stops the prefetch threads: queued hints are dropped, a load in flight completes first.
  /// Precondition: no pin is alive and no other thread is inside a member function.
  ~ShardCache();

  ShardCache(const ShardCache&) = delete;
  ShardCache& operator=(const ShardCache&) = delete;

  /// Pins `shard`, loading it in the calling thread if it is not resident (evicting the least
  /// recently used unpinned shards to make room). When the budget is full of shards pinned by
  /// other threads, waits until enough are released.
  /// @throw InputError if `shard` is out of range; if its expected size exceeds the whole
  ///        budget (the message names the shard, its size and the budget); if the calling
  ///        thread's own pins leave too little of the budget for it, or every pin is held by
  ///        threads that are themselves waiting for room (the budget is too small for the
  ///        queries' working set); if room did not appear within options.pin_wait_timeout;
  ///        or if the loaded shard is larger than announced and the difference cannot be made
  ///        room for by evicting unpinned shards.
  /// @throw Error if the loader returned no shard.
  /// @throw whatever the loader, expected_bytes or size_of threw (the reservation is
  ///        released and the next acquire of the shard tries again).
  Pin acquire(std::uint32_t shard);

  /// Queues hints for the prefetch threads and returns at once. A hint is loaded only if it
  /// fits after evicting unpinned shards older than options.protected_recent acquisitions;
  /// otherwise, or when the queue overflows (oldest first), or when the load fails, it is
  /// dropped and counted. A failed load (an I/O or checksum error) leaves the shard empty, so
  /// the next acquire of it loads it again in the caller's thread and throws the loader's
  /// error there: a fault the prefetcher meets surfaces in the query that needs the shard,
  /// and the other shards stay usable.
  /// @throw InputError if a shard id is out of range (nothing is queued then).
  void prefetch(std::span<const std::uint32_t> shards) { enqueue(shards, false); }
  /// The same, ahead of every queued hint, the last shard first: for the shards a query is
  /// about to acquire in order (the threads load from the end while the query loads from the
  /// start). On overflow the newest ordinary hints are dropped.
  void prefetch_urgently(std::span<const std::uint32_t> shards) { enqueue(shards, true); }

  /// Blocks until the prefetch queue is empty and no prefetch load is in flight (for
  /// benchmarks and tests that need a settled cache; hints queued meanwhile extend the wait).
  void wait_prefetch_idle();

  /// Whether `shard` is resident now (pinned or not; not while it is loading).
  /// @throw InputError if `shard` is out of range.
  bool contains(std::uint32_t shard) const;
  /// Acquisitions that had to load (cheap: one atomic read; counters() sorts latencies).
  std::uint64_t miss_count() const { return misses_.load(std::memory_order_relaxed); }
  /// The highest resident + reserved bytes so far (one lock; no latency sort).
  std::uint64_t peak_resident_bytes() const {
    const std::unique_lock lock = lock_spinning_first(mutex_, options_.spin_before_sleep);
    return peak_;
  }

  /// A snapshot of the counters, gauges and page-in latency percentiles.
  ShardCacheCounters counters() const;
  /// Zeroes the counters and the latency samples; the peak restarts from the current bytes.
  void reset_counters();
  /// How many times each shard was paged in (since construction or reset_counters), by shard
  /// id: where a flight made the cache work (tetrapage render colours regions by it).
  std::vector<std::uint32_t> page_ins_per_shard() const;

  std::uint64_t budget_bytes() const { return budget_; }
  std::size_t shard_count() const { return entries_.size(); }

 private:
  static constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

  enum class State : std::uint8_t { empty, loading, resident };
  struct Entry {
    std::shared_ptr<const ShardType> shard;
    std::uint64_t bytes = 0;  ///< reserved while loading, resident bytes once resident
    std::uint64_t stamp = 0;  ///< acquisitions_ when last acquired, released or prefetched
    std::uint32_t pins = 0;
    std::uint32_t page_ins = 0;  ///< since construction or the last reset_counters
    std::uint32_t lru_prev = kNone, lru_next = kNone;  ///< in the LRU list iff resident, unpinned
    State state = State::empty;
    bool prefetched_unused = false;
  };
  enum class Eviction : std::uint8_t { any_unpinned, old_unpinned };

  void release(std::uint32_t shard, std::thread::id owner) noexcept;
  Pin take_pin(std::uint32_t shard);
  void reserve(Entry& entry, std::uint64_t bytes, bool by_prefetch);
  void cancel_reservation(Entry& entry);
  void install(std::unique_lock<std::mutex>& lock, std::uint32_t shard,
               std::shared_ptr<const ShardType> loaded, std::uint64_t size, Eviction eviction);
  bool evict_one(std::unique_lock<std::mutex>& lock, Eviction eviction);
  bool evictable(const Entry& entry, Eviction eviction) const;
  bool old_bytes_cover(std::uint64_t bytes) const;
  bool nobody_can_release() const;
  std::uint64_t pinned_bytes_of(std::thread::id thread) const;
  void link_lru_tail(std::uint32_t shard);
  void unlink_lru(std::uint32_t shard);
  void add_used(std::uint64_t bytes);
  void notify_room() {
    if (room_waiters_ > 0) room_cv_.notify_all();
  }
  void check_shard(std::uint32_t shard, const char* operation) const;
  void enqueue(std::span<const std::uint32_t> shards, bool urgent);
  void prefetch_worker(std::stop_token stop);
  void prefetch_one(std::uint32_t shard, const std::stop_token& stop);

  const std::uint64_t budget_;
  const Loader loader_;
  const ExpectedBytes expected_bytes_;
  SizeOf size_of_;
  const ShardCacheOptions options_;

  mutable std::mutex mutex_;         // guards everything below up to the counters
  std::condition_variable room_cv_;  // bytes freed or pins released
  std::condition_variable load_cv_;  // a load finished (or failed)
  std::atomic<std::uint64_t> loads_ended_{0};  // loads finished or failed, read without the lock
  std::vector<Entry> entries_;
  PinTable pins_;
  std::uint32_t lru_head_ = kNone, lru_tail_ = kNone;  // oldest first, sorted by stamp
  std::uint64_t used_ = 0;       // resident + reserved + releasing, always <= budget_
  std::uint64_t reserved_ = 0;   // loads in flight
  std::uint64_t releasing_ = 0;  // evicted, destructor still running
  std::uint64_t pinned_ = 0;     // bytes of resident entries with pins > 0
  std::uint64_t resident_count_ = 0;
  std::uint64_t prefetched_unused_count_ = 0;
  std::uint64_t total_pins_ = 0;
  std::uint64_t acquisitions_ = 0;
  std::uint64_t peak_ = 0;
  std::size_t room_waiters_ = 0;

  // Event counters: atomics so that counters() reads them without the lock.
  std::atomic<std::uint64_t> hits_{0}, misses_{0}, page_ins_{0}, load_failures_{0},
      bytes_loaded_{0}, evictions_{0}, pin_waits_{0}, prefetch_hints_{0}, prefetch_loads_{0},
      prefetch_hits_{0}, prefetch_dropped_{0}, prefetch_evicted_unused_{0};

  LatencyReservoir latencies_;  // page-in times
  PrefetchQueue queue_;
  std::vector<std::jthread> workers_;  // last: stopped and joined before the rest goes
};

// ---------------------------------------------------------------------------------------------
// Implementation

template <class ShardType>
ShardCache<ShardType>::ShardCache(std::uint64_t budget_bytes, Loader loader,
                                  std::size_t shard_count, ExpectedBytes expected_bytes,
                                  ShardCacheOptions options, SizeOf size_of)
    : budget_(budget_bytes),
      loader_(std::move(loader)),
      expected_bytes_(std::move(expected_bytes)),
      size_of_(std::move(size_of)),
      options_(options),
      latencies_(options.latency_reservoir),
      queue_(options.prefetch_queue_limit) {
  if (budget_ == 0) throw InputError("shard cache: the memory budget is 0 bytes");
  if (shard_count >= kNone)
    throw InputError("shard cache: " + std::to_string(shard_count) +
                     " shards do not fit 32-bit shard ids");
  if (!loader_) throw InputError("shard cache: no loader given");
  if (!expected_bytes_) throw InputError("shard cache: no expected_bytes function given");
  if (!size_of_) {
    if constexpr (requires(const ShardType& s) { s.memory_bytes(); }) {
      size_of_ = [](const ShardType& s) { return static_cast<std::uint64_t>(s.memory_bytes()); };
    } else {
      throw InputError(
          "shard cache: no size_of function given and the shard type has no memory_bytes()");
    }
  }
  entries_.resize(shard_count);
  workers_.reserve(options_.prefetch_threads);
  for (std::size_t i = 0; i < options_.prefetch_threads; ++i)
    workers_.emplace_back([this](std::stop_token stop) { prefetch_worker(std::move(stop)); });
}

template <class ShardType>
ShardCache<ShardType>::~ShardCache() {
  // Stop all first, then join, so that the threads wind down in parallel.
  for (auto& worker : workers_) worker.request_stop();
  workers_.clear();
}

template <class ShardType>
void ShardCache<ShardType>::check_shard(std::uint32_t shard, const char* operation) const {
  if (shard >= entries_.size())
    throw InputError(std::string("shard cache: ") + operation + " of shard " +
                     std::to_string(shard) + ", but the index has " +
                     std::to_string(entries_.size()) + " shards");
}

template <class ShardType>
auto ShardCache<ShardType>::acquire(std::uint32_t shard) -> Pin {
  check_shard(shard, "acquire");
  const std::uint64_t need = expected_bytes_(shard);
  if (need > budget_)
    throw InputError("shard cache: shard " + std::to_string(shard) + " needs " +
                     std::to_string(need) + " bytes, more than the whole budget of " +
                     std::to_string(budget_) + " bytes");
  const std::thread::id me = std::this_thread::get_id();

  std::unique_lock lock = lock_spinning_first(mutex_, options_.spin_before_sleep);
  ++acquisitions_;
  bool counted = false, waited = false, spinning = false;
  std::chrono::steady_clock::time_point deadline, spin_until_time;
  for (;;) {
    Entry& entry = entries_[shard];
    if (entry.state == State::resident) {
      if (!counted) hits_.fetch_add(1, std::memory_order_relaxed);
      return take_pin(shard);
    }
    if (!counted) {
      misses_.fetch_add(1, std::memory_order_relaxed);
      counted = true;
    }
    if (entry.state == State::loading) {  // someone else loads it: wait for that one load
      // Poll for a while first (the load is likely shorter than a sleep), until some load
      // ends, then look again: another shard's load may have ended.
      const auto now = std::chrono::steady_clock::now();
      if (!spinning) spin_until_time = now + options_.spin_before_sleep, spinning = true;
      if (now < spin_until_time) {
        const std::uint64_t ended = loads_ended_.load(std::memory_order_acquire);
        lock.unlock();
        spin_until([&] { return loads_ended_.load(std::memory_order_acquire) != ended; },
                   std::chrono::duration_cast<std::chrono::microseconds>(spin_until_time - now));
        lock_spinning_first(lock, options_.spin_before_sleep);
        continue;
      }
      load_cv_.wait(lock);
      continue;
    }
    if (used_ + need <= budget_) {
      reserve(entry, need, false);
      break;
    }
    const std::uint64_t own = pinned_bytes_of(me);
    if (own + need > budget_)
      throw InputError("shard cache: shard " + std::to_string(shard) + " needs " +
                       std::to_string(need) + " bytes but this thread already pins " +
                       std::to_string(own) + " of the " + std::to_string(budget_) +
                       "-byte budget: the budget is too small for the query's working set");
    if (evict_one(lock, Eviction::any_unpinned)) continue;

    // Everything resident is pinned by others: wait for them, unless none of them can go on.
    const auto now = std::chrono::steady_clock::now();
    if (!waited) {
      waited = true;
      // Capped so that a "forever" timeout cannot overflow the clock.
      deadline = now + std::min<std::chrono::milliseconds>(options_.pin_wait_timeout,
                                                           std::chrono::hours(24 * 365));
      pin_waits_.fetch_add(1, std::memory_order_relaxed);
    } else if (now >= deadline) {
      throw InputError("shard cache: shard " + std::to_string(shard) + " needs " +
                       std::to_string(need) + " bytes; waited " +
                       std::to_string(options_.pin_wait_timeout.count()) +
                       " ms for other threads to release pins on the " + std::to_string(pinned_) +
                       " pinned bytes of the " + std::to_string(budget_) +
                       "-byte budget: the budget is too small for the queries' working set");
    }
    pins_.set_waiting(me, true);
    if (nobody_can_release()) {
      pins_.set_waiting(me, false);
      throw InputError("shard cache: shard " + std::to_string(shard) + " needs " +
                       std::to_string(need) + " bytes but all " + std::to_string(pinned_) +
                       " pinned bytes of the " + std::to_string(budget_) +
                       "-byte budget are held by threads waiting for room (deadlock): the "
                       "budget is too small for the queries' working set");
    }
    ++room_waiters_;
    room_cv_.wait_until(lock, deadline);
    --room_waiters_;
    pins_.set_waiting(me, false);
  }

  // Load with the reservation held and no lock.
  lock.unlock();
  std::shared_ptr<const ShardType> loaded;
  std::uint64_t size = 0;
  const auto start = std::chrono::steady_clock::now();
  try {
    loaded = loader_(shard);
    if (!loaded)
      throw Error("shard cache: the loader returned no shard for shard " + std::to_string(shard));
    size = size_of_(*loaded);
  } catch (...) {
    loaded.reset();
    lock_spinning_first(lock, options_.spin_before_sleep);
    cancel_reservation(entries_[shard]);
    load_failures_.fetch_add(1, std::memory_order_relaxed);
    throw;
  }
  latencies_.record(std::chrono::steady_clock::now() - start);
  lock_spinning_first(lock, options_.spin_before_sleep);
  install(lock, shard, std::move(loaded), size, Eviction::any_unpinned);
  return take_pin(shard);
}

template <class ShardType>
void ShardCache<ShardType>::reserve(Entry& entry, std::uint64_t bytes, bool by_prefetch) {
  entry.state = State::loading;
  entry.bytes = bytes;
  entry.prefetched_unused = by_prefetch;
  reserved_ += bytes;
  add_used(bytes);
}

template <class ShardType>
void ShardCache<ShardType>::cancel_reservation(Entry& entry) {
  reserved_ -= entry.bytes;
  used_ -= entry.bytes;
  entry.bytes = 0;
  entry.state = State::empty;
  entry.prefetched_unused = false;
  loads_ended_.fetch_add(1, std::memory_order_release);
  load_cv_.notify_all();
  notify_room();
}

template <class ShardType>
void ShardCache<ShardType>::add_used(std::uint64_t bytes) {
  used_ += bytes;
  peak_ = std::max(peak_, used_);
}

// Turns the reservation of a loaded shard into a resident entry (unpinned, in the LRU list).
// A shard larger than announced needs room for the difference, made by evicting without
// waiting (waiting with an uncounted shard in hand would break the budget).
template <class ShardType>
void ShardCache<ShardType>::install(std::unique_lock<std::mutex>& lock, std::uint32_t shard,
                                    std::shared_ptr<const ShardType> loaded, std::uint64_t size,
                                    Eviction eviction) {
  Entry& entry = entries_[shard];
  while (size > entry.bytes) {
    const std::uint64_t extra = size - entry.bytes;
    if (used_ + extra <= budget_) {
      reserved_ += extra;
      entry.bytes += extra;
      add_used(extra);
      break;
    }
    if (evict_one(lock, eviction)) continue;
    const std::uint64_t announced = entry.bytes;
    loaded.reset();
    cancel_reservation(entry);
    load_failures_.fetch_add(1, std::memory_order_relaxed);
    throw InputError("shard cache: shard " + std::to_string(shard) + " holds " +
                     std::to_string(size) + " bytes once loaded, more than the " +
                     std::to_string(announced) +
                     " bytes announced before loading, and no unpinned shard can be evicted "
                     "to make room for the difference within the " +
                     std::to_string(budget_) + "-byte budget");
  }
  if (size < entry.bytes) {  // smaller than announced: give the rest back
    const std::uint64_t spare = entry.bytes - size;
    reserved_ -= spare;
    used_ -= spare;
    entry.bytes = size;
    notify_room();
  }
  reserved_ -= entry.bytes;
  entry.shard = std::move(loaded);
  entry.state = State::resident;
  entry.stamp = acquisitions_;
  ++resident_count_;
  if (entry.prefetched_unused) ++prefetched_unused_count_;
  link_lru_tail(shard);
  ++entry.page_ins;
  page_ins_.fetch_add(1, std::memory_order_relaxed);
  bytes_loaded_.fetch_add(size, std::memory_order_relaxed);
  loads_ended_.fetch_add(1, std::memory_order_release);
  load_cv_.notify_all();
  notify_room();
}

template <class ShardType>
auto ShardCache<ShardType>::take_pin(std::uint32_t shard) -> Pin {
  Entry& entry = entries_[shard];
  const std::thread::id me = std::this_thread::get_id();
  pins_.add(me, shard);  // may allocate: before any state change
  if (entry.pins == 0) {
    unlink_lru(shard);
    pinned_ += entry.bytes;
  }
  ++entry.pins;
  ++total_pins_;
  entry.stamp = acquisitions_;
  if (entry.prefetched_unused) {
    entry.prefetched_unused = false;
    --prefetched_unused_count_;
    prefetch_hits_.fetch_add(1, std::memory_order_relaxed);
  }
  return Pin(this, shard, entry.shard.get(), me);
}

template <class ShardType>
void ShardCache<ShardType>::release(std::uint32_t shard, std::thread::id owner) noexcept {
  const std::unique_lock lock = lock_spinning_first(mutex_, options_.spin_before_sleep);
  Entry& entry = entries_[shard];
  pins_.remove(owner, shard);
  --entry.pins;
  --total_pins_;
  if (entry.pins == 0) {
    pinned_ -= entry.bytes;
    entry.stamp = acquisitions_;
    link_lru_tail(shard);
  }
  notify_room();  // even a shared pin matters: it may leave only waiting threads holding pins
}

// Evicts the least recently used unpinned shard allowed by `eviction`. Its bytes stay counted
// until its destructor has run, outside the lock.
template <class ShardType>
bool ShardCache<ShardType>::evict_one(std::unique_lock<std::mutex>& lock, Eviction eviction) {
  if (lru_head_ == kNone || !evictable(entries_[lru_head_], eviction)) return false;
  const std::uint32_t victim = lru_head_;
  Entry& entry = entries_[victim];
  unlink_lru(victim);
  std::shared_ptr<const ShardType> shard = std::move(entry.shard);
  const std::uint64_t bytes = std::exchange(entry.bytes, 0);
  entry.state = State::empty;
  --resident_count_;
  if (entry.prefetched_unused) {
    entry.prefetched_unused = false;
    --prefetched_unused_count_;
    prefetch_evicted_unused_.fetch_add(1, std::memory_order_relaxed);
  }
  releasing_ += bytes;
  evictions_.fetch_add(1, std::memory_order_relaxed);
  lock.unlock();
  shard.reset();
  lock_spinning_first(lock, options_.spin_before_sleep);
  releasing_ -= bytes;
  used_ -= bytes;
  notify_room();
  return true;
}

template <class ShardType>
bool ShardCache<ShardType>::evictable(const Entry& entry, Eviction eviction) const {
  return eviction == Eviction::any_unpinned ||
         entry.stamp + options_.protected_recent <= acquisitions_;
}

// Whether evicting the old unpinned shards (the LRU list is sorted by stamp, so they are a
// prefix of it) would free `bytes`.
template <class ShardType>
bool ShardCache<ShardType>::old_bytes_cover(std::uint64_t bytes) const {
  std::uint64_t sum = 0;
  for (std::uint32_t at = lru_head_; at != kNone && sum < bytes; at = entries_[at].lru_next) {
    if (!evictable(entries_[at], Eviction::old_unpinned)) break;
    sum += entries_[at].bytes;
  }
  return sum >= bytes;
}

// True when no future event can free room: no load or eviction in flight and every pin is
// held by a thread waiting for room (the caller marks itself waiting first).
template <class ShardType>
bool ShardCache<ShardType>::nobody_can_release() const {
  if (reserved_ > 0 || releasing_ > 0 || lru_head_ != kNone) return false;
  return pins_.pins_held_by_waiters() == total_pins_;
}

// Bytes of the distinct shards the thread pins (a shard pinned twice counts once).
template <class ShardType>
std::uint64_t ShardCache<ShardType>::pinned_bytes_of(std::thread::id thread) const {
  return pins_.pinned_bytes(thread, [this](std::uint32_t shard) { return entries_[shard].bytes; });
}

template <class ShardType>
void ShardCache<ShardType>::link_lru_tail(std::uint32_t shard) {
  Entry& entry = entries_[shard];
  entry.lru_prev = lru_tail_;
  entry.lru_next = kNone;
  if (lru_tail_ != kNone)
    entries_[lru_tail_].lru_next = shard;
  else
    lru_head_ = shard;
  lru_tail_ = shard;
}

template <class ShardType>
void ShardCache<ShardType>::unlink_lru(std::uint32_t shard) {
  Entry& entry = entries_[shard];
  if (entry.lru_prev != kNone)
    entries_[entry.lru_prev].lru_next = entry.lru_next;
  else
    lru_head_ = entry.lru_next;
  if (entry.lru_next != kNone)
    entries_[entry.lru_next].lru_prev = entry.lru_prev;
  else
    lru_tail_ = entry.lru_prev;
  entry.lru_prev = entry.lru_next = kNone;
}

template <class ShardType>
void ShardCache<ShardType>::enqueue(std::span<const std::uint32_t> shards, bool urgent) {
  for (const std::uint32_t shard : shards) check_shard(shard, "prefetch");
  prefetch_hints_.fetch_add(shards.size(), std::memory_order_relaxed);
  if (workers_.empty()) {
    prefetch_dropped_.fetch_add(shards.size(), std::memory_order_relaxed);
    return;
  }
  const std::uint64_t stale = queue_.push(shards, urgent);
  if (stale > 0) prefetch_dropped_.fetch_add(stale, std::memory_order_relaxed);
}

template <class ShardType>
void ShardCache<ShardType>::prefetch_worker(std::stop_token stop) {
  for (;;) {
    const std::optional<std::uint32_t> shard = queue_.pop(stop, options_.spin_before_sleep);
    if (!shard) return;
    try {
      prefetch_one(*shard, stop);
    } catch (...) {  // out of memory or a lock failure: a hint is not worth terminating for
      prefetch_dropped_.fetch_add(1, std::memory_order_relaxed);
    }
    queue_.done();
  }
}

template <class ShardType>
void ShardCache<ShardType>::wait_prefetch_idle() {
  queue_.wait_idle();
}

template <class ShardType>
void ShardCache<ShardType>::prefetch_one(std::uint32_t shard, const std::stop_token& stop) {
  auto drop = [this] { prefetch_dropped_.fetch_add(1, std::memory_order_relaxed); };
  std::uint64_t need = 0;
  try {
    need = expected_bytes_(shard);
  } catch (...) {
    return drop();
  }
  if (need > budget_) return drop();

  std::unique_lock lock = lock_spinning_first(mutex_, options_.spin_before_sleep);
  for (;;) {
    Entry& entry = entries_[shard];
    if (entry.state != State::empty) return;  // already resident or on its way
    if (stop.stop_requested()) return drop();
    if (used_ + need <= budget_) {
      reserve(entry, need, true);
      break;
    }
    if (!old_bytes_cover(used_ + need - budget_)) return drop();
    evict_one(lock, Eviction::old_unpinned);
  }

  lock.unlock();
  std::shared_ptr<const ShardType> loaded;
  std::uint64_t size = 0;
  const auto start = std::chrono::steady_clock::now();
  try {
    loaded = loader_(shard);
    if (loaded) size = size_of_(*loaded);
  } catch (...) {
    loaded.reset();
  }
  if (!loaded) {  // the later acquire retries and reports the error
    lock_spinning_first(lock, options_.spin_before_sleep);
    cancel_reservation(entries_[shard]);
    load_failures_.fetch_add(1, std::memory_order_relaxed);
    return drop();
  }
  latencies_.record(std::chrono::steady_clock::now() - start);
  lock_spinning_first(lock, options_.spin_before_sleep);
  try {
    install(lock, shard, std::move(loaded), size, Eviction::old_unpinned);
  } catch (const Error&) {
    return drop();
  }
  prefetch_loads_.fetch_add(1, std::memory_order_relaxed);
}

template <class ShardType>
bool ShardCache<ShardType>::contains(std::uint32_t shard) const {
  check_shard(shard, "contains");
  const std::unique_lock lock = lock_spinning_first(mutex_, options_.spin_before_sleep);
  return entries_[shard].state == State::resident;
}

template <class ShardType>
ShardCacheCounters ShardCache<ShardType>::counters() const {
  ShardCacheCounters c;
  auto get = [](const std::atomic<std::uint64_t>& a) { return a.load(std::memory_order_relaxed); };
  c.hits = get(hits_);
  c.misses = get(misses_);
  c.page_ins = get(page_ins_);
  c.load_failures = get(load_failures_);
  c.bytes_loaded = get(bytes_loaded_);
  c.evictions = get(evictions_);
  c.pin_waits = get(pin_waits_);
  c.prefetch_hints = get(prefetch_hints_);
  c.prefetch_loads = get(prefetch_loads_);
  c.prefetch_hits = get(prefetch_hits_);
  c.prefetch_dropped = get(prefetch_dropped_);
  c.prefetch_evicted_unused = get(prefetch_evicted_unused_);
  c.budget_bytes = budget_;
  {
    const std::unique_lock lock = lock_spinning_first(mutex_, options_.spin_before_sleep);
    c.resident_bytes = used_ - reserved_ - releasing_;
    c.reserved_bytes = reserved_;
    c.pinned_bytes = pinned_;
    c.resident_shards = resident_count_;
    c.prefetched_unused = prefetched_unused_count_;
    c.peak_resident_bytes = peak_;
  }
  const LatencyReservoir::Summary latency = latencies_.summary();
  c.latency_samples = latency.count;
  c.page_in_max_us = latency.max_us;
  c.page_in_p50_us = latency.p50_us;
  c.page_in_p99_us = latency.p99_us;
  return c;
}

template <class ShardType>
std::vector<std::uint32_t> ShardCache<ShardType>::page_ins_per_shard() const {
  const std::unique_lock lock = lock_spinning_first(mutex_, options_.spin_before_sleep);
  std::vector<std::uint32_t> counts(entries_.size());
  for (std::size_t i = 0; i < entries_.size(); ++i) counts[i] = entries_[i].page_ins;
  return counts;
}

template <class ShardType>
void ShardCache<ShardType>::reset_counters() {
  for (auto* counter : {&hits_, &misses_, &page_ins_, &load_failures_, &bytes_loaded_, &evictions_,
                        &pin_waits_, &prefetch_hints_, &prefetch_loads_, &prefetch_hits_,
                        &prefetch_dropped_, &prefetch_evicted_unused_})
    counter->store(0, std::memory_order_relaxed);
  {
    const std::unique_lock lock = lock_spinning_first(mutex_, options_.spin_before_sleep);
    peak_ = used_;
    for (auto& entry : entries_) entry.page_ins = 0;
  }
  latencies_.reset();
}

}  // namespace tetrapage
