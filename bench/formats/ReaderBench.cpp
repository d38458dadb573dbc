// Read throughput of our mesh readers (OBJ, binary STL, binary and ASCII PLY, OFF, GLB) and of
// the Assimp path on the same files, on one generated grid surface of ~2M triangles.
//
//   tetrapage_bench_formats [--triangles=N] [--keep] [benchmark flags]
//
// The files are written once at start-up into a temporary folder (removed at exit unless
// --keep) and are then in the page cache: the figures are warm-cache parse throughput, not
// disk throughput. Coordinates are multiples of 1e-6, as CAD exporters print them ("%.6f"),
// so text files hold short numbers.

#include <benchmark/benchmark.h>
#include <unistd.h>

#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/MeshWriter.h"

namespace {

using tetrapage::TriangleIndices;
using tetrapage::TriangleSoup;
using tetrapage::Vec3;

/// A height field over an n x n grid of quads (2 n^2 triangles), gently curved so that no
/// triangle is degenerate.
TriangleSoup grid_surface(std::size_t n) {
  TriangleSoup soup;
  soup.part_names = {"grid"};
  soup.vertices.reserve((n + 1) * (n + 1));
  const double step = 0.0123457;
  for (std::size_t j = 0; j <= n; ++j) {
    for (std::size_t i = 0; i <= n; ++i) {
      const double x = 100.0 + step * double(i);
      const double y = -50.0 + step * double(j);
      const double z = 3.0 * std::sin(0.01 * double(i)) * std::cos(0.013 * double(j));
      soup.vertices.push_back(
          {std::round(x * 1e6) / 1e6, std::round(y * 1e6) / 1e6, std::round(z * 1e6) / 1e6});
    }
  }
  soup.triangles.reserve(2 * n * n);
  for (std::size_t j = 0; j < n; ++j) {
    for (std::size_t i = 0; i < n; ++i) {
      const auto a = static_cast<std::uint32_t>(j * (n + 1) + i);
      const auto b = a + 1;
      const auto c = static_cast<std::uint32_t>(a + n + 1);
      const auto d = c + 1;
      soup.triangles.push_back({a, b, d});
      soup.triangles.push_back({a, d, c});
    }
  }
  soup.part_of.assign(soup.triangles.size(), 0);
  return soup;
}

/// ASCII PLY, which MeshWriter does not write (it writes binary PLY).
void write_ascii_ply(const std::filesystem::path& path, const TriangleSoup& soup) {
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) throw std::runtime_error("cannot write " + path.string());
  std::fprintf(file,
               "ply\nformat ascii 1.0\nelement vertex %zu\nproperty double x\nproperty double y\n"
               "property double z\nelement face %zu\nproperty list uchar int vertex_indices\n"
               "end_header\n",
               soup.vertices.size(), soup.triangles.size());
  char line[128];
  for (const Vec3& p : soup.vertices) {
    char* end = line;
    for (int k = 0; k < 3; ++k) {
      end = std::to_chars(end, line + sizeof line, p[k]).ptr;
      *end++ = k < 2 ? ' ' : '\n';
    }
    std::fwrite(line, 1, static_cast<std::size_t>(end - line), file);
  }
  for (const TriangleIndices& t : soup.triangles) {
    char* end = line;
    *end++ = '3';
    for (int k = 0; k < 3; ++k) {
      *end++ = ' ';
      end = std::to_chars(end, line + sizeof line, t[k]).ptr;
    }
    *end++ = '\n';
    std::fwrite(line, 1, static_cast<std::size_t>(end - line), file);
  }
  if (std::fclose(file) != 0) throw std::runtime_error("cannot write " + path.string());
}

/// ASCII STL, which MeshWriter does not write (it writes binary STL).
void write_ascii_stl(const std::filesystem::path& path, const TriangleSoup& soup) {
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) throw std::runtime_error("cannot write " + path.string());
  std::fprintf(file, "solid grid\n");
  for (const TriangleIndices& t : soup.triangles) {
    std::fprintf(file, "facet normal 0 0 1\nouter loop\n");
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = soup.vertices[t[k]];
      std::fprintf(file, "vertex %.6f %.6f %.6f\n", p[0], p[1], p[2]);
    }
    std::fprintf(file, "endloop\nendfacet\n");
  }
  std::fprintf(file, "endsolid grid\n");
  if (std::fclose(file) != 0) throw std::runtime_error("cannot write " + path.string());
}

void read_benchmark(benchmark::State& state, const std::filesystem::path& path, bool assimp) {
  std::uint64_t triangles = 0;
  std::uint64_t bytes = 0;
  for (auto _ : state) {
    try {
      tetrapage::ReadReport report;
      const TriangleSoup soup = assimp ? tetrapage::read_mesh_with_assimp(path, &report)
                                       : tetrapage::read_mesh(path, &report);
      benchmark::DoNotOptimize(soup.triangles.data());
      triangles = soup.triangle_count();
      bytes = report.bytes;
    } catch (const std::exception& error) {
      state.SkipWithError(error.what());
      break;
    }
  }
  using benchmark::Counter;
  // Rates print as "<value>/s": triangles_read=9.3M/s, MB_read=338/s.
  state.counters["triangles"] = double(triangles);
  state.counters["file_MB"] = double(bytes) / 1e6;
  state.counters["triangles_read"] = Counter(double(triangles), Counter::kIsIterationInvariantRate);
  state.counters["MB_read"] = Counter(double(bytes) / 1e6, Counter::kIsIterationInvariantRate);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  std::size_t triangles = 2'000'000;
  bool keep = false;
  for (int i = 1; i < argc; ++i) {
    const std::string argument = argv[i];
    if (argument.rfind("--triangles=", 0) == 0) {
      triangles = std::stoull(argument.substr(12));
    } else if (argument == "--keep") {
      keep = true;
    } else {
      std::fprintf(stderr, "unknown argument '%s' (use --triangles=N, --keep, --benchmark_*)\n",
                   argument.c_str());
      return 2;
    }
  }
  const auto n = static_cast<std::size_t>(std::ceil(std::sqrt(double(triangles) / 2.0)));
  const auto folder = std::filesystem::temp_directory_path() /
                      ("tetrapage_bench_formats_" + std::to_string(::getpid()));
  std::filesystem::create_directories(folder);

  const auto start = std::chrono::steady_clock::now();
  {
    const TriangleSoup grid = grid_surface(n);
    for (const char* name : {"grid.obj", "grid.stl", "grid.ply", "grid.off", "grid.glb"})
      tetrapage::write_mesh(folder / name, grid);
    write_ascii_ply(folder / "grid_ascii.ply", grid);
    write_ascii_stl(folder / "grid_ascii.stl", grid);
    std::fprintf(stderr, "generated a %zu x %zu grid (%zu triangles) in %s in %.1f s\n", n, n,
                 grid.triangle_count(), folder.c_str(),
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }

  struct Case {
    const char* name;
    const char* file;
    bool assimp;
  };
  const Case cases[] = {
      {"read/ours/obj", "grid.obj", false},
      {"read/ours/stl_binary", "grid.stl", false},
      {"read/ours/stl_ascii", "grid_ascii.stl", false},
      {"read/ours/ply_binary", "grid.ply", false},
      {"read/ours/ply_ascii", "grid_ascii.ply", false},
      {"read/ours/off", "grid.off", false},
      {"read/ours/glb", "grid.glb", false},
      {"read/assimp/obj", "grid.obj", true},
      {"read/assimp/stl_binary", "grid.stl", true},
      {"read/assimp/stl_ascii", "grid_ascii.stl", true},
      {"read/assimp/ply_binary", "grid.ply", true},
      {"read/assimp/ply_ascii", "grid_ascii.ply", true},
      {"read/assimp/off", "grid.off", true},
      {"read/assimp/glb", "grid.glb", true},
  };
  for (const Case& c : cases) {
    const auto path = folder / c.file;
    const bool assimp = c.assimp;
    benchmark::RegisterBenchmark(
        c.name, [path, assimp](benchmark::State& state) { read_benchmark(state, path, assimp); })
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime()
        ->MinTime(1.0);
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  if (!keep) std::filesystem::remove_all(folder);
  return 0;
}
