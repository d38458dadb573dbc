#pragma once
/// @file LatencySummary.h
/// Percentiles of per-step latencies, as every flight report prints them.

#include <nlohmann/json.hpp>
#include <span>

namespace tetrapage {

struct LatencySummary {
  double p50_us = 0, p95_us = 0, p99_us = 0, max_us = 0, mean_us = 0;
  /// Nearest-rank percentiles of `seconds` (copied and sorted).
  static LatencySummary of(std::span<const double> seconds);
  nlohmann::json to_json() const;
};

}  // namespace tetrapage
