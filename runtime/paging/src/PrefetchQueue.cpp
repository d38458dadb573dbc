#include "tetrapage/runtime/paging/PrefetchQueue.h"

#include "tetrapage/formats/base/SpinThenBlock.h"

namespace tetrapage {

std::uint64_t PrefetchQueue::push(std::span<const std::uint32_t> shards, bool urgent) {
  std::uint64_t dropped = 0;
  bool wake = false;
  {
    std::lock_guard lock(mutex_);
    if (urgent)
      queue_.insert(queue_.begin(), shards.rbegin(), shards.rend());
    else
      queue_.insert(queue_.end(), shards.begin(), shards.end());
    while (queue_.size() > limit_) {
      if (urgent)
        queue_.pop_back();
      else
        queue_.pop_front();
      ++dropped;
    }
    queued_count_.store(queue_.size(), std::memory_order_release);
    wake = sleeping_ > 0;  // a polling worker sees the hints without a wake-up
  }
  if (wake) queued_cv_.notify_all();
  return dropped;
}

std::optional<std::uint32_t> PrefetchQueue::pop(const std::stop_token& stop,
                                                std::chrono::microseconds spin) {
  spin_until(
      [&] { return queued_count_.load(std::memory_order_acquire) > 0 || stop.stop_requested(); },
      spin);
  std::unique_lock lock(mutex_);
  // wait() returns true with hints still queued when stopped: those are dropped.
  ++sleeping_;
  const bool woken = queued_cv_.wait(lock, stop, [this] { return !queue_.empty(); });
  --sleeping_;
  if (!woken || stop.stop_requested()) return std::nullopt;
  const std::uint32_t shard = queue_.front();
  queue_.pop_front();
  queued_count_.store(queue_.size(), std::memory_order_release);
  ++in_progress_;
  return shard;
}

void PrefetchQueue::done() {
  std::lock_guard lock(mutex_);
  if (--in_progress_ == 0 && queue_.empty()) idle_cv_.notify_all();
}

void PrefetchQueue::wait_idle() {
  std::unique_lock lock(mutex_);
  idle_cv_.wait(lock, [this] { return queue_.empty() && in_progress_ == 0; });
}

}  // namespace tetrapage
