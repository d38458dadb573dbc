#include "tetrapage/formats/EdgeParity.h"

#include <algorithm>
#include <bit>

namespace tetrapage {
namespace {

std::uint64_t mix(std::uint64_t x) {
  // splitmix64's finaliser: every input bit moves every output bit.
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ULL;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebULL;
  x ^= x >> 31;
  return x;
}

std::array<std::uint64_t, 3> bits_of(const Vec3& p) {
  std::array<std::uint64_t, 3> bits{};
  for (int a = 0; a < 3; ++a) bits[a] = std::bit_cast<std::uint64_t>(p[a] == 0.0 ? 0.0 : p[a]);
  return bits;
}

// A 128-bit hash of an unordered pair of positions: the pair is ordered first, then its six
// words are chained through two differently seeded lanes.
std::array<std::uint64_t, 2> edge_hash(const Vec3& p, const Vec3& q) {
  auto a = bits_of(p), b = bits_of(q);
  if (b < a) std::swap(a, b);
  std::array<std::uint64_t, 2> lane{0x243f6a8885a308d3ULL, 0x13198a2e03707344ULL};
  for (const auto* words : {&a, &b})
    for (const std::uint64_t w : *words) {
      lane[0] = mix(lane[0] ^ w);
      lane[1] = mix(lane[1] + (w ^ 0xa4093822299f31d0ULL));
    }
  return lane;
}

}  // namespace

void EdgeParity::add_triangle(const Vec3& a, const Vec3& b, const Vec3& c) {
  for (const auto& h : {edge_hash(a, b), edge_hash(b, c), edge_hash(c, a)}) {
    state_[0] ^= h[0];
    state_[1] ^= h[1];
  }
}

}  // namespace tetrapage
