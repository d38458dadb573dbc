#pragma once
/// @file PrefetchQueue.h
/// The shard cache's queue of prefetch hints: bounded (the oldest hints dropped first, or for
/// urgent hints queued at the front, the newest), popped by worker threads that poll before
/// they sleep, and waited on until it runs dry. Thread-safe.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <span>
#include <stop_token>

namespace tetrapage {

class PrefetchQueue {
 public:
  /// At most `limit` hints wait.
  explicit PrefetchQueue(std::size_t limit) : limit_(limit) {}

  /// Queues the hints, `urgent` ones at the front in their order; returns how many queued hints
  /// the limit dropped.
  std::uint64_t push(std::span<const std::uint32_t> shards, bool urgent);
  /// The next hint, polled for up to `spin` and then waited for; none once `stop` is requested
  /// (the hints still queued are then dropped). Each hint popped must be marked done().
  std::optional<std::uint32_t> pop(const std::stop_token& stop, std::chrono::microseconds spin);
  void done();
  /// Returns when no hint is queued and none is in progress.
  void wait_idle();

 private:
  const std::size_t limit_;
  std::mutex mutex_;
  std::condition_variable_any queued_cv_;  // hints queued (or stop requested)
  std::condition_variable idle_cv_;        // the queue ran dry with no hint in progress
  std::deque<std::uint32_t> queue_;
  std::size_t in_progress_ = 0;
  std::size_t sleeping_ = 0;                  // workers waiting on queued_cv_
  std::atomic<std::size_t> queued_count_{0};  // queue_.size(), read without the lock
};

}  // namespace tetrapage
