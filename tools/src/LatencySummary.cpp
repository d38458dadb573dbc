#include "tetrapage/tools/LatencySummary.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

namespace tetrapage {

LatencySummary LatencySummary::of(std::span<const double> seconds) {
  LatencySummary summary;
  if (seconds.empty()) return summary;
  std::vector<double> sorted(seconds.begin(), seconds.end());
  std::sort(sorted.begin(), sorted.end());
  const auto rank = [&](double p) {
    const auto index = static_cast<std::size_t>(std::ceil(p * double(sorted.size()))) - 1;
    return 1e6 * sorted[std::min(index, sorted.size() - 1)];
  };
  summary.p50_us = rank(0.50);
  summary.p95_us = rank(0.95);
  summary.p99_us = rank(0.99);
  summary.max_us = 1e6 * sorted.back();
  summary.mean_us = 1e6 * std::accumulate(sorted.begin(), sorted.end(), 0.0) / double(sorted.size());
  return summary;
}

nlohmann::json LatencySummary::to_json() const {
  return {{"p50", p50_us}, {"p95", p95_us}, {"p99", p99_us}, {"max", max_us}, {"mean", mean_us}};
}

}  // namespace tetrapage
