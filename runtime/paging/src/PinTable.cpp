#include "tetrapage/runtime/paging/PinTable.h"

namespace tetrapage {

void PinTable::remove(std::thread::id thread, std::uint32_t shard) noexcept {
  for (auto& record : threads_) {
    if (record.thread != thread) continue;
    auto& pinned = record.pinned;
    if (auto it = std::find(pinned.begin(), pinned.end(), shard); it != pinned.end()) {
      *it = pinned.back();
      pinned.pop_back();
    }
    return;
  }
}

std::uint64_t PinTable::pins_held_by_waiters() const {
  std::uint64_t held = 0;
  for (const auto& record : threads_)
    if (record.waiting) held += record.pinned.size();
  return held;
}

auto PinTable::find(std::thread::id thread) const -> const ThreadRecord* {
  for (const auto& record : threads_)
    if (record.thread == thread) return &record;
  return nullptr;
}

auto PinTable::record_for(std::thread::id thread) -> ThreadRecord& {
  for (auto& record : threads_)
    if (record.thread == thread) return record;
  for (auto& record : threads_)
    if (record.pinned.empty() && !record.waiting) {
      record.thread = thread;
      return record;
    }
  threads_.push_back(ThreadRecord{thread, {}, false});
  return threads_.back();
}

}  // namespace tetrapage
