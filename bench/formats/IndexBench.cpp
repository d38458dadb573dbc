// The index file layout, measured (docs/FORMAT.md "Measured" quotes these figures):
//  1. write + read-all time and file size of our layout (one chunked /shards/data with
//     per-shard extents) against one group per shard with its own small dataset;
//  2. read_shard (one pread, Fletcher-32 and LZ4 outside HDF5) against
//     read_shard_through_hdf5 (H5Dread, serialised behind HDF5's global lock), 1 and 2 threads.
//
//   tetrapage_bench_index [--shards=N] [benchmark flags]
//
// Payloads are 2-200 KiB of float32 coordinates with noisy low bits and increasing ids
// (compressible, as real shards are), written into a temporary folder removed at exit. Both
// layouts use the index's pipeline (shuffle, LZ4, Fletcher-32) and chunk size.
// Files are read from the page cache: the figures are decode and library cost, not disk.

#include <benchmark/benchmark.h>
#include <hdf5.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "tetrapage/formats/index/IndexReader.h"
#include "tetrapage/formats/index/IndexWriter.h"
#include "tetrapage/tools/Random.h"

namespace {

std::size_t g_shard_count = 2000;
std::filesystem::path g_folder;
std::vector<std::byte> g_pool;  ///< payloads are slices of this pool
std::vector<std::size_t> g_sizes;
std::vector<std::size_t> g_starts;
std::unique_ptr<tetrapage::IndexReader> g_reader;

void make_payloads() {
  tetrapage::Random random(12345);
  // Triangles: 9 float32 coordinates of a wavy surface plus a uint32 id, 40 bytes each.
  const std::size_t pool_triangles = (8u << 20) / 40;
  g_pool.resize(pool_triangles * 40);
  std::byte* out = g_pool.data();
  for (std::size_t t = 0; t < pool_triangles; ++t) {
    for (int c = 0; c < 9; ++c) {
      const double x = double(t) * 1e-3 + c;
      const auto value = static_cast<float>(100.0 * std::sin(x) + random.uniform(-0.01, 0.01));
      std::memcpy(out, &value, 4);
      out += 4;
    }
    const auto id = static_cast<std::uint32_t>(t);
    std::memcpy(out, &id, 4);
    out += 4;
  }
  for (std::size_t s = 0; s < g_shard_count; ++s) {
    const std::size_t size = 2048 + random.below(198 * 1024);
    g_sizes.push_back(size);
    g_starts.push_back(random.below(g_pool.size() - size));
  }
}

std::span<const std::byte> payload(std::size_t shard) {
  return {g_pool.data() + g_starts[shard], g_sizes[shard]};
}

std::uint64_t total_payload_bytes() {
  std::uint64_t bytes = 0;
  for (auto size : g_sizes) bytes += size;
  return bytes;
}

std::uint64_t write_index_layout(const std::filesystem::path& path) {
  tetrapage::IndexWriter writer(path);
  for (std::size_t s = 0; s < g_shard_count; ++s) writer.append_shard(payload(s));
  return writer.commit(tetrapage::IndexHeader{});
}

std::uint64_t write_group_per_shard(const std::filesystem::path& path) {
  const hid_t file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  const hid_t shards = H5Gcreate2(file, "shards", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  for (std::size_t s = 0; s < g_shard_count; ++s) {
    const hid_t group = H5Gcreate2(shards, std::to_string(s).c_str(), H5P_DEFAULT, H5P_DEFAULT,
                                   H5P_DEFAULT);
    // The index's pipeline and chunk size on 8-byte words; HDF5 compresses with the LZ4
    // plugin (Debian's hdf5-filter-plugin).
    const hsize_t words = (g_sizes[s] + 7) / 8;
    const hsize_t chunk = std::min<hsize_t>(words, tetrapage::IndexWriterOptions{}.chunk_bytes / 8);
    std::vector<std::byte> padded(words * 8);
    std::memcpy(padded.data(), payload(s).data(), g_sizes[s]);
    const hid_t space = H5Screate_simple(1, &words, nullptr);
    const hid_t creation = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_chunk(creation, 1, &chunk);
    H5Pset_shuffle(creation);
    const unsigned block = static_cast<unsigned>(chunk * 8);
    H5Pset_filter(creation, 32004, H5Z_FLAG_MANDATORY, 1, &block);
    H5Pset_fletcher32(creation);
    const hid_t dataset =
        H5Dcreate2(group, "data", H5T_STD_U64LE, space, H5P_DEFAULT, creation, H5P_DEFAULT);
    if (dataset < 0 || H5Dwrite(dataset, H5T_STD_U64LE, H5S_ALL, H5S_ALL, H5P_DEFAULT, padded.data()) < 0)
      throw std::runtime_error("H5Dwrite failed (is the LZ4 plugin, hdf5-filter-plugin, installed?)");
    H5Dclose(dataset);
    H5Pclose(creation);
    H5Sclose(space);
    H5Gclose(group);
  }
  H5Gclose(shards);
  H5Fclose(file);
  return std::filesystem::file_size(path);
}

std::uint64_t read_all_group_per_shard(const std::filesystem::path& path) {
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  std::uint64_t bytes = 0;
  std::vector<std::byte> buffer;
  for (std::size_t s = 0; s < g_shard_count; ++s) {
    const std::string name = "/shards/" + std::to_string(s) + "/data";
    const hid_t dataset = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
    const hid_t space = H5Dget_space(dataset);
    hsize_t size = 0;
    H5Sget_simple_extent_dims(space, &size, nullptr);
    buffer.resize(size * 8);
    if (H5Dread(dataset, H5T_STD_U64LE, H5S_ALL, H5S_ALL, H5P_DEFAULT, buffer.data()) < 0)
      throw std::runtime_error("H5Dread failed");
    bytes += g_sizes[s];
    H5Sclose(space);
    H5Dclose(dataset);
  }
  H5Fclose(file);
  return bytes;
}

void BM_Write_IndexLayout(benchmark::State& state) {
  std::uint64_t file_bytes = 0;
  for (auto _ : state) file_bytes = write_index_layout(g_folder / "write_index.tpi");
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * total_payload_bytes()));
  state.counters["file_MiB"] = double(file_bytes) / (1 << 20);
  state.counters["payload_MiB"] = double(total_payload_bytes()) / (1 << 20);
}

void BM_Write_GroupPerShard(benchmark::State& state) {
  std::uint64_t file_bytes = 0;
  for (auto _ : state) file_bytes = write_group_per_shard(g_folder / "write_groups.h5");
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * total_payload_bytes()));
  state.counters["file_MiB"] = double(file_bytes) / (1 << 20);
  state.counters["payload_MiB"] = double(total_payload_bytes()) / (1 << 20);
}

/// Open + read every shard (raw path), like a cold start that pages the whole model in.
void BM_ReadAll_IndexLayout(benchmark::State& state) {
  for (auto _ : state) {
    const tetrapage::IndexReader reader(g_folder / "index.tpi");
    std::uint64_t bytes = 0;
    for (std::uint32_t s = 0; s < reader.shard_count(); ++s) bytes += reader.read_shard(s).size();
    if (bytes != total_payload_bytes()) state.SkipWithError("wrong byte count");
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * total_payload_bytes()));
}

void BM_ReadAll_IndexLayoutThroughHdf5(benchmark::State& state) {
  for (auto _ : state) {
    const tetrapage::IndexReader reader(g_folder / "index.tpi");
    std::uint64_t bytes = 0;
    for (std::uint32_t s = 0; s < reader.shard_count(); ++s)
      bytes += reader.read_shard_through_hdf5(s).size();
    if (bytes != total_payload_bytes()) state.SkipWithError("wrong byte count");
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * total_payload_bytes()));
}

void BM_ReadAll_GroupPerShard(benchmark::State& state) {
  for (auto _ : state)
    if (read_all_group_per_shard(g_folder / "groups.h5") != total_payload_bytes())
      state.SkipWithError("wrong byte count");
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * total_payload_bytes()));
}

/// One shard per iteration from a shared reader; threads stride through the shards.
template <bool kThroughHdf5>
void BM_ReadShard(benchmark::State& state) {
  const auto count = g_reader->shard_count();
  std::uint32_t shard = static_cast<std::uint32_t>(state.thread_index()) * 997 % count;
  std::int64_t bytes = 0;
  for (auto _ : state) {
    const auto data = kThroughHdf5 ? g_reader->read_shard_through_hdf5(shard)
                                   : g_reader->read_shard(shard);
    bytes += static_cast<std::int64_t>(data.size());
    benchmark::DoNotOptimize(data.data());
    shard = (shard + 1) % count;
  }
  state.SetBytesProcessed(bytes);
}

}  // namespace

BENCHMARK(BM_Write_IndexLayout)->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(3);
BENCHMARK(BM_Write_GroupPerShard)->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(3);
BENCHMARK(BM_ReadAll_IndexLayout)->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(3);
BENCHMARK(BM_ReadAll_IndexLayoutThroughHdf5)
    ->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(3);
BENCHMARK(BM_ReadAll_GroupPerShard)->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(3);
BENCHMARK(BM_ReadShard<false>)
    ->Name("BM_ReadShard_Raw")->UseRealTime()->Threads(1)->Threads(2)
    ->Unit(benchmark::kMicrosecond)->MinTime(1.0)->Repetitions(3);
BENCHMARK(BM_ReadShard<true>)
    ->Name("BM_ReadShard_ThroughHdf5")->UseRealTime()->Threads(1)->Threads(2)
    ->Unit(benchmark::kMicrosecond)->MinTime(1.0)->Repetitions(3);

int main(int argc, char** argv) {
  std::vector<char*> arguments;
  for (int i = 0; i < argc; ++i) {
    const std::string argument = argv[i];
    if (argument.rfind("--shards=", 0) == 0)
      g_shard_count = std::stoul(argument.substr(9));
    else
      arguments.push_back(argv[i]);
  }
  int count = static_cast<int>(arguments.size());
  benchmark::Initialize(&count, arguments.data());
  if (benchmark::ReportUnrecognizedArguments(count, arguments.data())) return 1;

  g_folder = std::filesystem::temp_directory_path() /
             ("tetrapage_bench_index_" + std::to_string(::getpid()));
  std::filesystem::create_directories(g_folder);
  make_payloads();
  write_index_layout(g_folder / "index.tpi");
  write_group_per_shard(g_folder / "groups.h5");
  g_reader = std::make_unique<tetrapage::IndexReader>(g_folder / "index.tpi");

  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  g_reader.reset();
  std::filesystem::remove_all(g_folder);
  return 0;
}
