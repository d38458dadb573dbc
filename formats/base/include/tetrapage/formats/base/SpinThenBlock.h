#pragma once
/// @file SpinThenBlock.h
/// Waiting that polls before it sleeps. On a virtual machine a thread's sleep and its wake-up
/// cost about 25 us each way (a condition variable's round trip between two threads took
/// 50-60 us on a 2-core VM, polling 0.8 us: BM_HandOff, docs/BENCHMARKS.md): longer than the critical
/// sections and page-ins that the index reader's and the shard cache's threads wait for.

#include <chrono>
#include <mutex>

namespace tetrapage {

/// Tells the processor that the caller is polling (frees the core's resources for a sibling).
inline void spin_pause() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#elif defined(__aarch64__)
  asm volatile("yield");
#endif
}

/// Polls `done` until it holds or `limit` has passed; returns its last value.
template <class Done>
bool spin_until(Done&& done, std::chrono::microseconds limit) {
  if (done()) return true;
  if (limit.count() <= 0) return false;
  const auto until = std::chrono::steady_clock::now() + limit;
  do {
    for (int i = 0; i < 16; ++i) {
      spin_pause();
      if (done()) return true;
    }
  } while (std::chrono::steady_clock::now() < until);
  return done();
}

/// Locks `lock`'s mutex (which it must not own), polling it for up to `limit` first.
inline void lock_spinning_first(std::unique_lock<std::mutex>& lock,
                                std::chrono::microseconds limit) {
  if (!spin_until([&] { return lock.try_lock(); }, limit)) lock.lock();
}

/// A lock on `mutex`, taken by polling it for up to `limit` first.
inline std::unique_lock<std::mutex> lock_spinning_first(std::mutex& mutex,
                                                        std::chrono::microseconds limit) {
  std::unique_lock lock(mutex, std::defer_lock);
  lock_spinning_first(lock, limit);
  return lock;
}

}  // namespace tetrapage
