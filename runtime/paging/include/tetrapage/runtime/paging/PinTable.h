#pragma once
/// @file PinTable.h
/// The shard cache's pins per thread, for its deadlock checks: which shards each thread pins,
/// and whether it waits for room. Not thread-safe: the cache's lock guards it. Records are
/// reused, never erased, so the table stops growing once every thread has been seen.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <thread>
#include <vector>

namespace tetrapage {

class PinTable {
 public:
  /// May allocate: call it before any other state changes.
  void add(std::thread::id thread, std::uint32_t shard) {
    record_for(thread).pinned.push_back(shard);
  }
  void remove(std::thread::id thread, std::uint32_t shard) noexcept;
  void set_waiting(std::thread::id thread, bool waiting) { record_for(thread).waiting = waiting; }
  /// The bytes of the distinct shards `thread` pins (a shard pinned twice counts once), each
  /// shard's by `bytes_of(shard)`.
  template <class BytesOf>
  std::uint64_t pinned_bytes(std::thread::id thread, BytesOf bytes_of) const;
  /// The pins held by threads waiting for room.
  std::uint64_t pins_held_by_waiters() const;

 private:
  struct ThreadRecord {
    std::thread::id thread;
    std::vector<std::uint32_t> pinned;  ///< shard ids, one per pin
    bool waiting = false;               ///< waiting in acquire for room
  };
  const ThreadRecord* find(std::thread::id thread) const;
  ThreadRecord& record_for(std::thread::id thread);

  std::vector<ThreadRecord> threads_;
};

template <class BytesOf>
std::uint64_t PinTable::pinned_bytes(std::thread::id thread, BytesOf bytes_of) const {
  const ThreadRecord* record = find(thread);
  if (record == nullptr) return 0;
  std::uint64_t sum = 0;
  const auto& pinned = record->pinned;
  for (std::size_t i = 0; i < pinned.size(); ++i)
    if (std::find(pinned.begin(), pinned.begin() + std::ptrdiff_t(i), pinned[i]) ==
        pinned.begin() + std::ptrdiff_t(i))
      sum += bytes_of(pinned[i]);
  return sum;
}

}  // namespace tetrapage
