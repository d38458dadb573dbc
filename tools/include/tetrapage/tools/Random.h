#pragma once
/// @file Random.h
/// A seeded random source whose output is the same on every platform and library version
/// (std:: distributions are implementation-defined, so the generators never use them):
/// the same seed gives the same bytes.

#include <cmath>
#include <cstdint>
#include <numbers>
#include <numeric>
#include <utility>
#include <vector>

namespace tetrapage {

/// xoshiro256** seeded through SplitMix64, with explicit, portable distributions.
class Random {
 public:
  explicit Random(std::uint64_t seed) {
    std::uint64_t x = seed;
    for (auto& s : state_) s = splitmix64(x);
  }

  std::uint64_t next_u64() {
    const std::uint64_t result = rotl(state_[1] * 5, 7) * 9;
    const std::uint64_t t = state_[1] << 17;
    state_[2] ^= state_[0];
    state_[3] ^= state_[1];
    state_[1] ^= state_[2];
    state_[0] ^= state_[3];
    state_[2] ^= t;
    state_[3] = rotl(state_[3], 45);
    return result;
  }

  /// Uniform in [0, 1) with 53 random bits.
  double uniform() { return double(next_u64() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Uniform integer in [0, n); n > 0 (n below 2^53, which every generator respects).
  std::uint64_t below(std::uint64_t n) {
    const auto k = static_cast<std::uint64_t>(uniform() * double(n));
    return k < n ? k : n - 1;
  }
  /// Standard normal (Box-Muller, the cosine branch only, so one call = two uniforms).
  double normal() {
    const double u1 = 1.0 - uniform();  // (0, 1]
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
  }

 private:
  static std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  static std::uint64_t splitmix64(std::uint64_t& x) {
    std::uint64_t z = (x += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  std::uint64_t state_[4];
};

/// `count` distinct indices among [0, total), in draw order (partial Fisher-Yates: one uniform
/// draw per pick, no rejection). Precondition: count <= total.
inline std::vector<std::uint32_t> random_subset(std::size_t total, std::size_t count, Random& random) {
  std::vector<std::uint32_t> indices(total);
  std::iota(indices.begin(), indices.end(), 0u);
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t j = i + random.below(total - i);
    std::swap(indices[i], indices[j]);
  }
  indices.resize(count);
  return indices;
}

}  // namespace tetrapage
