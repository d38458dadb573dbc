// An index's shard payloads, measured (docs/BENCHMARKS.md, "Index size, and the codec", quotes
// these figures):
//  1. every Nth payload cut into chunks of 8, 16 and 64 KiB (the last one zero-padded, as the
//     index stores it), shuffled in 8-byte words or not, each chunk compressed alone with
//     libdeflate at levels 1 and 4 and with LZ4, one thread: the stored/decoded ratio and
//     compress and decompress MB/s per payload byte (padding excluded), which is what chose
//     the format's chunks (format 2) and codec (format 3);
//  2. IndexReader::read_shard (pread, Fletcher-32, LZ4 and unshuffle unless the index was
//     preprocessed with --compression none) and Shard::decode, microseconds a shard, from the
//     page cache (a first pass warms it), and the bytes a shard is stored in;
//  3. with --same-shards OTHER: how many shards' payloads differ between the two indexes (the
//     check that a preprocess change wrote the same shards).
//
//   tetrapage_bench_chunks INDEX [--every N] [--same-shards OTHER]

#include <libdeflate.h>
#include <lz4.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "ChunkCodec.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/index/IndexReader.h"
#include "tetrapage/runtime/paging/Shard.h"

namespace {

using tetrapage::IndexReader;
using Clock = std::chrono::steady_clock;

double seconds(Clock::time_point start, Clock::time_point end) {
  return std::chrono::duration<double>(end - start).count();
}

struct Compressor {
  void operator()(libdeflate_compressor* c) const { libdeflate_free_compressor(c); }
};
struct Decompressor {
  void operator()(libdeflate_decompressor* d) const { libdeflate_free_decompressor(d); }
};

/// One way to compress a chunk: into `stored` (large enough), returning the stored size, and
/// back into `back` (the chunk's size), returning false if it did not come back.
struct Codec {
  std::string name;
  std::function<std::size_t(std::span<const std::byte> chunk, std::vector<std::byte>& stored)> compress;
  std::function<bool(std::span<const std::byte> stored, std::span<std::byte> back)> decompress;
};

std::vector<Codec> codecs() {
  std::vector<Codec> all;
  auto inflater = std::shared_ptr<libdeflate_decompressor>(libdeflate_alloc_decompressor(), Decompressor{});
  for (const int level : {1, 4}) {
    auto deflater = std::shared_ptr<libdeflate_compressor>(libdeflate_alloc_compressor(level), Compressor{});
    all.push_back({"deflate " + std::to_string(level),
                   [deflater](std::span<const std::byte> chunk, std::vector<std::byte>& stored) {
                     return libdeflate_zlib_compress(deflater.get(), chunk.data(), chunk.size(), stored.data(),
                                                     stored.size());
                   },
                   [inflater](std::span<const std::byte> stored, std::span<std::byte> back) {
                     std::size_t got = 0;
                     return libdeflate_zlib_decompress(inflater.get(), stored.data(), stored.size(), back.data(),
                                                       back.size(), &got) == LIBDEFLATE_SUCCESS &&
                            got == back.size();
                   }});
  }
  all.push_back({"LZ4",
                 [](std::span<const std::byte> chunk, std::vector<std::byte>& stored) {
                   return std::size_t(LZ4_compress_default(reinterpret_cast<const char*>(chunk.data()),
                                                           reinterpret_cast<char*>(stored.data()), int(chunk.size()),
                                                           int(stored.size())));
                 },
                 [](std::span<const std::byte> stored, std::span<std::byte> back) {
                   return LZ4_decompress_safe(reinterpret_cast<const char*>(stored.data()),
                                              reinterpret_cast<char*>(back.data()), int(stored.size()),
                                              int(back.size())) == int(back.size());
                 }});
  return all;
}

void chunk_table(const std::vector<std::vector<std::byte>>& payloads) {
  std::uint64_t payload_bytes = 0;
  for (const auto& p : payloads) payload_bytes += p.size();
  std::printf("| chunk | shuffle | codec | ratio | compress MB/s | decompress MB/s |\n|---:|---|---|---:|---:|---:|\n");
  for (const Codec& codec : codecs())
    for (const std::size_t chunk : {8192, 16384, 65536})
      for (const bool shuffle : {false, true}) {
        std::vector<std::byte> piece(chunk), shuffled(chunk), stored(2 * chunk + 1024), back(chunk);
        std::uint64_t stored_bytes = 0;
        double compress_seconds = 0, decompress_seconds = 0;
        for (const auto& payload : payloads)
          for (std::size_t at = 0; at < payload.size(); at += chunk) {
            std::fill(piece.begin(), piece.end(), std::byte{0});
            std::memcpy(piece.data(), payload.data() + at, std::min(chunk, payload.size() - at));
            if (shuffle) tetrapage::detail::shuffle_bytes(piece, shuffled);
            const std::vector<std::byte>& input = shuffle ? shuffled : piece;
            const auto start = Clock::now();
            const std::size_t n = codec.compress(input, stored);
            const auto middle = Clock::now();
            if (n == 0 || !codec.decompress(std::span(stored).first(n), back) || back != input)
              throw tetrapage::Error("a chunk did not decompress back to itself (" + codec.name + ")");
            decompress_seconds += seconds(middle, Clock::now());
            compress_seconds += seconds(start, middle);
            stored_bytes += n;
          }
        std::printf("| %zu KiB | %s | %s | %.3f | %.0f | %.0f |\n", chunk / 1024, shuffle ? "yes" : "no",
                    codec.name.c_str(), double(stored_bytes) / double(payload_bytes),
                    double(payload_bytes) / compress_seconds / 1e6, double(payload_bytes) / decompress_seconds / 1e6);
      }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Measures an index's shard payloads: chunks compressed with deflate and LZ4, page-in and decode"};
  std::filesystem::path index, other;
  std::uint32_t every = 8;
  app.add_option("index", index, "Index file (.tpi)")->required()->check(CLI::ExistingFile);
  app.add_option("--every", every, "Measure every Nth shard")->capture_default_str()->check(CLI::PositiveNumber);
  app.add_option("--same-shards", other, "Count the shards whose payloads differ from this index's")
      ->check(CLI::ExistingFile);
  CLI11_PARSE(app, argc, argv);
  try {
    const IndexReader reader(index);
    std::vector<std::vector<std::byte>> payloads;
    double read_seconds = 0, decode_seconds = 0;
    // Timed as a page-in is, each payload dropped after its decode: keeping them all made the
    // reads pay for fresh pages. The first pass warms the page cache (the machine reclaims
    // idle file pages) and is not timed.
    for (std::uint32_t s = 0; s < reader.shard_count(); s += every) (void)reader.read_shard(s);
    for (std::uint32_t s = 0; s < reader.shard_count(); s += every) {
      const auto start = Clock::now();
      const std::vector<std::byte> payload = reader.read_shard(s);
      const auto middle = Clock::now();
      const tetrapage::Shard shard = tetrapage::Shard::decode(payload);
      decode_seconds += seconds(middle, Clock::now());
      read_seconds += seconds(start, middle);
    }
    for (std::uint32_t s = 0; s < reader.shard_count(); s += every) payloads.push_back(reader.read_shard(s));
    if (payloads.empty()) throw tetrapage::InputError(index.string() + " holds no shard");
    std::uint64_t bytes = 0, stored = 0;
    for (const auto& p : payloads) bytes += p.size();
    for (std::uint32_t s = 0; s < reader.shard_count(); s += every) stored += reader.stored_shard_size(s);
    const double n = double(payloads.size());
    // (Stored: as the index keeps them, LZ4 or, from `preprocess --compression none`, as they are.)
    std::printf("%zu of %u shards, mean payload %.0f B, stored %.0f B: read_shard %.2f us, Shard::decode %.2f us a "
                "shard\n\n",
                payloads.size(), reader.shard_count(), double(bytes) / n, double(stored) / n, 1e6 * read_seconds / n,
                1e6 * decode_seconds / n);
    chunk_table(payloads);
    if (!other.empty()) {
      const IndexReader second(other);
      if (second.shard_count() != reader.shard_count()) {
        std::printf("\nshards: %u against %u\n", reader.shard_count(), second.shard_count());
        return 1;
      }
      std::uint32_t differ = 0;
      for (std::uint32_t s = 0; s < reader.shard_count(); ++s) differ += reader.read_shard(s) != second.read_shard(s);
      std::printf("\nsame shards: %u of %u differ\n", differ, reader.shard_count());
      return differ == 0 ? 0 : 1;
    }
  } catch (const tetrapage::Error& error) {
    std::fprintf(stderr, "tetrapage_bench_chunks: %s\n", error.what());
    return 1;
  }
  return 0;
}
