#pragma once
// Internal: the byte-level encoding of one stored chunk of /shards/data, exactly as HDF5's
// pipeline "shuffle (8-byte elements), deflate, fletcher32" produces and expects it, so that
// the index reader can check and inflate chunks it read itself (outside HDF5's global lock)
// and the writer can hand HDF5 chunks it compressed itself (H5Dwrite_chunk).
//
// A stored chunk is:   filtered bytes | Fletcher-32 of the filtered bytes (4 bytes, little endian)
// where "filtered bytes" are a zlib stream (RFC 1950) of the shuffled chunk (byte k of every
// 8-byte element, for k = 0..7 in turn), or the chunk itself when the filter mask says shuffle
// and deflate were skipped (incompressible data).

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace tetrapage::detail {

/// Bits of an HDF5 chunk filter mask: bit i set = filter i of the pipeline was skipped.
inline constexpr std::uint32_t kShuffleSkipped = 1u << 0;
inline constexpr std::uint32_t kDeflateSkipped = 1u << 1;
inline constexpr std::uint32_t kChecksumSkipped = 1u << 2;
/// The shuffle's element size: the dataset's type, 8-byte little-endian words.
inline constexpr std::size_t kShuffleElementBytes = 8;
inline constexpr std::size_t kChecksumBytes = 4;

/// HDF5's Fletcher-32: 16-bit big-endian words (an odd last byte is the high byte of a final
/// word), both sums folded modulo 65535 every 360 words, result (sum2 << 16) | sum1.
std::uint32_t fletcher32(std::span<const std::byte> data);

/// One chunk as it goes to disk, and the filter mask to store with it.
struct EncodedChunk {
  std::vector<std::byte> bytes;
  std::uint32_t filter_mask = 0;
};

/// Shuffles and deflates `chunk` at `level` (0-9) and appends the checksum; keeps the chunk as
/// it is (filter_mask = kShuffleSkipped | kDeflateSkipped) when deflate would not make it
/// smaller. `out` is reused to avoid an allocation per chunk.
/// @throw InputError for an invalid level or a chunk that is not whole 8-byte elements.
void encode_chunk(std::span<const std::byte> chunk, int level, EncodedChunk& out);

/// Checks the checksum of `stored` and decodes it into `out`, which must receive exactly
/// out.size() bytes (the chunk size). Returns "" on success, else what is wrong (the caller
/// names the file, shard and chunk).
std::string decode_chunk(std::span<const std::byte> stored, std::uint32_t filter_mask,
                         std::span<std::byte> out);

/// HDF5's shuffle filter of whole 8-byte elements: byte k of element i goes to k * n + i (n
/// elements), and its inverse. `in` and `out` have the same size, a multiple of 8.
void shuffle_bytes(std::span<const std::byte> in, std::span<std::byte> out);
void unshuffle_bytes(std::span<const std::byte> in, std::span<std::byte> out);

}  // namespace tetrapage::detail
