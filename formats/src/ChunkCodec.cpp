#include "ChunkCodec.h"

#include <libdeflate.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <array>
#include <new>
#include <cstdio>
#include <cstring>
#include <memory>

#include "tetrapage/formats/Error.h"

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
  // uint32_t on purpose: the sums wrap exactly as HDF5's do, so even pathological inputs
  // give HDF5's value.
  std::uint32_t sum1 = 0;
  std::uint32_t sum2 = 0;
  const std::byte* word = data.data();
  std::size_t words_left = data.size() / 2;
  while (words_left > 0) {
    const std::size_t block = std::min<std::size_t>(words_left, 360);
    words_left -= block;
    for (std::size_t i = 0; i < block; ++i, word += 2) {
      sum1 += (std::uint32_t(word[0]) << 8) | std::uint32_t(word[1]);
      sum2 += sum1;
    }
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

void encode_chunk(std::span<const std::byte> chunk, int level, EncodedChunk& out) {
  if (level < 0 || level > 9)
    throw InputError("cannot deflate a chunk at level " + std::to_string(level) +
                     " (levels are 0 to 9)");
  if (chunk.size() % kShuffleElementBytes != 0)
    throw InputError("cannot shuffle a chunk of " + std::to_string(chunk.size()) +
                     " bytes: not whole 8-byte elements");
  // Byte planes: the high bytes of coordinates and indices repeat and the noisy low ones stay
  // together, so that level 1 compresses about as well as level 4 on the bytes as they are.
  thread_local std::vector<std::byte> shuffled;
  shuffled.resize(chunk.size());
  shuffle_bytes(chunk, shuffled);
  // libdeflate writes the same zlib format as zlib's compress2, about twice as fast and a
  // little smaller at a given level; one compressor per thread and level, as shards are
  // compressed in parallel.
  struct FreeCompressor {
    void operator()(libdeflate_compressor* c) const { libdeflate_free_compressor(c); }
  };
  thread_local std::array<std::unique_ptr<libdeflate_compressor, FreeCompressor>, 10> compressors;
  auto& compressor = compressors[std::size_t(level)];
  if (!compressor) compressor.reset(libdeflate_alloc_compressor(level));
  if (!compressor) throw std::bad_alloc();
  const std::size_t bound = libdeflate_zlib_compress_bound(compressor.get(), chunk.size());
  out.bytes.resize(std::max(bound, chunk.size()) + kChecksumBytes);
  // 0: the stream would not fit in `bound`, which libdeflate promises never happens.
  const std::size_t compressed_bytes = libdeflate_zlib_compress(
      compressor.get(), shuffled.data(), shuffled.size(), out.bytes.data(), bound);
  std::size_t filtered_bytes = compressed_bytes;
  out.filter_mask = 0;
  if (compressed_bytes == 0 || compressed_bytes >= chunk.size()) {
    // Both filters are optional in the pipeline: HDF5 readers honour the mask bits.
    std::memcpy(out.bytes.data(), chunk.data(), chunk.size());
    filtered_bytes = chunk.size();
    out.filter_mask = kShuffleSkipped | kDeflateSkipped;
  }
  const std::uint32_t checksum = fletcher32({out.bytes.data(), filtered_bytes});
  store_le32(out.bytes.data() + filtered_bytes, checksum);
  out.bytes.resize(filtered_bytes + kChecksumBytes);
}

std::string decode_chunk(std::span<const std::byte> stored, std::uint32_t filter_mask,
                         std::span<std::byte> out) {
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
  if (out.size() % kShuffleElementBytes != 0)
    return "chunk of " + std::to_string(out.size()) + " bytes is not whole 8-byte elements";
  const bool shuffled = (filter_mask & kShuffleSkipped) == 0;
  thread_local std::vector<std::byte> planes;
  std::span<std::byte> target = out;  // where the filtered bytes go before unshuffling
  if (shuffled) {
    planes.resize(out.size());
    target = planes;
  }
  if ((filter_mask & kDeflateSkipped) != 0) {
    if (filtered.size() != out.size())
      return "uncompressed chunk holds " + std::to_string(filtered.size()) + " bytes, expected " +
             std::to_string(out.size());
    std::memcpy(target.data(), filtered.data(), out.size());
    if (shuffled) unshuffle_bytes(target, out);
    return {};
  }
  // The Fletcher-32 above already covers the whole stream, so inflate it raw, past the 2-byte
  // zlib header and without the Adler-32 trailer: zlib's own Adler-32 pass cost about a tenth
  // of a page-in.
  constexpr std::size_t kZlibHeader = 2, kAdlerTrailer = 4;
  if (filtered.size() < kZlibHeader + kAdlerTrailer)
    return "zlib stream of " + std::to_string(filtered.size()) + " bytes is too short";
  const unsigned cmf = std::to_integer<unsigned>(filtered[0]), flg = std::to_integer<unsigned>(filtered[1]);
  if ((cmf & 0x0f) != 8 || (cmf >> 4) > 7 || ((cmf << 8) | flg) % 31 != 0 || (flg & 0x20) != 0)
    return "chunk does not start with a zlib deflate header";
  // libdeflate inflates about twice as fast as zlib (page-ins are on the query's path); one
  // decompressor per thread, as page-ins run on several threads at once.
  struct FreeDecompressor {
    void operator()(libdeflate_decompressor* d) const { libdeflate_free_decompressor(d); }
  };
  thread_local const std::unique_ptr<libdeflate_decompressor, FreeDecompressor> decompressor(
      libdeflate_alloc_decompressor());
  if (!decompressor) return "cannot allocate a deflate decompressor";
  std::size_t inflated_bytes = 0;
  const libdeflate_result status = libdeflate_deflate_decompress(
      decompressor.get(), filtered.data() + kZlibHeader, filtered.size() - kZlibHeader - kAdlerTrailer,
      target.data(), target.size(), &inflated_bytes);
  if (status == LIBDEFLATE_INSUFFICIENT_SPACE)
    return "chunk inflates to more than " + std::to_string(out.size()) + " bytes";
  if (status != LIBDEFLATE_SUCCESS) return "cannot inflate the chunk (corrupt or incomplete deflate data)";
  if (inflated_bytes != out.size())
    return "chunk inflates to " + std::to_string(inflated_bytes) + " bytes, expected " +
           std::to_string(out.size());
  if (shuffled) unshuffle_bytes(target, out);
  return {};
}

}  // namespace tetrapage::detail
