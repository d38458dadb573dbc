#pragma once
// Edits of an index's HDF5 metadata that keep its checksums right, so that a test of a crafted
// file reaches the reader's own checks rather than HDF5's checksum test. HDF5 checksums each
// block of metadata of the formats tetrapage writes (object headers 2, extensible arrays,
// fractal heaps) with Bob Jenkins' lookup3 hash of the block's bytes, stored after them.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <string>

namespace tetrapage::test {

/// lookup3's hashlittle() over bytes, with an initial value of 0 (as HDF5 uses it), written
/// from the algorithm's published description.
inline std::uint32_t lookup3_checksum(const unsigned char* bytes, std::size_t length) {
  std::uint32_t a = 0xdeadbeefu + static_cast<std::uint32_t>(length);
  std::uint32_t b = a, c = a;
  const auto mix = [&] {
    a -= c, a ^= std::rotl(c, 4), c += b;
    b -= a, b ^= std::rotl(a, 6), a += c;
    c -= b, c ^= std::rotl(b, 8), b += a;
    a -= c, a ^= std::rotl(c, 16), c += b;
    b -= a, b ^= std::rotl(a, 19), a += c;
    c -= b, c ^= std::rotl(b, 4), b += a;
  };
  const auto word = [&](std::size_t at, std::size_t count) {
    std::uint32_t value = 0;
    for (std::size_t i = 0; i < count; ++i) value |= std::uint32_t{bytes[at + i]} << (8 * i);
    return value;
  };
  std::size_t at = 0;
  for (; length - at > 12; at += 12) {
    a += word(at, 4), b += word(at + 4, 4), c += word(at + 8, 4);
    mix();
  }
  const std::size_t tail = length - at;
  if (tail == 0) return c;
  a += word(at, std::min<std::size_t>(tail, 4));
  if (tail > 4) b += word(at + 4, std::min<std::size_t>(tail - 4, 4));
  if (tail > 8) c += word(at + 8, tail - 8);
  c ^= b, c -= std::rotl(b, 14);
  a ^= c, a -= std::rotl(c, 11);
  b ^= a, b -= std::rotl(a, 25);
  c ^= b, c -= std::rotl(b, 16);
  a ^= c, a -= std::rotl(c, 4);
  b ^= a, b -= std::rotl(a, 14);
  c ^= b, c -= std::rotl(b, 24);
  return c;
}

/// Whether `bytes`[start, end) is a block whose checksum, with the 4 bytes at `at` zeroed, is
/// the little-endian word stored at `at`.
inline bool checksum_at(const std::string& bytes, std::size_t start, std::size_t end, std::size_t at) {
  std::string block = bytes.substr(start, end - start);
  std::uint32_t stored = 0;
  std::memcpy(&stored, block.data() + (at - start), 4);
  std::memset(block.data() + (at - start), 0, 4);
  return stored == lookup3_checksum(reinterpret_cast<const unsigned char*>(block.data()), block.size());
}

inline void store_checksum(std::string& bytes, std::size_t start, std::size_t end, std::size_t at) {
  std::memset(bytes.data() + at, 0, 4);
  const std::uint32_t checksum =
      lookup3_checksum(reinterpret_cast<const unsigned char*>(bytes.data()) + start, end - start);
  std::memcpy(bytes.data() + at, &checksum, 4);
}

/// After `patched` (a copy of `original`) was edited at [at, at + length), recomputes the
/// checksum of the metadata block that holds the edit. The block is found in `original`: the
/// nearest signature of a checksummed block before `at` whose checksum matches its bytes,
/// stored after them, or for a fractal heap's direct block (a power of two in size) after its
/// header fields. Fails the test if no such block holds the edit.
inline void reseal_metadata(const std::string& original, std::string& patched, std::size_t at,
                            std::size_t length) {
  static constexpr std::array<const char*, 11> trailing{"OHDR", "OCHK", "EAHD", "EAIB", "EASB", "EADB",
                                                        "FAHD", "FADB", "FRHP", "FHIB", "BTHD"};
  constexpr std::size_t kLongestBlock = 65536;
  const auto* bytes = reinterpret_cast<const unsigned char*>(original.data());
  for (std::size_t start = at + 1; start-- > 0 && at - start < kLongestBlock;) {
    if (original.compare(start, 4, "FHDB") == 0) {
      // Signature, version, the heap's address (8 bytes), the block's offset (1 to 8 bytes).
      for (std::size_t size = 64; size <= kLongestBlock && start + size <= original.size(); size *= 2)
        for (std::size_t field = start + 14; field <= start + 21 && field + 4 <= start + size; ++field)
          if (field + 4 <= at && at + length <= start + size && checksum_at(original, start, start + size, field)) {
            store_checksum(patched, start, start + size, field);
            return;
          }
      continue;
    }
    if (std::none_of(trailing.begin(), trailing.end(),
                     [&](const char* s) { return original.compare(start, 4, s) == 0; }))
      continue;
    for (std::size_t end = at + length; end + 4 <= original.size() && end - start <= kLongestBlock; ++end) {
      std::uint32_t stored = 0;
      std::memcpy(&stored, bytes + end, 4);
      if (stored != lookup3_checksum(bytes + start, end - start)) continue;
      const std::uint32_t resealed =
          lookup3_checksum(reinterpret_cast<const unsigned char*>(patched.data()) + start, end - start);
      std::memcpy(patched.data() + end, &resealed, 4);
      return;
    }
  }
  FAIL() << "no checksummed HDF5 metadata block holds bytes [" << at << ", " << at + length << ")";
}

}  // namespace tetrapage::test
