#include "tetrapage/runtime/paging/LatencyReservoir.h"

#include <algorithm>
#include <cmath>

namespace tetrapage {

LatencyReservoir::LatencyReservoir(std::size_t capacity) : capacity_(capacity) {
  sample_ns_.reserve(capacity);
}

void LatencyReservoir::record(std::chrono::nanoseconds duration) {
  const auto ns = static_cast<std::uint64_t>(std::max<std::int64_t>(0, duration.count()));
  std::lock_guard lock(mutex_);
  ++count_;
  max_ns_ = std::max(max_ns_, ns);
  if (capacity_ == 0) return;
  if (sample_ns_.size() < capacity_) {
    sample_ns_.push_back(ns);
    return;
  }
  // Reservoir sampling (algorithm R) with a splitmix64 generator.
  std::uint64_t z = (random_ += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  if (const std::uint64_t slot = z % count_; slot < sample_ns_.size()) sample_ns_[slot] = ns;
}

LatencyReservoir::Summary LatencyReservoir::summary() const {
  Summary summary;
  std::vector<std::uint64_t> samples;
  {
    std::lock_guard lock(mutex_);
    samples = sample_ns_;
    summary.count = count_;
    summary.max_us = double(max_ns_) / 1e3;
  }
  if (!samples.empty()) {
    std::sort(samples.begin(), samples.end());
    auto rank = [&](double p) {  // nearest rank
      const auto index = static_cast<std::size_t>(std::ceil(p * double(samples.size())));
      return double(samples[std::clamp<std::size_t>(index, 1, samples.size()) - 1]) / 1e3;
    };
    summary.p50_us = rank(0.50);
    summary.p99_us = rank(0.99);
  }
  return summary;
}

void LatencyReservoir::reset() {
  std::lock_guard lock(mutex_);
  sample_ns_.clear();
  count_ = 0;
  max_ns_ = 0;
}

}  // namespace tetrapage
