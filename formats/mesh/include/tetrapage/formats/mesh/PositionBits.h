#pragma once
/// @file PositionBits.h
/// How vertex positions are compared and hashed wherever positions are matched exactly (the
/// components of a surface, its edge parity, the components of a file read in chunks): by the
/// bits of their coordinates, -0.0 read as 0.0, mixed by splitmix64's finaliser.

#include <bit>
#include <cstdint>

namespace tetrapage {

/// The bits of a coordinate, -0.0 read as 0.0 (the same position).
inline std::uint64_t coordinate_bits(double x) {
  return std::bit_cast<std::uint64_t>(x == 0.0 ? 0.0 : x);
}

/// splitmix64's finaliser: every input bit moves every output bit.
inline std::uint64_t mix_bits(std::uint64_t x) {
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ULL;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

}  // namespace tetrapage
