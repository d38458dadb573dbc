#pragma once
/// @file LatencyReservoir.h
/// A fixed-size uniform sample of durations (the shard cache's page-in times): every duration
/// counted and its maximum kept, a reservoir of at most `capacity` of them for the percentiles.
/// Thread-safe.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <vector>

namespace tetrapage {

class LatencyReservoir {
 public:
  struct Summary {
    std::uint64_t count = 0;  ///< durations recorded (not only those sampled)
    double max_us = 0;
    double p50_us = 0;  ///< nearest-rank percentiles of the sample; 0 when it is empty
    double p99_us = 0;
  };

  /// capacity 0: count and maximum only.
  explicit LatencyReservoir(std::size_t capacity);

  void record(std::chrono::nanoseconds duration);
  Summary summary() const;
  void reset();

 private:
  const std::size_t capacity_;
  mutable std::mutex mutex_;
  std::vector<std::uint64_t> sample_ns_;
  std::uint64_t count_ = 0;
  std::uint64_t max_ns_ = 0;
  std::uint64_t random_ = 0x9E3779B97F4A7C15ull;  // fixed seed: reproducible sampling
};

}  // namespace tetrapage
