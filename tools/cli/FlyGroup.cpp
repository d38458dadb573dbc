// `tetrapage fly` with several objects: an ObjectGroup step per pose, each object against the
// environment and against the others.

#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "Commands.h"
#include "FlyArguments.h"
#include "tetrapage/formats/base/ByteSize.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/MemoryUsage.h"
#include "tetrapage/formats/base/Progress.h"
#include "tetrapage/runtime/query/ObjectGroup.h"
#include "tetrapage/tools/CsvFile.h"
#include "tetrapage/tools/LatencySummary.h"
#include "tetrapage/tools/QueryAnswerFile.h"

namespace tetrapage::cli {
namespace {

// The options one object alone would take that a group does not.
void refuse_single_object_options(const FlyArguments& args) {
  if (parse_fly_query(args.query) != FlyQuery::collide)
    throw UsageError(
        "fly: several objects answer --query collide only (contacts, distance and toi take one "
        "object)");
  if (!args.contacts.empty()) throw UsageError("fly: --contacts takes one object");
  if (!args.check.empty()) throw UsageError("fly: --check takes one object");
  if (args.preload) throw UsageError("fly: --preload takes one object");
  // The objects are tested against each other exactly: another accuracy would hold against the
  // environment only, and the answers would mix two rules.
  if (geometry::parse_accuracy(args.accuracy).mode != geometry::AccuracyMode::exact)
    throw UsageError(
        "fly: several objects are tested against each other exactly, not with --accuracy " +
        args.accuracy + "; fly them one at a time");
}

// The flights, one per object, all as long as the first.
std::vector<std::vector<Pose>> read_flights(const FlyArguments& args) {
  std::vector<std::vector<Pose>> flights;
  for (const auto& path : args.paths) {
    flights.push_back(read_poses(path));
    if (flights.back().size() != flights.front().size())
      throw InputError("fly: " + path.string() + " holds " + std::to_string(flights.back().size()) + " poses but " +
                       args.paths.front().string() + " holds " + std::to_string(flights.front().size()) +
                       ": the objects' flights must be as long");
  }
  return flights;
}

// The answer rows of a step: per object, whether it collides, with the environment and with
// which other objects.
void write_step(CsvFile& file, std::size_t step, const GroupResult& result, std::size_t objects) {
  std::vector<std::string> others(objects);
  for (const CollidingPair& pair : result.pairs) {
    others[pair.first] += (others[pair.first].empty() ? "" : ";") + std::to_string(pair.second);
    others[pair.second] += (others[pair.second].empty() ? "" : ";") + std::to_string(pair.first);
  }
  for (std::size_t k = 0; k < objects; ++k) {
    const bool environment = result.environment[k].collides;
    const bool collides = environment || !others[k].empty();
    file.row(std::to_string(step) + ',' + std::to_string(k) + ',' + (collides ? '1' : '0') + ',' +
             (environment ? '1' : '0') + ',' + others[k]);
  }
}

}  // namespace

void run_fly_group(const FlyArguments& args) {
  refuse_single_object_options(args);
  std::vector<std::filesystem::path> inputs{args.index};
  inputs.insert(inputs.end(), args.objects.begin(), args.objects.end());
  inputs.insert(inputs.end(), args.paths.begin(), args.paths.end());
  if (!args.obstacles.empty()) inputs.push_back(args.obstacles);
  const std::filesystem::path outputs[] = {args.answers, args.report};
  check_outputs_writable(outputs, inputs);
  GroupQueryOptions options;
  options.environment.accuracy = geometry::parse_accuracy(args.accuracy);
  options.environment.mode = args.all_contacts ? QueryMode::all_contacts : QueryMode::first_hit;
  options.pair_mode = options.environment.mode;
  const CollisionIndexOptions index_options = fly_index_options(args);
  std::vector<std::shared_ptr<const ObjectModel>> models;
  for (const auto& path : args.objects) models.push_back(std::make_shared<const ObjectModel>(load_object(args, path)));
  const std::vector<std::vector<Pose>> flights = read_flights(args);
  auto index = std::make_shared<const CollisionIndex>(args.index, index_options);
  ObjectGroup group(index, models);
  group.set_obstacles(load_obstacles(args, index));
  std::optional<CsvFile> answers;
  if (!args.answers.empty())
    answers.emplace(args.answers, "step,object,collides,environment,objects");

  const std::size_t steps = flights.front().size();
  std::vector<Pose> poses(models.size());
  std::vector<double> seconds(steps);
  std::uint64_t environment_hits = 0, pair_hits = 0, steps_colliding = 0;
  GroupResult result;
  Progress progress("flying", steps);
  for (std::size_t i = 0; i < steps; ++i) {
    for (std::size_t k = 0; k < models.size(); ++k) poses[k] = flights[k][i];
    const auto start = std::chrono::steady_clock::now();
    group.step(poses, options, result);
    seconds[i] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::uint64_t hits = result.pairs.size();
    for (const QueryResult& environment : result.environment) hits += environment.collides ? 1 : 0;
    environment_hits += hits - result.pairs.size();
    pair_hits += result.pairs.size();
    steps_colliding += hits > 0 ? 1 : 0;
    if (answers) write_step(*answers, i, result, models.size());
    progress.advance();
  }
  progress.finish();
  double total = 0;
  for (const double s : seconds) total += s;
  const double steps_per_second = total > 0 ? double(steps) / total : 0;
  const auto latency = LatencySummary::of(seconds);
  std::printf("fly (%zu objects, %s): %zu steps, %llu with a collision; %llu object-environment and %llu object-object "
              "collisions\n",
              models.size(), args.accuracy.c_str(), steps, (unsigned long long)steps_colliding,
              (unsigned long long)environment_hits, (unsigned long long)pair_hits);
  std::printf("%.0f steps/s, latency p50 %.1f us, p95 %.1f us, p99 %.1f us, max %.1f us; peak RSS %s\n",
              steps_per_second, latency.p50_us, latency.p95_us, latency.p99_us, latency.max_us,
              format_byte_size(peak_resident_bytes()).c_str());
  if (answers) answers->commit();
  if (!args.report.empty())
    write_report(args.report, {{"command", "fly"},
                               {"index", args.index.string()},
                               {"objects", models.size()},
                               {"accuracy", args.accuracy},
                               {"query", "collide"},
                               {"steps", steps},
                               {"steps_with_collision", steps_colliding},
                               {"object_environment_collisions", environment_hits},
                               {"object_object_collisions", pair_hits},
                               {"steps_per_second", steps_per_second},
                               {"latency_us", latency.to_json()},
                               {"budget_bytes", index_options.memory_budget_bytes},
                               {"peak_rss_bytes", peak_resident_bytes()}});
}

}  // namespace tetrapage::cli
