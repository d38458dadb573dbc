#include "tetrapage/formats/mesh/EdgeParity.h"

#include <utility>

#include "tetrapage/formats/mesh/PositionBits.h"

namespace tetrapage {
namespace {

// A 128-bit hash of an unordered pair of positions from their hashes: the pair is ordered
// first, then each lane chains the two vertices' words of that lane.
std::array<std::uint64_t, 2> edge_hash(const EdgeParity::VertexHash& p, const EdgeParity::VertexHash& q) {
  const auto& [a, b] = q < p ? std::pair(q, p) : std::pair(p, q);
  return {mix_bits(mix_bits(a[0] ^ 0x243f6a8885a308d3ULL) ^ b[0]),
          mix_bits(mix_bits(a[1] + 0x13198a2e03707344ULL) + b[1])};
}

}  // namespace

EdgeParity::VertexHash EdgeParity::hash_vertex(const Vec3& p) {
  VertexHash lane{0xa4093822299f31d0ULL, 0x082efa98ec4e6c89ULL};
  for (int a = 0; a < 3; ++a) {
    const std::uint64_t w = coordinate_bits(p[a]);  // -0 is 0
    lane[0] = mix_bits(lane[0] ^ w);
    lane[1] = mix_bits(lane[1] + (w ^ 0x452821e638d01377ULL));
  }
  return lane;
}

void EdgeParity::add_hashed_triangle(const VertexHash& a, const VertexHash& b, const VertexHash& c) {
  for (const auto& h : {edge_hash(a, b), edge_hash(b, c), edge_hash(c, a)}) {
    state_[0] ^= h[0];
    state_[1] ^= h[1];
  }
}

void EdgeParity::add_triangle(const Vec3& a, const Vec3& b, const Vec3& c) {
  add_hashed_triangle(hash_vertex(a), hash_vertex(b), hash_vertex(c));
}

}  // namespace tetrapage
