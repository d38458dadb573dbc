#pragma once
// Internal: the byte-level encoding of one stored chunk of /shards/data, exactly as HDF5's
// pipeline "deflate, then fletcher32" produces and expects it, so that the index reader can
// check and inflate chunks it read itself (outside HDF5's global lock) and the writer can
// hand HDF5 chunks it compressed itself (H5Dwrite_chunk).
//
// A stored chunk is:   filtered bytes | Fletcher-32 of the filtered bytes (4 bytes, little endian)
// where "filtered bytes" are a zlib stream (RFC 1950) of the chunk, or the chunk itself when
// bit 0 of the chunk's filter mask says deflate was skipped (incompressible data).

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace tetrapage::detail {

/// Bits of an HDF5 chunk filter mask: bit i set = filter i of the pipeline was skipped.
inline constexpr std::uint32_t kDeflateSkipped = 1u << 0;
inline constexpr std::uint32_t kChecksumSkipped = 1u << 1;
inline constexpr std::size_t kChecksumBytes = 4;

/// HDF5's Fletcher-32: 16-bit big-endian words (an odd last byte is the high byte of a final
/// word), both sums folded modulo 65535 every 360 words, result (sum2 << 16) | sum1.
std::uint32_t fletcher32(std::span<const std::byte> data);

/// One chunk as it goes to disk, and the filter mask to store with it.
struct EncodedChunk {
  std::vector<std::byte> bytes;
  std::uint32_t filter_mask = 0;
};

/// Deflates `chunk` at `level` (0-9) and appends the checksum; keeps the chunk uncompressed
/// (filter_mask = kDeflateSkipped) when deflate would not make it smaller.
/// `out` is reused to avoid an allocation per chunk.
/// @throw InputError if zlib refuses (it only does for an invalid level).
void encode_chunk(std::span<const std::byte> chunk, int level, EncodedChunk& out);

/// Checks the checksum of `stored` and decodes it into `out`, which must receive exactly
/// out.size() bytes (the chunk size). Returns "" on success, else what is wrong (the caller
/// names the file, shard and chunk).
std::string decode_chunk(std::span<const std::byte> stored, std::uint32_t filter_mask,
                         std::span<std::byte> out);

}  // namespace tetrapage::detail
