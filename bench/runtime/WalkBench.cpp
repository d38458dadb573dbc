// Point location by straight-line walking and the breadth-first box search, in the Delaunay
// mesh of 100k random sites in the unit cube (plus the corners of the cube enlarged by 0.05,
// as the preprocess builds it). Counters:
//  faces_per_walk        faces crossed per walk
//  faces_per_unit        faces crossed per unit of walked length (the stabbing number)
//  walk_steps_per_second faces crossed per second
//  tets_found, tets_visited, exact_tests   per box search
//
// Short walks follow an object step: from the tet found for the previous position to a point
// 0.005 away (the runtime's step 2). Long walks go from a random tet's reference point to a
// random point of the cube.

#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "tetrapage/preprocess/CoarseMesh.h"
#include "tetrapage/runtime/paging/BoxSearch.h"
#include "tetrapage/runtime/query/MeshWalk.h"

namespace {

using namespace tetrapage;
using geometry::Point;

constexpr std::size_t kSites = 100000;
constexpr std::size_t kQueries = 4096;

const TetMesh& mesh() {
  static const TetMesh built = [] {
    std::mt19937_64 random(2024);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::vector<Vec3> sites;
    for (std::size_t i = 0; i < kSites; ++i) sites.push_back({unit(random), unit(random), unit(random)});
    for (int c = 0; c < 8; ++c)
      sites.push_back({c & 1 ? 1.05 : -0.05, c & 2 ? 1.05 : -0.05, c & 4 ? 1.05 : -0.05});
    return build_coarse_mesh(sites);
  }();
  return built;
}

double distance(const Point& a, const Point& b) {
  return std::hypot(b[0] - a[0], b[1] - a[1], b[2] - a[2]);
}

// A random walk with steps of length `step`, reflected into [0, 1]^3.
std::vector<Point> trajectory(double step, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> normal;
  std::vector<Point> points{{0.5, 0.5, 0.5}};
  while (points.size() < kQueries) {
    Point d{normal(random), normal(random), normal(random)};
    const double n = std::hypot(d[0], d[1], d[2]);
    Point p = points.back();
    for (int k = 0; k < 3; ++k) {
      p[k] += step * d[k] / n;
      if (p[k] < 0) p[k] = -p[k];
      if (p[k] > 1) p[k] = 2 - p[k];
    }
    points.push_back(p);
  }
  return points;
}

void BM_WalkShortObjectSteps(benchmark::State& state) {
  const TetMesh& m = mesh();
  const auto points = trajectory(0.005, 7);
  std::uint32_t tet = locate_point(m, 0, points[0]).tet;
  std::uint64_t faces = 0, walks = 0;
  // Back and forth along the trajectory, so that every walk is one object step.
  std::size_t i = 0;
  std::ptrdiff_t direction = 1;
  for (auto _ : state) {
    if (i + 1 == points.size()) direction = -1;
    if (i == 0) direction = 1;
    i = std::size_t(std::ptrdiff_t(i) + direction);
    const WalkResult r = locate_point(m, tet, points[i]);
    benchmark::DoNotOptimize(r);
    tet = r.tet;
    faces += r.tets_crossed;
    ++walks;
  }
  state.SetItemsProcessed(std::int64_t(walks));
  state.counters["faces_per_walk"] = double(faces) / double(walks);
  state.counters["walk_steps_per_second"] = benchmark::Counter(double(faces), benchmark::Counter::kIsRate);
  state.counters["tets"] = double(m.tet_count());
}
BENCHMARK(BM_WalkShortObjectSteps);

void BM_WalkLong(benchmark::State& state) {
  const TetMesh& m = mesh();
  std::mt19937_64 random(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<std::uint32_t> starts;
  std::vector<Point> targets;
  std::vector<double> lengths;
  for (std::size_t q = 0; q < kQueries; ++q) {
    starts.push_back(std::uint32_t(random() % m.tet_count()));
    targets.push_back({unit(random), unit(random), unit(random)});
    lengths.push_back(distance(*walk_reference_point(m, starts.back()), targets.back()));
  }
  std::uint64_t faces = 0, walks = 0;
  double length = 0;
  std::size_t i = 0;
  for (auto _ : state) {
    const WalkResult r = locate_point(m, starts[i], targets[i]);
    benchmark::DoNotOptimize(r);
    faces += r.tets_crossed;
    length += lengths[i];
    ++walks;
    if (++i == kQueries) i = 0;
  }
  state.SetItemsProcessed(std::int64_t(walks));
  state.counters["faces_per_walk"] = double(faces) / double(walks);
  state.counters["faces_per_unit"] = double(faces) / length;
  state.counters["walk_steps_per_second"] = benchmark::Counter(double(faces), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_WalkLong);

void BM_BoxSearch(benchmark::State& state) {
  const TetMesh& m = mesh();
  const double side = double(state.range(0)) / 1000;
  std::mt19937_64 random(13);
  std::uniform_real_distribution<double> unit(0.0, 1.0 - side);
  std::vector<geometry::Box> boxes;
  std::vector<std::uint32_t> starts;
  for (std::size_t q = 0; q < kQueries; ++q) {
    geometry::Box box;
    box.lo = {unit(random), unit(random), unit(random)};
    box.hi = {box.lo[0] + side, box.lo[1] + side, box.lo[2] + side};
    boxes.push_back(box);
    starts.push_back(locate_point(m, 0, box.lo).tet);  // the runtime has it from step 2
  }
  BoxSearchScratch scratch;
  std::uint64_t found = 0, visited = 0, exact = 0, searches = 0;
  std::size_t i = 0;
  for (auto _ : state) {
    const BoxSearchResult r = tets_overlapping_box(m, starts[i], boxes[i], scratch);
    benchmark::DoNotOptimize(r);
    found += r.tets.size();
    visited += r.tets_visited;
    exact += r.exact_tests;
    ++searches;
    if (++i == kQueries) i = 0;
  }
  state.SetItemsProcessed(std::int64_t(searches));
  state.counters["tets_found"] = double(found) / double(searches);
  state.counters["tets_visited"] = double(visited) / double(searches);
  state.counters["exact_tests"] = double(exact) / double(searches);
}
BENCHMARK(BM_BoxSearch)->Arg(50)->Arg(10);

}  // namespace

BENCHMARK_MAIN();
