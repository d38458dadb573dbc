#include "tetrapage/runtime/paging/ShardArena.h"

#include <sys/mman.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cstdint>
#include <functional>
#include <new>
#include <utility>

#ifndef MADV_POPULATE_WRITE
#define MADV_POPULATE_WRITE 23  // Linux 5.14's value, for headers older than the kernel
#endif

namespace tetrapage {

namespace {

// Requests up to this size take blocks in steps of 64 bytes (a shard's many tiny arrays: kept
// in the range too, so that the range holds everything a shard is counted for).
constexpr std::size_t kLargestSmallBlock = 512;
constexpr std::size_t kSmallClasses = kLargestSmallBlock / 64;
constexpr std::size_t kLargestBlock = std::size_t(4) << 20;
constexpr std::size_t kBlockAlignment = 64;
constexpr std::size_t kClassesPerDoubling = 8;
constexpr std::size_t kRangeGranule = std::size_t(2) << 20;
constexpr std::size_t kPageBytes = 4096;  // a divisor of every page size Linux uses
// One madvise call populates this much: it holds the address space's lock for reading, which
// delays the process's own mmap and brk calls until it returns.
constexpr std::size_t kPopulateStep = std::size_t(256) << 10;

// The class of a request of `bytes` in (0, kLargestBlock], and its block size: up to 512
// bytes, multiples of 64; above, with 2^(p-1) < bytes <= 2^p, blocks of 9/8 .. 16/8 of 2^(p-1)
// in steps of 2^(p-4) (a multiple of 64 from p = 10 on).
std::size_t size_class(std::size_t bytes, std::size_t& block) {
  if (bytes <= kLargestSmallBlock) {
    block = std::max<std::size_t>(64, (bytes + 63) / 64 * 64);
    return block / 64 - 1;
  }
  const unsigned p = unsigned(std::bit_width(bytes - 1));
  const std::size_t step = std::size_t(1) << (p - 4);
  const std::size_t steps = (bytes + step - 1) / step;  // 9 .. 16
  block = steps * step;
  return kSmallClasses + (p - 10) * kClassesPerDoubling + (steps - 9);
}

// The block size of class `c` (size_class's inverse).
std::size_t class_block_bytes(std::size_t c) {
  if (c < kSmallClasses) return (c + 1) * 64;
  const std::size_t k = c - kSmallClasses;
  const std::size_t p = 10 + k / kClassesPerDoubling, steps = 9 + k % kClassesPerDoubling;
  return steps << (p - 4);
}

// Free blocks this size and more give their pages back to keep the range within its limit as
// other classes grow (smaller ones hold too few whole pages to be worth the call).
constexpr std::size_t kGivesBackWhenFree = std::size_t(16) << 10;

// The whole pages of a free block that may go back to the system: all but the partial pages at
// either end (its link in a free list is then kept outside it).
std::pair<std::byte*, std::size_t> inner_pages(void* p, std::size_t block) {
  const auto at = reinterpret_cast<std::uintptr_t>(p);
  const std::uintptr_t from = (at + kPageBytes - 1) / kPageBytes * kPageBytes;
  const std::uintptr_t to = (at + block) / kPageBytes * kPageBytes;
  if (to <= from) return {nullptr, 0};
  return {reinterpret_cast<std::byte*>(from), std::size_t(to - from)};
}

bool in_classes(std::size_t bytes, std::size_t alignment) {
  return bytes > 0 && bytes <= kLargestBlock && alignment <= kBlockAlignment;
}

constexpr std::size_t kClassCount = kSmallClasses +
    (std::bit_width(kLargestBlock - 1) - std::bit_width(kLargestSmallBlock) + 1) * kClassesPerDoubling;

}  // namespace

ShardArena::ShardArena(std::size_t capacity_bytes, std::size_t populate_ahead_bytes,
                       std::pmr::memory_resource* upstream, std::size_t populate_limit_bytes)
    : upstream_(upstream),
      ahead_(populate_ahead_bytes),
      populate_limit_(populate_limit_bytes),
      free_heads_(kClassCount, nullptr),
      given_back_blocks_(kClassCount) {
#if defined(__SANITIZE_ADDRESS__)
  // AddressSanitizer sees blocks recycled here as live: leave every shard to malloc so that
  // it still catches a shard used after its eviction.
  capacity_bytes = 0;
#endif
  if (capacity_bytes > 0) {
    const std::size_t rounded =
        (capacity_bytes + kRangeGranule - 1) / kRangeGranule * kRangeGranule;
    void* range = ::mmap(nullptr, rounded, PROT_READ | PROT_WRITE,
                         MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
    if (range != MAP_FAILED) {
      base_ = static_cast<std::byte*>(range);
      capacity_ = rounded;
    }
  }
  if (capacity_ > 0 && ahead_ > 0)
    populator_ = std::jthread([this](std::stop_token stop) { populate(std::move(stop)); });
}

ShardArena::~ShardArena() {
  if (populator_.joinable()) {
    populator_.request_stop();
    populator_.join();
  }
  if (base_ != nullptr) ::munmap(base_, capacity_);
}

std::size_t ShardArena::block_bytes(std::size_t bytes) {
  if (!in_classes(bytes, 1)) return bytes;
  std::size_t block = 0;
  size_class(bytes, block);
  return block;
}

bool ShardArena::owns(const void* p) const {
  const auto* b = static_cast<const std::byte*>(p);
  return base_ != nullptr && std::less_equal<const std::byte*>()(base_, b) &&
         std::less<const std::byte*>()(b, base_ + capacity_);
}

void* ShardArena::do_allocate(std::size_t bytes, std::size_t alignment) {
  if (capacity_ > 0 && in_classes(bytes, alignment)) {
    std::size_t block = 0;
    const std::size_t c = size_class(bytes, block);
    bool wake = false;
    void* p = nullptr;
    {
      const std::lock_guard lock(mutex_);
      if (void* head = free_heads_[c]) {
        free_heads_[c] = *static_cast<void**>(head);
        p = head;
      } else if (std::vector<void*>& given_back = given_back_blocks_[c]; !given_back.empty()) {
        // Its pages fault in again as they are written: only once the range is over its limit.
        give_back_free_blocks(block);
        p = given_back.back();
        given_back.pop_back();
        given_back_.fetch_sub(inner_pages(p, block).second, std::memory_order_relaxed);
      } else if (const std::size_t at = frontier_.load(std::memory_order_relaxed);
                 block <= capacity_ - at) {
        give_back_free_blocks(block);
        p = base_ + at;
        frontier_.store(at + block, std::memory_order_relaxed);
        // Wake the populating thread when the frontier has eaten into its lead.
        wake = populated_.load(std::memory_order_relaxed) <
               std::min(capacity_, at + block + ahead_ / 2);
      }
    }
    if (wake) {
      // Under its mutex, so that the wake cannot fall between its check and its wait.
      { const std::lock_guard lock(populate_mutex_); }
      populate_cv_.notify_one();
    }
    if (p != nullptr) {
      arena_blocks_.fetch_add(1, std::memory_order_relaxed);
      return p;
    }
  }
  upstream_blocks_.fetch_add(1, std::memory_order_relaxed);
  upstream_bytes_.fetch_add(bytes, std::memory_order_relaxed);
  return upstream_->allocate(bytes, alignment);
}

void ShardArena::do_deallocate(void* p, std::size_t bytes, std::size_t alignment) {
  if (!owns(p)) {
    upstream_bytes_.fetch_sub(bytes, std::memory_order_relaxed);
    return upstream_->deallocate(p, bytes, alignment);
  }
  std::size_t block = 0;
  const std::size_t c = size_class(bytes, block);
  // Over the limit, a freed block's pages go back to the system, before the block is listed
  // (no other thread can take it yet): the range and the blocks upstream then hold about the
  // limit however the size classes mix, where free blocks of one class would otherwise keep
  // their pages.
  std::size_t returned = 0;
  if (resident_bytes() + upstream_bytes_.load(std::memory_order_relaxed) > populate_limit_) {
    const auto [pages, length] = inner_pages(p, block);
    if (length > 0 && ::madvise(pages, length, MADV_DONTNEED) == 0) returned = length;
  }
  const std::lock_guard lock(mutex_);
  if (returned > 0) {
    // Listed outside the block: writing a link into it would fault a page back in.
    try {
      given_back_blocks_[c].push_back(p);
      given_back_.fetch_add(returned, std::memory_order_relaxed);
      return;
    } catch (const std::bad_alloc&) {
      // Listed as a free block instead (its first page faults in again for the link).
    }
  }
  *static_cast<void**>(p) = free_heads_[c];
  free_heads_[c] = p;
}

void ShardArena::give_back_free_blocks(std::size_t incoming) {
  if (populate_limit_ == SIZE_MAX) return;
  const auto over = [&] {
    return resident_bytes() + upstream_bytes_.load(std::memory_order_relaxed) + incoming >
           populate_limit_;
  };
  // Largest first: the fewest calls for the most pages.
  for (std::size_t c = free_heads_.size(); c-- > 0 && over();) {
    const std::size_t block = class_block_bytes(c);
    if (block < kGivesBackWhenFree) break;
    while (free_heads_[c] != nullptr && over()) {
      void* p = free_heads_[c];
      const auto [pages, length] = inner_pages(p, block);
      given_back_blocks_[c].push_back(p);        // may throw: before anything changes
      free_heads_[c] = *static_cast<void**>(p);  // read before its page goes
      if (::madvise(pages, length, MADV_DONTNEED) != 0) {
        given_back_blocks_[c].pop_back();
        free_heads_[c] = p;
        return;
      }
      given_back_.fetch_add(length, std::memory_order_relaxed);
    }
  }
}

std::size_t ShardArena::resident_bytes() const {
  const std::size_t touched = std::max(frontier_.load(std::memory_order_relaxed),
                                       populated_.load(std::memory_order_relaxed));
  return touched - std::min(touched, given_back_.load(std::memory_order_relaxed));
}

std::size_t ShardArena::populate_target() const {
  return std::min({capacity_, populate_limit_, frontier_.load(std::memory_order_relaxed) + ahead_});
}

void ShardArena::populate(std::stop_token stop) {
  std::unique_lock lock(populate_mutex_);
  while (!stop.stop_requested()) {
    if (!populate_cv_.wait(lock, stop, [this] {
          return populated_.load(std::memory_order_relaxed) < populate_target();
        }))
      return;
    // Whole pages: madvise wants a page-aligned start, and the frontier moves by 64 bytes.
    const std::size_t from = populated_.load(std::memory_order_relaxed);
    const std::size_t to =
        std::min(capacity_, (std::min(populate_target(), from + kPopulateStep) + kPageBytes - 1) /
                                kPageBytes * kPageBytes);
    lock.unlock();
    // Pages already in use are left as they are: populating only faults in missing ones.
    const int result = ::madvise(base_ + from, to - from, MADV_POPULATE_WRITE);
    lock.lock();
    if (result != 0 && errno != EINTR && errno != EAGAIN) {
      populate_failed_.store(true, std::memory_order_relaxed);  // EINVAL before Linux 5.14
      return;
    }
    if (result == 0) populated_.store(to, std::memory_order_release);
  }
}

}  // namespace tetrapage
