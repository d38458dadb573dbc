// Where a flight's time goes, step by step: the index preloaded (everything in memory), the
// flight replayed --repeat times by one FlyingObject in exact mode, each step timed and sorted
// by what it did (docs/BENCHMARKS.md, "Where a step's time goes", quotes these tables):
//   searched      the box left the searched region: walk, box search, then the shards
//   no candidate  shards touched, but no triangle survived the box and own-frame tests
//   phase II      candidates tested exactly, and no contact
//   candidates    candidates, none of which needed a triangle pair test
//   collides      a contact or a containment
//   no shard      the box met no shard's reach
// With --answers, every repetition's answers are compared with the oracle's and the count of
// disagreements is printed (it should be 0); the exit status is 0 either way.
//
//   tetrapage_bench_steps INDEX OBJECT FLIGHT [--answers A.csv] [--repeat N] [--steps K]

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/runtime/paging/CollisionIndex.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/tools/AnswerFile.h"
#include "tetrapage/tools/LatencySummary.h"

namespace {

using namespace tetrapage;
using Clock = std::chrono::steady_clock;

enum Kind : std::size_t { searched, no_candidate, phase_two, candidates, collides, no_shard, kind_count };
constexpr std::array<const char*, kind_count> kKindNames{"searched",   "no candidate", "phase II",
                                                         "candidates", "collides",     "no shard"};

Kind kind_of(const QueryResult& result) {
  const StepCounters& c = result.counters;
  if (result.collides) return collides;
  if (c.searched) return searched;
  if (c.shards_touched == 0) return no_shard;
  if (c.candidates == 0) return no_candidate;
  return c.triangle_tests > 0 ? phase_two : candidates;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("Replays a flight with the whole index in memory and shows where its steps' time goes: the share "
               "of steps and of time by what a step did, the mean step of each kind, and the searches' counters");
  std::string index_path, object_path, flight_path, answers_path;
  std::size_t repeat = 5, limit = 0;
  app.add_option("index", index_path, "Index (.tpi)")->required()->check(CLI::ExistingFile);
  app.add_option("object", object_path, "Flying object mesh")->required()->check(CLI::ExistingFile);
  app.add_option("flight", flight_path, "Pose file (CSV tx,ty,tz,qw,qx,qy,qz)")->required()->check(CLI::ExistingFile);
  app.add_option("--answers", answers_path, "The oracle's answers (step,collides) to compare with")
      ->check(CLI::ExistingFile);
  app.add_option("--repeat", repeat, "Passes over the flight (the first one included)")->check(CLI::PositiveNumber);
  app.add_option("--steps", limit, "Only the first K poses (0: all)");
  CLI11_PARSE(app, argc, argv);
  try {
    CollisionIndexOptions options;
    options.memory_budget_bytes = std::uint64_t(1) << 40;  // nothing is ever evicted
    options.prefetch = false;
    auto index = std::make_shared<const CollisionIndex>(index_path, options);
    index->preload();
    std::vector<Pose> poses = read_poses(flight_path);
    if (limit > 0 && limit < poses.size()) poses.resize(limit);
    std::vector<std::uint8_t> expected;
    if (!answers_path.empty()) {
      expected = read_answers(answers_path);
      if (expected.size() < poses.size())
        throw InputError(answers_path + ": " + std::to_string(expected.size()) + " answers for " +
                         std::to_string(poses.size()) + " poses");
    }
    FlyingObject object(index, read_mesh(object_path));
    QueryResult result;
    std::array<double, kind_count> seconds{};
    std::array<std::size_t, kind_count> steps{};
    // Per kind, the runtime's own phase clocks (StepCounters), summed.
    enum Phase : std::size_t { locate, search, free_box, shard, test, interior, phase_count };
    constexpr std::array<const char*, phase_count> kPhaseNames{"locate", "search", "free box", "shards",
                                                               "phase I+II", "containment"};
    std::array<std::array<double, phase_count>, kind_count> phase_seconds{};
    std::array<std::uint64_t, kind_count> shards_touched{}, candidates{}, repeats{}, triangle_tests{}, free_box_found{},
        in_free_box{};
    std::vector<double> all;
    all.reserve(poses.size() * repeat);
    std::uint64_t tets_crossed = 0, tets_visited = 0, tets_overlapping = 0, searches = 0, disagreements = 0;
    double search_seconds = 0;  // the walk and the box search of the searching steps (their own clocks)
    for (std::size_t pass = 0; pass < repeat; ++pass)
      for (std::size_t i = 0; i < poses.size(); ++i) {
        const auto start = Clock::now();
        object.query(poses[i], {}, result);
        const double step = std::chrono::duration<double>(Clock::now() - start).count();
        const Kind kind = kind_of(result);
        seconds[kind] += step;
        ++steps[kind];
        all.push_back(step);
        const StepCounters& c = result.counters;
        const std::array<double, phase_count> phases{c.locate_seconds, c.search_seconds, c.free_box_seconds,
                                                     c.shard_seconds,  c.test_seconds,   c.interior_seconds};
        for (std::size_t p = 0; p < phase_count; ++p) phase_seconds[kind][p] += phases[p];
        shards_touched[kind] += c.shards_touched;
        candidates[kind] += c.candidates;
        repeats[kind] += c.repeats;
        triangle_tests[kind] += c.triangle_tests;
        free_box_found[kind] += c.found_free_box;
        in_free_box[kind] += c.in_free_box;
        tets_crossed += result.counters.tets_crossed;
        tets_visited += result.counters.tets_visited;
        tets_overlapping += result.counters.tets_overlapping;
        if (result.counters.searched) {
          ++searches;
          search_seconds += result.counters.search_seconds;
        }
        if (!expected.empty() && result.collides != (expected[i] != 0)) ++disagreements;
      }
    double total = 0;
    for (const double s : all) total += s;
    const LatencySummary latency = LatencySummary::of(all);
    std::printf("%zu steps (%zu passes of %zu poses), %.0f steps/s, p50 %.2f us, p95 %.2f us, p99 %.2f us\n",
                all.size(), repeat, poses.size(), double(all.size()) / total, latency.p50_us, latency.p95_us,
                latency.p99_us);
    std::printf("\n| step | share of steps | mean us | share of time |\n|---|---:|---:|---:|\n");
    for (std::size_t k = 0; k < kind_count; ++k)
      std::printf("| %s | %.2f %% | %.3f | %.1f %% |\n", kKindNames[k], 100.0 * double(steps[k]) / double(all.size()),
                  steps[k] > 0 ? 1e6 * seconds[k] / double(steps[k]) : 0.0, 100.0 * seconds[k] / total);
    // The phases' clocks leave out what runs between them (and a step in the free box reads none).
    std::printf("\nmean us of each phase by kind of step (the runtime's own clocks), and counters per step:\n\n| step |");
    for (const char* name : kPhaseNames) std::printf(" %s |", name);
    std::printf(" shards | candidates | repeats | triangle tests | found free box | in free box |\n|---|");
    for (std::size_t p = 0; p < phase_count + 6; ++p) std::printf("---:|");
    std::printf("\n");
    for (std::size_t k = 0; k < kind_count; ++k) {
      if (steps[k] == 0) continue;
      const double n = double(steps[k]);
      std::printf("| %s |", kKindNames[k]);
      for (std::size_t p = 0; p < phase_count; ++p) std::printf(" %.3f |", 1e6 * phase_seconds[k][p] / n);
      std::printf(" %.1f | %.1f | %.1f | %.1f | %.1f %% | %.1f %% |\n", double(shards_touched[k]) / n,
                  double(candidates[k]) / n, double(repeats[k]) / n, double(triangle_tests[k]) / n,
                  100.0 * double(free_box_found[k]) / n, 100.0 * double(in_free_box[k]) / n);
    }
    const double per_search = double(std::max<std::uint64_t>(1, searches));
    std::printf("\nper search: %.1f tets crossed by the walk, %.1f visited, %.1f kept, %.2f us for the box search "
                "and the shard list\n",
                double(tets_crossed) / per_search, double(tets_visited) / per_search,
                double(tets_overlapping) / per_search, 1e6 * search_seconds / per_search);
    if (!expected.empty()) std::printf("disagreements with %s: %llu\n", answers_path.c_str(), (unsigned long long)disagreements);
  } catch (const Error& e) {
    std::fprintf(stderr, "tetrapage_bench_steps: %s\n", e.what());
    return 1;
  }
  return 0;
}
