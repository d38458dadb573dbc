#pragma once
/// @file ShardArena.h
/// Memory for decoded shards whose pages are faulted in ahead of use, by a background thread.
///
/// A paged flight fills an empty budget: each decoded shard would otherwise land on pages the
/// process never touched, and the flying thread would take the page faults (about five a
/// page-in, a fifth of its cost on the 10M scene: docs/BENCHMARKS.md, "The runtime's paging
/// options, and the process's memory"). The
/// arena reserves one range of address space, keeps the next few MiB past its frontier
/// populated from a background thread (madvise MADV_POPULATE_WRITE), and recycles freed blocks
/// by size class (eight classes per doubling, so a block wastes at most an eighth), as a
/// database's buffer pool keeps its frames. Once the range's resident pages and the blocks
/// served upstream hold more than the limit (free blocks of one class cannot serve another),
/// freed blocks give their pages back to the system, so that the arena holds about the limit
/// whatever the mix of sizes.
///
/// Requests outside the classes (over 4 MiB, alignment over 64), and any when
/// the range is used up, go to the upstream resource. Thread-safe.

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <memory_resource>
#include <mutex>
#include <stop_token>
#include <thread>
#include <vector>

namespace tetrapage {

class ShardArena final : public std::pmr::memory_resource {
 public:
  /// Reserves `capacity_bytes` of address space (rounded up to 2 MiB; nothing is resident
  /// until populated or used) and starts the populating thread, which keeps
  /// `populate_ahead_bytes` past the frontier faulted in, but never past the first
  /// `populate_limit_bytes` of the range (a memory budget: what lies past it is faulted in only
  /// when a block there is used). A capacity of 0, or one the system will not map, leaves every
  /// request to upstream.
  explicit ShardArena(std::size_t capacity_bytes,
                      std::size_t populate_ahead_bytes = std::size_t(8) << 20,
                      std::pmr::memory_resource* upstream = std::pmr::new_delete_resource(),
                      std::size_t populate_limit_bytes = SIZE_MAX);
  /// Precondition: every block from the arena has been deallocated.
  ~ShardArena() override;
  ShardArena(const ShardArena&) = delete;
  ShardArena& operator=(const ShardArena&) = delete;

  /// The bytes a request of `bytes` holds: its size class, or `bytes` for one that goes
  /// upstream.
  static std::size_t block_bytes(std::size_t bytes);

  std::size_t capacity() const { return capacity_; }
  /// Bytes of the range handed out at least once (freed blocks are kept for reuse).
  std::size_t frontier_bytes() const { return frontier_.load(std::memory_order_relaxed); }
  /// Bytes of the range that may be resident: handed out or populated, less the pages freed
  /// blocks gave back.
  std::size_t resident_bytes() const;
  /// Bytes of the range faulted in by the populating thread.
  std::size_t populated_bytes() const { return populated_.load(std::memory_order_acquire); }
  /// False when the kernel cannot populate ahead (before Linux 5.14): pages then fault on
  /// first use, as malloc's do.
  bool populates() const { return !populate_failed_.load(std::memory_order_relaxed); }
  /// Whether `p` lies in the arena's range.
  bool owns(const void* p) const;
  /// Blocks served from the range and from upstream (for tests and benchmarks).
  std::uint64_t arena_blocks() const { return arena_blocks_.load(std::memory_order_relaxed); }
  std::uint64_t upstream_blocks() const { return upstream_blocks_.load(std::memory_order_relaxed); }

 private:
  void* do_allocate(std::size_t bytes, std::size_t alignment) override;
  void do_deallocate(void* p, std::size_t bytes, std::size_t alignment) override;
  bool do_is_equal(const std::pmr::memory_resource& other) const noexcept override {
    return this == &other;
  }
  // Over the limit, free blocks of other classes give their pages back before `incoming`
  // more bytes become resident. Called with mutex_ held.
  void give_back_free_blocks(std::size_t incoming);
  void populate(std::stop_token stop);
  std::size_t populate_target() const;

  std::pmr::memory_resource* const upstream_;
  std::byte* base_ = nullptr;
  std::size_t capacity_ = 0;
  const std::size_t ahead_;
  const std::size_t populate_limit_;

  std::mutex mutex_;               // guards the free lists and the frontier's advance
  std::vector<void*> free_heads_;  // per size class: a freed block, which links to the next
  std::vector<std::vector<void*>> given_back_blocks_;  // per class: blocks whose pages went back
  std::atomic<std::size_t> given_back_{0};  // bytes of those pages
  std::atomic<std::size_t> frontier_{0};
  std::atomic<std::uint64_t> arena_blocks_{0}, upstream_blocks_{0};
  std::atomic<std::size_t> upstream_bytes_{0};  // live blocks served upstream

  std::mutex populate_mutex_;
  std::condition_variable_any populate_cv_;
  std::atomic<std::size_t> populated_{0};
  std::atomic<bool> populate_failed_{false};
  std::jthread populator_;  // last: stopped and joined before the rest goes
};

}  // namespace tetrapage
