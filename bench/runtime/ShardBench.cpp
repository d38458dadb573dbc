// Shard micro benchmarks: build time, query time and counters (cells or nodes visited,
// references examined, candidates) of the grid and the R-tree on three region shapes, bytes
// per triangle raw, stored (the index's codec: shuffle, LZ4, Fletcher-32) and resident, float
// vs double, and the fit of the cost model's constants (BM_CostFit, BM_PageIn) quoted in
// preprocess/src/ShardCostModel.cpp.
//
// Regions (4096 triangles each, the preprocess's leaf size, fixed seeds):
//  soup       small random triangles uniform in a unit cube
//  shell      a tessellated unit sphere surface (a thin shell: most cells of a grid are empty)
//  clustered  small triangles in 8 tight Gaussian clusters
// Queries: cubes of side `extent` (a fraction of the region) centred on random triangles.

#include <benchmark/benchmark.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <ctime>
#include <filesystem>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "tetrapage/formats/index/IndexReader.h"
#include "tetrapage/formats/index/IndexWriter.h"
#include "tetrapage/preprocess/ShardBuilder.h"
#include "tetrapage/preprocess/ShardCostModel.h"
#include "tetrapage/runtime/paging/Shard.h"
#include "tetrapage/tools/Random.h"

namespace {

using namespace tetrapage;
using geometry::Box;
using geometry::Point;
using geometry::Triangle;

constexpr std::size_t kTriangles = 4096;
const char* const kScenes[] = {"soup", "shell", "clustered"};

struct Region {
  std::vector<Triangle> triangles;
  std::vector<std::uint64_t> ids;
  std::vector<std::uint32_t> parts;
  ShardTriangles view() const { return {triangles, ids, parts}; }
};

Point jitter(Random& r, const Point& c, double s) {
  return {c[0] + r.uniform(-s, s), c[1] + r.uniform(-s, s), c[2] + r.uniform(-s, s)};
}

Region make_region(int scene) {
  Random r(100 + std::uint64_t(scene));
  Region region;
  if (scene == 1) {  // sphere: a latitude/longitude tessellation with 2 * 32 * 64 triangles
    const int rings = 32, segments = 64;
    auto at = [](int i, int j, int rings_, int segments_) {
      const double theta = std::numbers::pi * i / rings_, phi = 2 * std::numbers::pi * j / segments_;
      return Point{std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
    };
    for (int i = 0; i < rings; ++i)
      for (int j = 0; j < segments; ++j) {
        region.triangles.push_back({at(i, j, rings, segments), at(i + 1, j, rings, segments),
                                    at(i + 1, j + 1, rings, segments)});
        region.triangles.push_back({at(i, j, rings, segments), at(i + 1, j + 1, rings, segments),
                                    at(i, j + 1, rings, segments)});
      }
  } else {
    std::vector<Point> clusters;
    for (int c = 0; c < 8; ++c) clusters.push_back(jitter(r, {0, 0, 0}, 0.8));
    const double size = scene == 0 ? 0.02 : 0.01;
    for (std::size_t i = 0; i < kTriangles; ++i) {
      Point c;
      if (scene == 0) {
        c = jitter(r, {0, 0, 0}, 1);
      } else {
        const Point& k = clusters[r.below(8)];
        c = {k[0] + 0.05 * r.normal(), k[1] + 0.05 * r.normal(), k[2] + 0.05 * r.normal()};
      }
      region.triangles.push_back({jitter(r, c, size), jitter(r, c, size), jitter(r, c, size)});
    }
  }
  for (std::size_t i = 0; i < region.triangles.size(); ++i) {
    region.ids.push_back(5'000'000 + i);
    region.parts.push_back(std::uint32_t(i / 1000));
  }
  return region;
}

const Region& region(int scene) {
  static const std::array<Region, 3> regions{make_region(0), make_region(1), make_region(2)};
  return regions[std::size_t(scene)];
}

std::vector<Box> queries(int scene, double extent, std::size_t count) {
  const Region& reg = region(scene);
  Random r(200 + std::uint64_t(scene));
  std::vector<Box> boxes;
  for (std::size_t i = 0; i < count; ++i) {
    const Triangle& t = reg.triangles[r.below(reg.triangles.size())];
    Box b;
    for (int k = 0; k < 3; ++k) {
      const double c = (t[0][k] + t[1][k] + t[2][k]) / 3;
      b.lo[k] = c - extent / 2;
      b.hi[k] = c + extent / 2;
    }
    boxes.push_back(b);
  }
  return boxes;
}

// The bytes a payload takes in an index file (chunks as IndexWriter stores them).
std::size_t stored_bytes(const std::vector<std::byte>& payload) {
  std::size_t bytes = 0;
  for (const auto& chunk : encode_shard(payload).chunks) bytes += chunk.size();
  return bytes;
}

// Args: scene, kind, precision.
void BM_Build(benchmark::State& state) {
  const Region& reg = region(int(state.range(0)));
  const auto kind = ShardKind(state.range(1));
  const auto precision = StoredPrecision(state.range(2));
  BuiltShard built;
  for (auto _ : state) {
    built = build_shard(reg.view(), kind, precision);
    benchmark::DoNotOptimize(built.payload.data());
  }
  const double n = double(reg.triangles.size());
  const Shard shard = Shard::decode(built.payload);
  state.counters["bytes_per_triangle"] = double(built.payload.size()) / n;
  state.counters["stored_bytes_per_triangle"] = double(stored_bytes(built.payload)) / n;
  state.counters["resident_bytes_per_triangle"] = double(shard.memory_bytes()) / n;
  state.counters["vertices_per_triangle"] = double(built.vertex_count) / n;
  state.counters["grid_references_per_triangle"] = double(built.grid_references) / n;
  state.counters["max_rounding_distance"] = built.max_rounding_distance;
  state.counters["triangles_per_second"] =
      benchmark::Counter(n, benchmark::Counter::kIsIterationInvariantRate);
  state.SetLabel(std::string(kScenes[state.range(0)]) + "/" + std::string(to_string(kind)) +
                 "/" + std::string(to_string(precision)));
}

// Args: scene, kind, extent in thousandths of the region's side (2).
void BM_Query(benchmark::State& state) {
  const int scene = int(state.range(0));
  const auto kind = ShardKind(state.range(1));
  const double extent = 2.0 * double(state.range(2)) / 1000;
  const Shard shard =
      Shard::decode(build_shard(region(scene).view(), kind, StoredPrecision::float32).payload);
  const std::vector<Box> boxes = queries(scene, extent, 1024);
  ShardQueryCounters counters;
  std::size_t i = 0, found = 0;
  for (auto _ : state) {
    shard.for_each_candidate(boxes[i++ & 1023], [&](std::uint32_t t) { found += t; }, counters);
  }
  benchmark::DoNotOptimize(found);
  const double q = double(state.iterations());
  state.counters["visited_per_query"] = double(counters.visited) / q;
  state.counters["references_per_query"] = double(counters.references) / q;
  state.counters["candidates_per_query"] = double(counters.candidates) / q;
  state.counters["queries_per_second"] =
      benchmark::Counter(1, benchmark::Counter::kIsIterationInvariantRate);
  state.SetLabel(std::string(kScenes[scene]) + "/" + std::string(to_string(kind)) + "/extent " +
                 std::to_string(extent));
}

// Paging in as the runtime does, per decoded byte: the shard written alone to an index file
// (format 3: shuffled, LZ4, Fletcher-32), then IndexReader::read_shard into a kept buffer
// (direct chunk reads, the file in the page cache) and Shard::decode with the runtime's
// checks (its structure). Args: scene, kind.
void BM_PageIn(benchmark::State& state) {
  const BuiltShard built = build_shard(region(int(state.range(0))).view(),
                                       ShardKind(state.range(1)), StoredPrecision::float32);
  const std::filesystem::path path = std::filesystem::temp_directory_path() /
                                     ("tetrapage_bench_pagein_" + std::to_string(::getpid()) + ".tpi");
  {
    IndexWriter writer(path);
    writer.append_shard(built.payload);
    IndexHeader header;
    header.shard_count = 1;
    writer.commit(header);
  }
  {
    const IndexReader reader(path);
    std::vector<std::byte> payload;
    for (auto _ : state) {
      reader.read_shard(0, payload);
      const Shard shard = Shard::decode(payload, "shard", DecodeChecks::structure);
      benchmark::DoNotOptimize(shard.triangle_count());
    }
  }
  std::filesystem::remove(path);
  state.SetBytesProcessed(std::int64_t(state.iterations()) * std::int64_t(built.payload.size()));
  state.counters["seconds_per_byte"] = benchmark::Counter(
      double(built.payload.size()),
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.SetLabel(std::string(kScenes[state.range(0)]) + "/" +
                 std::string(to_string(ShardKind(state.range(1)))));
}

double thread_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

// Least squares over many workloads: CPU seconds per query = a * visited + b * references +
// c * candidates + d, per kind (thread CPU time: the machine is shared). Workloads: 3 scenes
// x 5 extents x 3 layouts; each timed as the median of 5 runs of 512 queries.
void BM_CostFit(benchmark::State& state) {
  const auto kind = ShardKind(state.range(0));
  constexpr int kTerms = 4;
  std::array<double, kTerms> solution{};
  for (auto _ : state) {
    std::vector<std::array<double, kTerms + 1>> rows;
    for (int scene = 0; scene < 3; ++scene)
      for (const double extent : {0.0, 0.02, 0.06, 0.15, 0.4})
        for (int layout_index = 0; layout_index < 3; ++layout_index) {
          ShardLayout layout;
          layout.grid_cells_per_triangle = std::array{0.25, 1.0, 4.0}[std::size_t(layout_index)];
          layout.rtree_leaf_size = std::array{4u, 8u, 16u}[std::size_t(layout_index)];
          const Shard shard = Shard::decode(
              build_shard(region(scene).view(), kind, StoredPrecision::float32, layout).payload);
          const std::vector<Box> boxes = queries(scene, extent, 512);
          ShardQueryCounters counters;
          std::size_t sink = 0;
          for (const Box& b : boxes)
            shard.for_each_candidate(b, [&](std::uint32_t t) { sink += t; }, counters);
          std::vector<double> times;
          for (int run = 0; run < 5; ++run) {
            const double start = thread_seconds();
            for (const Box& b : boxes)
              shard.for_each_candidate(b, [&](std::uint32_t t) { sink += t; });
            times.push_back(thread_seconds() - start);
          }
          benchmark::DoNotOptimize(sink);
          std::nth_element(times.begin(), times.begin() + 2, times.end());
          const double q = double(boxes.size());
          rows.push_back({double(counters.visited) / q, double(counters.references) / q,
                          double(counters.candidates) / q, 1.0, times[2] / q});
        }
    // Non-negative least squares by elimination: solve the normal equations on the active
    // terms, drop the most negative term, repeat (a cost is never negative).
    std::array<bool, kTerms> active{};
    active.fill(true);
    for (bool negative = true; negative;) {
      std::array<std::array<double, kTerms + 1>, kTerms> m{};
      for (const auto& row : rows)
        for (std::size_t i = 0; i < kTerms; ++i)
          for (std::size_t j = 0; j <= kTerms; ++j)
            if (active[i] && (j == kTerms || active[j])) m[i][j] += row[i] * row[j];
      for (std::size_t i = 0; i < kTerms; ++i)
        if (!active[i]) m[i][i] = 1;  // the dropped term: 0
      for (std::size_t c = 0; c < kTerms; ++c) {
        std::size_t pivot = c;
        for (std::size_t r = c + 1; r < kTerms; ++r)
          if (std::fabs(m[r][c]) > std::fabs(m[pivot][c])) pivot = r;
        std::swap(m[c], m[pivot]);
        for (std::size_t r = 0; r < kTerms; ++r) {
          if (r == c) continue;
          const double f = m[r][c] / m[c][c];
          for (std::size_t j = c; j <= kTerms; ++j) m[r][j] -= f * m[c][j];
        }
      }
      for (std::size_t c = 0; c < kTerms; ++c) solution[c] = m[c][kTerms] / m[c][c];
      const auto worst = std::min_element(solution.begin(), solution.end());
      negative = *worst < 0;
      if (negative) active[std::size_t(worst - solution.begin())] = false;
    }
  }
  state.counters["ns_per_visit"] = solution[0] * 1e9;
  state.counters["ns_per_reference"] = solution[1] * 1e9;
  state.counters["ns_per_candidate"] = solution[2] * 1e9;
  state.counters["ns_per_query"] = solution[3] * 1e9;
  state.SetLabel(std::string(to_string(kind)));
}

// Preprocess cost of choosing: estimate_shard_costs on each scene (6 builds + sampled queries).
void BM_ChooseKind(benchmark::State& state) {
  const ShardCostModel model;
  ShardCostReport report;
  for (auto _ : state)
    report = estimate_shard_costs(region(int(state.range(0))).view(), 0.1,
                                  StoredPrecision::float32, model);
  state.counters["chosen_rtree"] = report.chosen == ShardKind::rtree;
  state.counters["grid_us_per_query"] = report.grid.total_seconds() * 1e6;
  state.counters["rtree_us_per_query"] = report.rtree.total_seconds() * 1e6;
  state.SetLabel(std::string(kScenes[state.range(0)]));
}

BENCHMARK(BM_Build)->ArgsProduct({{0, 1, 2}, {0, 1}, {0, 1}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Query)->ArgsProduct({{0, 1, 2}, {0, 1}, {10, 50, 200}});
BENCHMARK(BM_PageIn)->ArgsProduct({{0, 1, 2}, {0, 1}})->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_CostFit)->Arg(0)->Arg(1)->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ChooseKind)->DenseRange(0, 2)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
