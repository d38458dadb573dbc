// An index's shard payloads, measured (docs/BENCHMARKS.md, "Preprocess, fifth pass", quotes
// these figures):
//  1. every Nth payload cut into chunks of 8, 16 and 64 KiB (the last one zero-padded, as the
//     index stores it), shuffled in 8-byte words or not, each chunk deflated alone at levels 1
//     and 4 with libdeflate, one thread: the stored/decoded ratio and deflate and inflate MB/s
//     per payload byte (padding excluded), which is what chose format 2's chunks;
//  2. IndexReader::read_shard (pread, Fletcher-32, inflate, unshuffle) and Shard::decode,
//     microseconds a shard (run it twice: the first run may read from disk);
//  3. with --same-shards OTHER: how many shards' payloads differ between the two indexes (the
//     check that a preprocess change wrote the same shards).
//
//   tetrapage_bench_chunks INDEX [--every N] [--same-shards OTHER]

#include <libdeflate.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <vector>

#include "ChunkCodec.h"
#include "tetrapage/formats/Error.h"
#include "tetrapage/formats/IndexReader.h"
#include "tetrapage/runtime/Shard.h"

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

void chunk_table(const std::vector<std::vector<std::byte>>& payloads) {
  std::uint64_t payload_bytes = 0;
  for (const auto& p : payloads) payload_bytes += p.size();
  std::printf("| chunk | shuffle | level | ratio | deflate MB/s | inflate MB/s |\n|---:|---|---:|---:|---:|---:|\n");
  const std::unique_ptr<libdeflate_decompressor, Decompressor> inflater(libdeflate_alloc_decompressor());
  for (const std::size_t chunk : {8192, 16384, 65536})
    for (const bool shuffle : {false, true})
      for (const int level : {1, 4}) {
        const std::unique_ptr<libdeflate_compressor, Compressor> deflater(libdeflate_alloc_compressor(level));
        std::vector<std::byte> piece(chunk), shuffled(chunk), stored(libdeflate_zlib_compress_bound(deflater.get(), chunk)),
            back(chunk);
        std::uint64_t stored_bytes = 0;
        double deflate_seconds = 0, inflate_seconds = 0;
        for (const auto& payload : payloads)
          for (std::size_t at = 0; at < payload.size(); at += chunk) {
            std::fill(piece.begin(), piece.end(), std::byte{0});
            std::memcpy(piece.data(), payload.data() + at, std::min(chunk, payload.size() - at));
            if (shuffle) tetrapage::detail::shuffle_bytes(piece, shuffled);
            const std::vector<std::byte>& input = shuffle ? shuffled : piece;
            const auto start = Clock::now();
            const std::size_t n = libdeflate_zlib_compress(deflater.get(), input.data(), chunk, stored.data(), stored.size());
            const auto middle = Clock::now();
            std::size_t got = 0;
            if (libdeflate_zlib_decompress(inflater.get(), stored.data(), n, back.data(), chunk, &got) !=
                    LIBDEFLATE_SUCCESS ||
                got != chunk || back != input)
              throw tetrapage::Error("a chunk did not inflate back to itself");
            inflate_seconds += seconds(middle, Clock::now());
            deflate_seconds += seconds(start, middle);
            stored_bytes += n;
          }
        std::printf("| %zu KiB | %s | %d | %.3f | %.0f | %.0f |\n", chunk / 1024, shuffle ? "yes" : "no", level,
                    double(stored_bytes) / double(payload_bytes), double(payload_bytes) / deflate_seconds / 1e6,
                    double(payload_bytes) / inflate_seconds / 1e6);
      }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Measures an index's shard payloads: chunked deflate and inflate, page-in and decode"};
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
    for (std::uint32_t s = 0; s < reader.shard_count(); s += every) {
      const auto start = Clock::now();
      payloads.push_back(reader.read_shard(s));
      const auto middle = Clock::now();
      const tetrapage::Shard shard = tetrapage::Shard::decode(payloads.back());
      decode_seconds += seconds(middle, Clock::now());
      read_seconds += seconds(start, middle);
    }
    if (payloads.empty()) throw tetrapage::InputError(index.string() + " holds no shard");
    std::uint64_t bytes = 0;
    for (const auto& p : payloads) bytes += p.size();
    const double n = double(payloads.size());
    std::printf("%zu of %u shards, mean payload %.0f B: read_shard %.1f us, Shard::decode %.1f us a shard\n\n",
                payloads.size(), reader.shard_count(), double(bytes) / n, 1e6 * read_seconds / n,
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
