#pragma once
/// @file TriangleIdSet.h
/// The model-wide triangle ids a step has met: a triangle that crosses regions is stored in
/// each of their shards, and a step that reads several of them tests it once. Open addressing
/// with generation stamps, so that clearing between steps costs nothing.
#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

namespace tetrapage {

class TriangleIdSet {
 public:
  /// Empties the set (O(1) but once in 2^32 calls).
  void clear() {
    size_ = 0;
    if (++generation_ == 0) {
      std::fill(stamps_.begin(), stamps_.end(), 0u);
      generation_ = 1;
    }
  }

  /// Adds `id`; false if it was there already.
  bool insert(std::uint64_t id) {
    if (2 * (size_ + 1) > stamps_.size()) grow();
    const std::size_t mask = stamps_.size() - 1;
    for (std::size_t slot = hash(id) & mask;; slot = (slot + 1) & mask) {
      if (stamps_[slot] != generation_) {
        stamps_[slot] = generation_;
        ids_[slot] = id;
        ++size_;
        return true;
      }
      if (ids_[slot] == id) return false;
    }
  }

  std::size_t size() const { return size_; }

 private:
  static std::size_t hash(std::uint64_t id) {
    // Ids of neighbouring triangles are close: mix the bits (splitmix64's finaliser).
    id = (id ^ (id >> 30)) * 0xbf58476d1ce4e5b9ull;
    id = (id ^ (id >> 27)) * 0x94d049bb133111ebull;
    return std::size_t(id ^ (id >> 31));
  }

  void grow() {
    const std::size_t slots = stamps_.size() < 256 ? 512 : 2 * stamps_.size();
    const std::vector<std::uint64_t> previous_ids =
        std::exchange(ids_, std::vector<std::uint64_t>(slots));
    const std::vector<std::uint32_t> previous_stamps =
        std::exchange(stamps_, std::vector<std::uint32_t>(slots, 0u));
    const std::uint32_t previous_generation = std::exchange(generation_, 1u);
    size_ = 0;
    for (std::size_t slot = 0; slot < previous_stamps.size(); ++slot)
      if (previous_stamps[slot] == previous_generation) insert(previous_ids[slot]);
  }

  std::vector<std::uint64_t> ids_;
  std::vector<std::uint32_t> stamps_;
  std::uint32_t generation_ = 1;
  std::size_t size_ = 0;
};

}  // namespace tetrapage
