#pragma once
// Internal: the byte-level encoding of one stored chunk of /shards/data, exactly as HDF5's
// pipeline "shuffle (8-byte elements), LZ4 (registered filter 32004), fletcher32" produces and
// expects it, so that the index reader can check and decompress chunks it read itself (outside
// HDF5's global lock) and the writer can hand HDF5 chunks it compressed itself (H5Dwrite_chunk).
//
// A stored chunk is:   filtered bytes | Fletcher-32 of the filtered bytes (4 bytes, little endian)
// where "filtered bytes" are the LZ4 filter's frame of the shuffled chunk (byte k of every
// 8-byte element, for k = 0..7 in turn), or the chunk itself when the filter mask says shuffle
// and LZ4 were skipped (incompressible data). The frame, as the filter plugin that HDF5
// distributes (Debian: hdf5-filter-plugin) writes and reads it, all numbers big endian:
//   uint64 decoded size | uint32 block size | per block: uint32 stored size, then the block's
//   LZ4 block-format bytes, or the block itself when its stored size equals its decoded size.

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace tetrapage::detail {

/// Bits of an HDF5 chunk filter mask: bit i set = filter i of the pipeline was skipped.
inline constexpr std::uint32_t kShuffleSkipped = 1u << 0;
inline constexpr std::uint32_t kCompressionSkipped = 1u << 1;
inline constexpr std::uint32_t kChecksumSkipped = 1u << 2;
/// The shuffle's element size: the dataset's type, 8-byte little-endian words.
inline constexpr std::size_t kShuffleElementBytes = 8;
inline constexpr std::size_t kChecksumBytes = 4;
/// HDF5's registered id of the LZ4 filter (the HDF Group's list of registered filters).
inline constexpr int kLz4FilterId = 32004;

/// HDF5's Fletcher-32: 16-bit big-endian words (an odd last byte is the high byte of a final
/// word), both sums folded modulo 65535 every 360 words, result (sum2 << 16) | sum1.
std::uint32_t fletcher32(std::span<const std::byte> data);

/// One chunk as it goes to disk, and the filter mask to store with it.
struct EncodedChunk {
  std::vector<std::byte> bytes;
  std::uint32_t filter_mask = 0;
};

/// Shuffles and compresses `chunk` (one LZ4 block) and appends the checksum; keeps the chunk as
/// it is (filter_mask = kShuffleSkipped | kCompressionSkipped) when LZ4 would not make it
/// smaller. `out` is reused to avoid an allocation per chunk.
/// @throw InputError for an empty chunk, one over 1 GiB or one that is not whole 8-byte elements.
void encode_chunk(std::span<const std::byte> chunk, EncodedChunk& out);

/// Stores `chunk` uncompressed: the first `payload_bytes` as they are (nothing to decompress
/// or unshuffle on reading), the rest, which must be zero (a shard's padding), as at most 15 LZ4
/// blocks of a few bytes each. A full chunk is stored as it is (shuffle and LZ4 skipped in the mask);
/// a padded one as an LZ4 filter frame (shuffle skipped) whose first block is stored as it is.
/// @throw InputError as encode_chunk, or when payload_bytes is 0 or past the chunk, or a byte
///        past payload_bytes is not zero.
void encode_chunk_uncompressed(std::span<const std::byte> chunk, std::size_t payload_bytes, EncodedChunk& out);

/// Checks the checksum of `stored` and decodes the first out.size() bytes of its chunk of
/// `chunk_bytes` bytes (0: out.size(), the whole chunk) into `out`: a shard's last chunk is
/// decoded straight into the payload. Blocks of an unshuffled frame past out.size() are
/// checked by the checksum only, not decompressed. Returns "" on success, else what is wrong
/// (the caller names the file, shard and chunk).
std::string decode_chunk(std::span<const std::byte> stored, std::uint32_t filter_mask,
                         std::span<std::byte> out, std::size_t chunk_bytes = 0);

/// HDF5's shuffle filter of whole 8-byte elements: byte k of element i goes to k * n + i (n
/// elements), and its inverse. `in` and `out` have the same size, a multiple of 8.
void shuffle_bytes(std::span<const std::byte> in, std::span<std::byte> out);
void unshuffle_bytes(std::span<const std::byte> in, std::span<std::byte> out);

}  // namespace tetrapage::detail
