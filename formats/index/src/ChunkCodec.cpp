#include "ChunkCodec.h"

#include <lz4.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <array>
#include <new>
#include <cstdio>
#include <cstring>
#include <memory>

#include "tetrapage/formats/base/Error.h"

namespace tetrapage::detail {

namespace {

std::uint32_t fold(std::uint32_t sum) { return (sum & 0xffffu) + (sum >> 16); }

void store_le32(std::byte* out, std::uint32_t value) {
  for (int i = 0; i < 4; ++i) out[i] = std::byte((value >> (8 * i)) & 0xffu);
}

std::uint32_t load_le32(const std::byte* in) {
  std::uint32_t value = 0;
  for (int i = 0; i < 4; ++i) value |= std::uint32_t(in[i]) << (8 * i);
  return value;
}

}  // namespace

std::uint32_t fletcher32(std::span<const std::byte> data) {
  // HDF5's sums, word by word: sum1 += w; sum2 += sum1, both uint32_t (wrapping), folded every
  // 360 words. Over a block of n words that is sum2 += n * sum1 + sum of (n - j) * w_j and
  // sum1 += sum of w_j, modulo 2^32 as the wrapping sums are; so a block's two sums can be
  // taken 8 words at a time (it was a tenth of a page-in word by word).
  std::uint32_t sum1 = 0;
  std::uint32_t sum2 = 0;
  const std::byte* word = data.data();
  std::size_t words_left = data.size() / 2;
  while (words_left > 0) {
    const std::size_t block = std::min<std::size_t>(words_left, 360);
    words_left -= block;
    std::uint32_t words_sum = 0, weighted_sum = 0;
    std::size_t j = 0;
#if defined(__SSE2__)
    // Each big-endian word as its high and low bytes (0..255) in 16-bit lanes, so that
    // _mm_madd_epi16's signed products are exact; weights block - j are at most 360.
    const __m128i low_byte = _mm_set1_epi16(0x00ff), ones = _mm_set1_epi16(1), eight = _mm_set1_epi16(8);
    __m128i weights = _mm_sub_epi16(_mm_set1_epi16(static_cast<short>(block)), _mm_setr_epi16(0, 1, 2, 3, 4, 5, 6, 7));
    __m128i high_words = _mm_setzero_si128(), low_words = _mm_setzero_si128();
    __m128i high_weighted = _mm_setzero_si128(), low_weighted = _mm_setzero_si128();
    for (; j + 8 <= block; j += 8) {
      const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(word + 2 * j));
      const __m128i high = _mm_and_si128(v, low_byte);  // byte 0 of each word
      const __m128i low = _mm_srli_epi16(v, 8);         // byte 1
      high_words = _mm_add_epi32(high_words, _mm_madd_epi16(high, ones));
      low_words = _mm_add_epi32(low_words, _mm_madd_epi16(low, ones));
      high_weighted = _mm_add_epi32(high_weighted, _mm_madd_epi16(high, weights));
      low_weighted = _mm_add_epi32(low_weighted, _mm_madd_epi16(low, weights));
      weights = _mm_sub_epi16(weights, eight);
    }
    const auto lanes_sum = [](__m128i x) {
      alignas(16) std::uint32_t lane[4];
      _mm_store_si128(reinterpret_cast<__m128i*>(lane), x);
      return lane[0] + lane[1] + lane[2] + lane[3];
    };
    words_sum = (lanes_sum(high_words) << 8) + lanes_sum(low_words);
    weighted_sum = (lanes_sum(high_weighted) << 8) + lanes_sum(low_weighted);
#endif
    for (; j < block; ++j) {
      const std::uint32_t w = (std::uint32_t(word[2 * j]) << 8) | std::uint32_t(word[2 * j + 1]);
      words_sum += w;
      weighted_sum += static_cast<std::uint32_t>(block - j) * w;
    }
    word += 2 * block;
    sum2 += static_cast<std::uint32_t>(block) * sum1 + weighted_sum;
    sum1 += words_sum;
    sum1 = fold(sum1);
    sum2 = fold(sum2);
  }
  if (data.size() % 2 != 0) {
    sum1 += std::uint32_t(*word) << 8;
    sum2 += sum1;
    sum1 = fold(sum1);
    sum2 = fold(sum2);
  }
  sum1 = fold(sum1);
  sum2 = fold(sum2);
  return (sum2 << 16) | sum1;
}

namespace {

// 8 elements of 8 bytes at once: an 8 x 8 byte transpose in registers (row j = element j,
// column k = its byte k), so that each plane gets one 8-byte store. Its own inverse.
void transpose8x8(const std::byte* in, std::size_t in_stride, std::byte* out, std::size_t out_stride) {
#if defined(__SSE2__)
  // Interleaving bytes, then pairs, then quadruples of rows: three rounds of unpacks (the
  // scalar version below was a twelfth of a page-in).
  __m128i r[8];
  for (int j = 0; j < 8; ++j)
    r[j] = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(in + std::size_t(j) * in_stride));
  const __m128i t0 = _mm_unpacklo_epi8(r[0], r[1]), t1 = _mm_unpacklo_epi8(r[2], r[3]);
  const __m128i t2 = _mm_unpacklo_epi8(r[4], r[5]), t3 = _mm_unpacklo_epi8(r[6], r[7]);
  const __m128i u0 = _mm_unpacklo_epi16(t0, t1), u1 = _mm_unpackhi_epi16(t0, t1);
  const __m128i u2 = _mm_unpacklo_epi16(t2, t3), u3 = _mm_unpackhi_epi16(t2, t3);
  const __m128i columns[4] = {_mm_unpacklo_epi32(u0, u2), _mm_unpackhi_epi32(u0, u2),
                              _mm_unpacklo_epi32(u1, u3), _mm_unpackhi_epi32(u1, u3)};
  for (int k = 0; k < 4; ++k) {
    _mm_storel_epi64(reinterpret_cast<__m128i*>(out + std::size_t(2 * k) * out_stride), columns[k]);
    _mm_storel_epi64(reinterpret_cast<__m128i*>(out + std::size_t(2 * k + 1) * out_stride),
                     _mm_srli_si128(columns[k], 8));
  }
#else
  std::uint64_t row[8];
  for (int j = 0; j < 8; ++j) std::memcpy(&row[j], in + std::size_t(j) * in_stride, 8);
  for (int k = 0; k < 8; ++k) {
    std::uint64_t column = 0;
    for (int j = 0; j < 8; ++j) column |= ((row[j] >> (8 * k)) & 0xffu) << (8 * j);
    std::memcpy(out + std::size_t(k) * out_stride, &column, 8);
  }
#endif
}

}  // namespace

void shuffle_bytes(std::span<const std::byte> in, std::span<std::byte> out) {
  const std::size_t n = in.size() / kShuffleElementBytes;
  std::size_t i = 0;
  for (; i + 8 <= n; i += 8) transpose8x8(in.data() + 8 * i, 8, out.data() + i, n);
  for (; i < n; ++i)
    for (std::size_t k = 0; k < 8; ++k) out[k * n + i] = in[8 * i + k];
}

void unshuffle_bytes(std::span<const std::byte> in, std::span<std::byte> out) {
  const std::size_t n = in.size() / kShuffleElementBytes;
  std::size_t i = 0;
  for (; i + 8 <= n; i += 8) transpose8x8(in.data() + i, n, out.data() + 8 * i, 8);
  for (; i < n; ++i)
    for (std::size_t k = 0; k < 8; ++k) out[8 * i + k] = in[k * n + i];
}

namespace {

void store_be32(std::byte* out, std::uint32_t value) {
  for (int i = 0; i < 4; ++i) out[i] = std::byte((value >> (8 * (3 - i))) & 0xffu);
}

void store_be64(std::byte* out, std::uint64_t value) {
  for (int i = 0; i < 8; ++i) out[i] = std::byte((value >> (8 * (7 - i))) & 0xffu);
}

std::uint64_t load_be(const std::byte* in, int bytes) {
  std::uint64_t value = 0;
  for (int i = 0; i < bytes; ++i) value = (value << 8) | std::uint64_t(in[i]);
  return value;
}

constexpr std::size_t kFrameHeaderBytes = 12;  // decoded size, block size
constexpr std::size_t kBlockHeaderBytes = 4;   // the block's stored size

void check_encodable(std::span<const std::byte> chunk) {
  if (chunk.empty() || chunk.size() > (std::size_t{1} << 30) || chunk.size() % kShuffleElementBytes != 0)
    throw InputError("cannot encode a chunk of " + std::to_string(chunk.size()) +
                     " bytes: not whole 8-byte elements between 8 bytes and 1 GiB");
}

/// Appends the Fletcher-32 of the first `filtered_bytes` of `out` and trims what follows.
void seal(EncodedChunk& out, std::size_t filtered_bytes) {
  const std::uint32_t checksum = fletcher32({out.bytes.data(), filtered_bytes});
  out.bytes.resize(filtered_bytes + kChecksumBytes);
  store_le32(out.bytes.data() + filtered_bytes, checksum);
}

}  // namespace

void encode_chunk(std::span<const std::byte> chunk, EncodedChunk& out) {
  check_encodable(chunk);
  // Byte planes: the high bytes of coordinates and indices repeat and the noisy low ones stay
  // together (LZ4 stores 0.738 of the 10M scene's 16 KiB chunks shuffled, 0.938 unshuffled).
  thread_local std::vector<std::byte> shuffled;
  shuffled.resize(chunk.size());
  shuffle_bytes(chunk, shuffled);
  // One block for the whole chunk. LZ4 compresses 8x and decompresses 3.6x as fast as deflate
  // at level 1 (format 2), for 4 % more stored bytes (tetrapage_bench_chunks, docs/FORMAT.md).
  const int size = static_cast<int>(chunk.size());
  const int bound = LZ4_compressBound(size);
  out.bytes.resize(std::max<std::size_t>(kFrameHeaderBytes + kBlockHeaderBytes + std::size_t(bound), chunk.size()) +
                   kChecksumBytes);
  std::byte* frame = out.bytes.data();
  const int compressed = LZ4_compress_default(reinterpret_cast<const char*>(shuffled.data()),
                                              reinterpret_cast<char*>(frame + kFrameHeaderBytes + kBlockHeaderBytes),
                                              size, bound);
  std::size_t filtered_bytes = kFrameHeaderBytes + kBlockHeaderBytes + std::size_t(compressed);
  out.filter_mask = 0;
  if (compressed <= 0 || filtered_bytes >= chunk.size()) {
    // Both filters are optional in the pipeline: HDF5 readers honour the mask bits.
    std::memcpy(frame, chunk.data(), chunk.size());
    filtered_bytes = chunk.size();
    out.filter_mask = kShuffleSkipped | kCompressionSkipped;
  } else {
    store_be64(frame, chunk.size());
    store_be32(frame + 8, static_cast<std::uint32_t>(chunk.size()));
    store_be32(frame + kFrameHeaderBytes, static_cast<std::uint32_t>(compressed));
  }
  seal(out, filtered_bytes);
}

void encode_chunk_uncompressed(std::span<const std::byte> chunk, std::size_t payload_bytes, EncodedChunk& out) {
  check_encodable(chunk);
  if (payload_bytes == 0 || payload_bytes > chunk.size())
    throw InputError("cannot encode a chunk of " + std::to_string(chunk.size()) + " bytes with " +
                     std::to_string(payload_bytes) + " payload bytes");
  for (std::size_t i = payload_bytes; i < chunk.size(); ++i)
    if (chunk[i] != std::byte{0})
      throw InputError("cannot store a chunk's padding uncompressed: byte " + std::to_string(i) + " is not zero");
  if (payload_bytes == chunk.size()) {
    out.bytes.resize(chunk.size() + kChecksumBytes);
    std::memcpy(out.bytes.data(), chunk.data(), chunk.size());
    out.filter_mask = kShuffleSkipped | kCompressionSkipped;
    seal(out, chunk.size());
    return;
  }
  // Blocks of at least a sixteenth of the chunk (1 KiB of the index's 16 KiB), so that the
  // padding takes at most 15 blocks of a few bytes; the first holds the payload (and, for a
  // shorter one, some zeros) as it is.
  const std::size_t block = std::max(payload_bytes, (chunk.size() + 15) / 16);
  const std::size_t blocks = (chunk.size() + block - 1) / block;
  out.bytes.resize(kFrameHeaderBytes + blocks * (kBlockHeaderBytes + std::size_t(LZ4_compressBound(int(block)))) +
                   kChecksumBytes);
  std::byte* frame = out.bytes.data();
  store_be64(frame, chunk.size());
  store_be32(frame + 8, static_cast<std::uint32_t>(block));
  std::size_t at = kFrameHeaderBytes;
  for (std::size_t done = 0; done < chunk.size(); done += block) {
    const std::size_t bytes = std::min(block, chunk.size() - done);
    int stored = 0;
    if (done > 0) {
      stored = LZ4_compress_default(reinterpret_cast<const char*>(chunk.data() + done),
                                    reinterpret_cast<char*>(frame + at + kBlockHeaderBytes), int(bytes),
                                    LZ4_compressBound(int(bytes)));
    }
    // A block whose stored size equals its decoded size is read as it is: the payload's, and
    // any LZ4 could not shrink.
    if (stored <= 0 || std::size_t(stored) >= bytes) {
      std::memcpy(frame + at + kBlockHeaderBytes, chunk.data() + done, bytes);
      stored = int(bytes);
    }
    store_be32(frame + at, static_cast<std::uint32_t>(stored));
    at += kBlockHeaderBytes + std::size_t(stored);
  }
  out.filter_mask = kShuffleSkipped;
  seal(out, at);
}

namespace {

/// Decodes the first out.size() bytes of an LZ4 filter frame of `decoded_size` bytes into
/// `out`; "" or what is wrong. Blocks past out.size() are walked, not decompressed.
std::string decode_lz4_frame(std::span<const std::byte> frame, std::span<std::byte> out, std::uint64_t expected_size) {
  if (frame.size() < kFrameHeaderBytes)
    return "LZ4 frame of " + std::to_string(frame.size()) + " bytes is too short for its header";
  const std::uint64_t decoded_size = load_be(frame.data(), 8);
  std::uint64_t block_size = load_be(frame.data() + 8, 4);
  if (decoded_size != expected_size)
    return "LZ4 frame decodes to " + std::to_string(decoded_size) + " bytes, expected " + std::to_string(expected_size);
  if (block_size == 0) return "LZ4 frame has blocks of 0 bytes";
  block_size = std::min(block_size, decoded_size);
  const std::uint64_t wanted = out.size();
  std::size_t at = kFrameHeaderBytes;
  for (std::uint64_t done = 0; done < decoded_size;) {
    const std::uint64_t expected = std::min(block_size, decoded_size - done);
    if (frame.size() - at < kBlockHeaderBytes) return "LZ4 frame ends inside a block header";
    const std::uint64_t stored = load_be(frame.data() + at, 4);
    at += kBlockHeaderBytes;
    if (stored > frame.size() - at) return "LZ4 block of " + std::to_string(stored) + " bytes runs past the frame";
    if (done < wanted) {
      const std::uint64_t take = std::min(expected, wanted - done);  // of this block, into out
      if (stored == expected) {
        std::memcpy(out.data() + done, frame.data() + at, take);  // stored as it is
      } else {
        const int decoded =
            take == expected
                ? LZ4_decompress_safe(reinterpret_cast<const char*>(frame.data() + at),
                                      reinterpret_cast<char*>(out.data() + done), static_cast<int>(stored),
                                      static_cast<int>(expected))
                : LZ4_decompress_safe_partial(reinterpret_cast<const char*>(frame.data() + at),
                                              reinterpret_cast<char*>(out.data() + done), static_cast<int>(stored),
                                              static_cast<int>(take), static_cast<int>(take));
        if (decoded < 0 || std::uint64_t(decoded) != take)
          return "cannot decompress an LZ4 block (corrupt or incomplete data)";
      }
    }
    at += stored;
    done += expected;
  }
  if (at != frame.size()) return std::to_string(frame.size() - at) + " bytes follow the LZ4 frame's last block";
  return {};
}

}  // namespace

std::string decode_chunk(std::span<const std::byte> stored, std::uint32_t filter_mask,
                         std::span<std::byte> out, std::size_t chunk_bytes) {
  if (chunk_bytes == 0) chunk_bytes = out.size();
  if ((filter_mask & kChecksumSkipped) != 0)
    return "stored without its Fletcher-32 checksum (filter mask " +
           std::to_string(filter_mask) + ")";
  if (stored.size() < kChecksumBytes)
    return "stored chunk of " + std::to_string(stored.size()) +
           " bytes is too short to hold a checksum";
  const auto filtered = stored.first(stored.size() - kChecksumBytes);
  const std::uint32_t expected = load_le32(stored.data() + filtered.size());
  const std::uint32_t actual = fletcher32(filtered);
  if (expected != actual) {
    char text[64];
    std::snprintf(text, sizeof text, "Fletcher-32 mismatch (stored %08x, computed %08x)",
                  expected, actual);
    return text;
  }
  if (chunk_bytes % kShuffleElementBytes != 0)
    return "chunk of " + std::to_string(chunk_bytes) + " bytes is not whole 8-byte elements";
  if (out.size() > chunk_bytes)
    return "asked for " + std::to_string(out.size()) + " bytes of a " + std::to_string(chunk_bytes) + "-byte chunk";
  const bool shuffled = (filter_mask & kShuffleSkipped) == 0;
  // A shuffled chunk is decoded whole (its byte planes span it), then unshuffled.
  thread_local std::vector<std::byte> planes, whole;
  std::span<std::byte> target = out;  // where the filtered bytes go before unshuffling
  if (shuffled) {
    planes.resize(chunk_bytes);
    target = planes;
  }
  if ((filter_mask & kCompressionSkipped) != 0) {
    if (filtered.size() != chunk_bytes)
      return "uncompressed chunk holds " + std::to_string(filtered.size()) + " bytes, expected " +
             std::to_string(chunk_bytes);
    if (!target.empty()) std::memcpy(target.data(), filtered.data(), target.size());
  } else if (std::string problem = decode_lz4_frame(filtered, target, chunk_bytes); !problem.empty()) {
    return problem;
  }
  if (shuffled) {
    if (out.size() == chunk_bytes) {
      unshuffle_bytes(target, out);
    } else {
      whole.resize(chunk_bytes);
      unshuffle_bytes(target, whole);
      if (!out.empty()) std::memcpy(out.data(), whole.data(), out.size());
    }
  }
  return {};
}

}  // namespace tetrapage::detail
