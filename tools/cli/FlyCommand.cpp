// `tetrapage fly`: fly a pose file through an index with the paged runtime.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <future>
#include <limits>
#include <optional>

#include "Commands.h"
#include "FlyArguments.h"
#include "TessellationArguments.h"
#include "tetrapage/formats/base/ByteSize.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/MemoryUsage.h"
#include "tetrapage/formats/base/Progress.h"
#include "tetrapage/formats/index/IndexHeader.h"
#include "tetrapage/formats/index/IndexReader.h"
#include "tetrapage/formats/mesh/Manifest.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/tools/AnswerCheck.h"
#include "tetrapage/tools/AnswerFile.h"
#include "tetrapage/tools/ContactFile.h"
#include "tetrapage/tools/LatencySummary.h"
#include "tetrapage/tools/QueryAnswerFile.h"
#include "tetrapage/tools/StepTotals.h"

namespace tetrapage::cli {

TriangleSoup load_object(const FlyArguments& args, const std::filesystem::path& path) {
  std::vector<ReadReport> reports;
  TriangleSoup object = load_inputs({path}, &reports, Progress::silent(), args.tessellation.options(false));
  std::string unit = is_manifest_path(path) ? read_manifest(path).units
                                                   : (reports.empty() ? std::string() : reports.front().length_unit);
  if (!args.object_unit.empty()) {
    metres_per_unit(args.object_unit);  // an unknown unit is an InputError naming it
    if (!unit.empty() && unit != args.object_unit)
      throw InputError("--object-unit " + args.object_unit + ", but " + path.string() + " is in " + unit);
    unit = args.object_unit;
  }
  const std::string index_unit = IndexReader(args.index).header().length_unit;
  double scale = args.object_scale;
  if (!unit.empty() && !index_unit.empty()) {
    scale *= metres_per_unit(unit) / metres_per_unit(index_unit);
  } else if (unit != index_unit) {
    std::fprintf(stderr, "fly: the object is in %s and the index in %s: the object is taken in the index's units\n",
                 unit.empty() ? "unstated units" : unit.c_str(), index_unit.empty() ? "unstated units" : index_unit.c_str());
  }
  if (!(scale > 0) || !std::isfinite(scale)) throw InputError("--object-scale must be a positive number");
  if (scale != 1.0)
    for (Vec3& v : object.vertices)
      for (double& c : v) c *= scale;
  return object;
}

std::shared_ptr<const DynamicObstacles> load_obstacles(const FlyArguments& args,
                                                        const std::shared_ptr<const CollisionIndex>& index) {
  if (args.obstacles.empty()) return nullptr;
  return std::make_shared<const DynamicObstacles>(DynamicObstacles::load(index, args.obstacles));
}

CollisionIndexOptions fly_index_options(const FlyArguments& args) {
  CollisionIndexOptions index_options;
  index_options.memory_budget_bytes = parse_byte_size(args.memory);
  index_options.prefetch = !args.no_prefetch;
  index_options.prefetch_ahead = args.prefetch_ahead;
  index_options.shard_arena = !args.no_shard_arena;
  index_options.spin_before_sleep = std::chrono::microseconds(args.spin_before_sleep_us);
  return index_options;
}

namespace {

// One step of the query --query names, its answer row, and what its summary counts.
class QueryStep {
 public:
  QueryStep(const FlyArguments& args, const QueryOptions& options, const CollisionIndex& index)
      : query_(parse_fly_query(args.query)), options_(options) {
    if (!args.contacts.empty() && (query_ == FlyQuery::distance || query_ == FlyQuery::time_of_impact))
      throw UsageError(
          std::string("fly: --contacts lists a collision query's contacts, not --query ") +
          args.query);
    if (query_ == FlyQuery::contacts) options_.mode = QueryMode::all_contacts;
    distance_options_.max_distance = args.max_distance;
    impact_options_.tolerance = args.toi_tolerance;
    if (query_ != FlyQuery::collide && !args.answers.empty()) answers_.emplace(args.answers, query_, index);
  }
  FlyQuery query() const { return query_; }
  /// Whether the object collides at step i (touches; for toi, during the motion to pose i).
  bool run(FlyingObject& object, std::span<const Pose> poses, std::size_t i) {
    switch (query_) {
      case FlyQuery::distance:
        object.distance(poses[i], distance_options_, distance_);
        ++separations_[int(distance_.separation)];
        if (answers_) answers_->write_distance(i, object, distance_);
        return distance_.separation == Separation::touching;
      case FlyQuery::time_of_impact:
        impact_ = i == 0 ? object.time_of_impact(poses[0], poses[0], impact_options_)
                         : object.time_of_impact(poses[i - 1], poses[i], impact_options_);
        ++impacts_[int(impact_.impact)];
        iterations_ += impact_.iterations;
        if (answers_) answers_->write_impact(i, object, impact_);
        return impact_.impact == Impact::hit;
      case FlyQuery::contacts:
      case FlyQuery::collide:
        break;
    }
    object.query(poses[i], options_, result);
    if (answers_) answers_->write_contacts(i, object, result);
    return result.collides;
  }
  /// The collision query's last result (collide and contacts).
  QueryResult result;
  void commit() {
    if (answers_) answers_->commit();
  }
  /// What the summary and the report add for this query.
  std::string summary(std::size_t steps) const {
    char text[200] = "";
    if (query_ == FlyQuery::distance)
      std::snprintf(text, sizeof text, "distance: %llu touching, %llu apart, %llu farther than --max-distance",
                    (unsigned long long)separations_[0], (unsigned long long)separations_[1],
                    (unsigned long long)separations_[2]);
    else if (query_ == FlyQuery::time_of_impact)
      std::snprintf(text, sizeof text, "time of impact: %llu hits, %llu free motions, %llu unresolved; %.1f distance queries per step",
                    (unsigned long long)impacts_[1], (unsigned long long)impacts_[0],
                    (unsigned long long)impacts_[2], double(iterations_) / double(std::max<std::size_t>(1, steps)));
    return text;
  }
  /// Whether each step runs the collision query, whose result, contacts and counters the
  /// summary adds up (distance and toi answer through their own results).
  bool collision_query() const {
    return query_ == FlyQuery::collide || query_ == FlyQuery::contacts;
  }
  /// The report's figures of distance and toi (null for the collision queries, which have none).
  nlohmann::json report() const {
    if (query_ == FlyQuery::distance)
      return {{"touching", separations_[0]}, {"apart", separations_[1]}, {"farther", separations_[2]}};
    if (query_ == FlyQuery::time_of_impact)
      return {{"hits", impacts_[1]}, {"none", impacts_[0]}, {"unresolved", impacts_[2]}, {"distance_queries", iterations_}};
    return nullptr;
  }

 private:
  FlyQuery query_;
  QueryOptions options_;
  DistanceOptions distance_options_;
  ImpactOptions impact_options_;
  DistanceResult distance_;
  ImpactResult impact_;
  std::optional<QueryAnswerFile> answers_;
  std::uint64_t separations_[3] = {0, 0, 0};
  std::uint64_t impacts_[3] = {0, 0, 0};
  std::uint64_t iterations_ = 0;
};

// What a flight holds beside its shards, from three readings of the resident set: before any
// work (libraries, threads), once the index and the object are open (the coarse mesh and its
// tables, the object's BVH and grid), and the peak.
struct ResidentBesideShards {
  std::uint64_t at_start = resident_bytes();
  std::uint64_t opened = 0;
  // The resident set once `index` is open, less the shard arena's pages populated ahead so
  // far: those hold shards later, and are counted with them.
  void note_opened(const CollisionIndex& index) {
    const ShardArena* arena = index.shard_arena();
    const std::uint64_t populated = arena != nullptr ? arena->resident_bytes() : 0;
    const std::uint64_t now = resident_bytes();
    opened = now > populated ? now - populated : 0;
  }
  std::uint64_t promised(std::uint64_t budget) const { return budget + at_start + kRuntimeOverheadAllowance; }
  // One line: the peak, what it is made of, and whether the promise held.
  std::string statement(std::uint64_t peak, std::uint64_t shards, std::uint64_t budget) const {
    const std::uint64_t tables = opened > at_start ? opened - at_start : 0;
    const std::uint64_t counted = at_start + tables + shards;
    std::string text = "memory: peak RSS " + format_byte_size(peak) + " = before any work (libraries, threads) " +
                       format_byte_size(at_start) + " + index tables and object " + format_byte_size(tables) +
                       " + shards " + format_byte_size(shards) + " + the rest " +
                       format_byte_size(peak > counted ? peak - counted : 0) + "; --memory + " +
                       format_byte_size(at_start) + " + " + format_byte_size(kRuntimeOverheadAllowance) + " = " +
                       format_byte_size(promised(budget));
    return text.append(peak <= promised(budget) ? ": kept"
                                                 : ": exceeded by " + format_byte_size(peak - promised(budget)));
  }
  void add_to(nlohmann::json& report, std::uint64_t peak, std::uint64_t budget) const {
    report["resident_at_start_bytes"] = at_start;
    report["resident_after_open_bytes"] = opened;
    report["promised_peak_bytes"] = promised(budget);
    report["promise_exceeded_bytes"] = peak > promised(budget) ? peak - promised(budget) : 0;
  }
};

void run_fly(const FlyArguments& args) {
  // The object's reader's libraries (the CAD module) are the process's own, as the others are.
  load_readers_for(args.objects);
  ResidentBesideShards memory;
  if (args.objects.size() != args.paths.size())
    throw UsageError("fly: " + std::to_string(args.objects.size()) + " --object but " +
                     std::to_string(args.paths.size()) + " --path: give one pose file per object");
  if (args.objects.size() > 1) return run_fly_group(args);
  check_outputs_writable({args.answers, args.report, args.contacts},
                         {args.index, args.objects[0], args.paths[0], args.check, args.obstacles});
  QueryOptions query_options;
  query_options.accuracy = geometry::parse_accuracy(args.accuracy);
  query_options.mode = args.all_contacts ? QueryMode::all_contacts : QueryMode::first_hit;
  query_options.max_contacts = args.max_contacts;
  const CollisionIndexOptions index_options = fly_index_options(args);

  TriangleSoup object_mesh = load_object(args, args.objects[0]);
  const std::vector<Pose> poses = read_poses(args.paths[0]);
  AnswerCheck check(args.check, poses.size(), "fly");
  const auto open_start = std::chrono::steady_clock::now();
  // The object's structures do not need the index: build them while it opens (the model keeps
  // the mesh: no second copy).
  auto model = std::async(std::launch::async,
                          [&] { return std::make_shared<const ObjectModel>(std::move(object_mesh)); });
  auto index = std::make_shared<const CollisionIndex>(args.index, index_options);
  FlyingObject object(index, model.get());
  object.set_obstacles(load_obstacles(args, index));
  memory.note_opened(*index);
  std::optional<ContactFile> contact_file;
  if (!args.contacts.empty()) contact_file.emplace(args.contacts, *index);
  double preload_seconds = 0;
  if (args.preload) {
    if (index->total_shard_bytes() > index_options.memory_budget_bytes)
      throw InputError("--preload: the index's " + format_byte_size(index->total_shard_bytes()) +
                       " of shards do not fit --memory " + args.memory);
    const auto preload_start = std::chrono::steady_clock::now();
    Progress loading("preloading shards", index->shard_count());
    index->preload([&](std::uint32_t) { loading.advance(); });
    loading.finish();
    preload_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - preload_start).count();
    index->cache().reset_counters();
  }
  QueryStep step(args, query_options, *index);
  const QueryResult& result = step.result;
  double first_answer_seconds = 0;

  std::vector<std::uint8_t> answers(poses.size());
  std::vector<double> seconds(poses.size());
  std::uint64_t collisions = 0, outside = 0, contacts = 0, containments = 0;
  StepTotals totals;
  Progress progress("flying", poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const auto start = std::chrono::steady_clock::now();
    answers[i] = step.run(object, poses, i) ? 1 : 0;
    const auto end = std::chrono::steady_clock::now();
    seconds[i] = std::chrono::duration<double>(end - start).count();
    if (i == 0) first_answer_seconds = std::chrono::duration<double>(end - open_start).count() - preload_seconds;
    collisions += answers[i];
    containments += result.containment != Containment::none ? 1 : 0;
    contacts += result.contacts.size();
    outside += result.outside_model ? 1 : 0;
    totals.add(result.counters);
    check.record(i, answers[i]);
    if (contact_file) contact_file->write_step(i, object, result);
    progress.advance();
  }
  progress.finish();
  double total = 0;
  for (double s : seconds) total += s;
  const double steps_per_second = total > 0 ? double(poses.size()) / total : 0;
  const auto latency = LatencySummary::of(seconds);
  const ShardCacheCounters cache = index->cache().counters();
  const double lookups = double(cache.hits + cache.misses);
  const double hit_rate = lookups > 0 ? double(cache.hits) / lookups : 1.0;
  const double steps = std::max<double>(1, double(poses.size()));
  const std::string by_containment =
      step.collision_query()
          ? " (" + std::to_string(containments) + " by containment: one body inside the other)"
          : "";
  std::printf("fly (%s, %s, %s): %zu steps, %llu collisions%s%s\n", fly_query_name(step.query()),
              args.accuracy.c_str(), args.no_prefetch ? "no prefetch" : "prefetch", poses.size(),
              (unsigned long long)collisions, by_containment.c_str(),
              index->has_interiors()
                  ? ""
                  : "; the index has no interiors: objects inside obstacles go unseen");
  std::printf("%s\n", storage_statement(index->header()).c_str());
  std::printf("%.0f steps/s, latency p50 %.1f us, p95 %.1f us, p99 %.1f us, max %.1f us; open to first answer %.1f ms\n",
              steps_per_second, latency.p50_us, latency.p95_us, latency.p99_us, latency.max_us,
              first_answer_seconds * 1e3);
  std::printf("shards: peak resident %s of budget %s (index shards %s), page-ins %llu (%s read), hit rate %.4f, "
              "page-in p50 %.0f us p99 %.0f us\n",
              format_byte_size(cache.peak_resident_bytes).c_str(), format_byte_size(index_options.memory_budget_bytes).c_str(),
              format_byte_size(index->total_shard_bytes()).c_str(), (unsigned long long)cache.page_ins,
              format_byte_size(cache.bytes_loaded).c_str(), hit_rate, cache.page_in_p50_us, cache.page_in_p99_us);
  if (step.collision_query()) std::printf("%s\n", totals.statement().c_str());
  const std::uint64_t peak_rss = peak_resident_bytes();
  std::printf("peak RSS %s\n%s\n", format_byte_size(peak_rss).c_str(),
              memory.statement(peak_rss, cache.peak_resident_bytes, index_options.memory_budget_bytes).c_str());
  if (const std::string summary = step.summary(poses.size()); !summary.empty()) std::printf("%s\n", summary.c_str());
  if (step.query() == FlyQuery::collide && !args.answers.empty()) write_answers(args.answers, answers);
  step.commit();
  if (contact_file) {
    contact_file->commit();
    std::printf("contacts: %llu rows written to %s\n", (unsigned long long)contact_file->rows(), args.contacts.c_str());
  }
  if (!args.report.empty()) {
    // Keys about a feature the run did not use are left out, not written as zeros.
    nlohmann::json report{
        {"command", "fly"},
        {"index", args.index.string()},
        {"accuracy", args.accuracy},
        {"query", fly_query_name(step.query())},
        {"prefetch", !args.no_prefetch},
        {"shard_arena", !args.no_shard_arena},
        {"spin_before_sleep_us", args.spin_before_sleep_us},
        {"preloaded", args.preload},
        {"steps", poses.size()},
        {"collisions", collisions},
        {"index_has_interiors", index->has_interiors()},
        {"precision", index->header().precision},
        {"answers_exact_for", index->header().precision == "float" ? "rounded model" : "input"},
        {"steps_per_second", steps_per_second},
        {"latency_us", latency.to_json()},
        {"open_to_first_answer_ms", first_answer_seconds * 1e3},
        {"budget_bytes", index_options.memory_budget_bytes},
        {"index_shard_bytes", index->total_shard_bytes()},
        {"peak_resident_shard_bytes", cache.peak_resident_bytes},
        {"peak_rss_bytes", peak_rss},
        {"page_ins", cache.page_ins},
        {"bytes_read", cache.bytes_loaded},
        {"bytes_read_per_step", double(cache.bytes_loaded) / steps},
        {"cache_hit_rate", hit_rate},
        {"page_in_latency_us",
         {{"p50", cache.page_in_p50_us},
          {"p99", cache.page_in_p99_us},
          {"max", cache.page_in_max_us}}}};
    if (index->header().precision == "float")
      report["max_rounding_distance"] = index->header().max_rounding_distance;
    if (!args.no_prefetch) {
      report["prefetch_ahead"] = args.prefetch_ahead;
      report["prefetch_loads"] = cache.prefetch_loads;
      report["prefetch_hits"] = cache.prefetch_hits;
    }
    if (args.preload) report["preload_seconds"] = preload_seconds;
    if (const ShardArena* arena = index->shard_arena())
      report["shard_arena_blocks"] = {{"frontier_bytes", arena->frontier_bytes()},
                                      {"resident_bytes", arena->resident_bytes()},
                                      {"from_range", arena->arena_blocks()},
                                      {"from_malloc", arena->upstream_blocks()}};
    memory.add_to(report, peak_rss, index_options.memory_budget_bytes);
    if (step.collision_query()) {
      report["containments"] = containments;
      report["contacts"] = contacts;
      report["steps_outside_model"] = outside;
      totals.add_to(report);
    } else {
      report["query_answers"] = step.report();
    }
    if (contact_file) report["contact_rows_written"] = contact_file->rows();
    if (const auto& obstacles = object.obstacles())
      report["obstacles"] = {{"dynamic_parts", obstacles->size()},
                             {"hidden_index_parts", obstacles->hidden_parts().size()}};
    if (check.checking()) report["disagreements"] = check.disagreements();
    write_report(args.report, report);
  }
  check.finish();
}

// An option of one query given with another would change nothing: a mistake, not a no-op.
void refuse_options_of_other_queries(const FlyArguments& args, const CLI::Option& max_distance,
                                     const CLI::Option& toi_tolerance) {
  const FlyQuery query = parse_fly_query(args.query);
  if (max_distance.count() > 0 && query != FlyQuery::distance)
    throw UsageError("fly: --max-distance applies to --query distance, not to --query " +
                     args.query);
  if (toi_tolerance.count() > 0 && query != FlyQuery::time_of_impact)
    throw UsageError("fly: --toi-tolerance applies to --query toi, not to --query " + args.query);
}

}  // namespace

void add_fly_command(CLI::App& app) {
  auto args = std::make_shared<FlyArguments>();
  auto* command = app.add_subcommand(
      "fly",
      "Fly a pose file through an index with the paged runtime: shards are paged in around the\n"
      "object under --memory, and every pose is answered. Prints steps per second, latency\n"
      "percentiles, page-ins, the cache hit rate and the collisions.");
  command->add_option("index", args->index, "Index file (.tpi) from `tetrapage preprocess`")
      ->required()
      ->check(existing_file_check());
  command
      ->add_option(
          "--object", args->objects,
          "Flying object: a mesh, a STEP or IGES file (read in mm), or a manifest (.json); "
          "converted "
          "to the index's unit when both state theirs. Repeat it, with one --path each, to fly "
          "several objects at once (each against the environment and against each other; --query "
          "collide only)")
      ->required()
      ->check(existing_file_check());
  command
      ->add_option(
          "--object-unit", args->object_unit,
          "Unit of an object file that states none (plain meshes): m, cm, mm, um, in or ft")
      ->check(parsed_by([](const std::string& unit) { metres_per_unit(unit); }, "UNIT"));
  command
      ->add_option("--object-scale", args->object_scale,
                   "Scale applied to the object after the unit conversion")
      ->capture_default_str()
      ->check(positive_number_check(1e12));
  args->tessellation.add_to(command);
  command->add_option("--contacts", args->contacts,
                      "Write the contacts as CSV, one row per contact and per containment: step, kind "
                      "(surface, near under clearance:D, object_inside, obstacle_inside), the environment "
                      "part and the object's part (id, name, instance path), both triangles, the point on "
                      "each side (the first contact of a step; every pair with --all-contacts; the columns "
                      "of every answer file: docs/USAGE.md, \"Answer files\")");
  command
      ->add_option("--path", args->paths,
                   "Pose file (CSV tx,ty,tz,qw,qx,qy,qz); one per --object, in order")
      ->required()
      ->check(existing_file_check());
  add_memory_option(
      command, args->memory,
      "Budget of the decoded shards held in memory; one above the index's shards costs no more");
  command
      ->add_option("--accuracy", args->accuracy,
                   "exact, double_eps, float_eps (optionally :EPSILON) or clearance:D")
      ->capture_default_str()
      ->check(parsed_by([](const std::string& text) { geometry::parse_accuracy(text); }, "MODE"));
  command->add_flag("--all-contacts", args->all_contacts, "Collect every contact pair, not only the first hit");
  command
      ->add_option("--max-contacts", args->max_contacts,
                   "The most contact pairs one step may collect (--all-contacts, --query contacts): a "
                   "step that finds more fails, naming the limit")
      ->capture_default_str()
      ->check(whole_number_check(1, 1'000'000'000));
  command->add_flag("--no-prefetch", args->no_prefetch, "Disable the background prefetcher");
  command->add_flag("--prefetch-ahead", args->prefetch_ahead,
                    "Also prefetch the next region along the motion at each region change (a walk and a box "
                    "search on the flying thread; pays where page-ins wait for a disk)");
  command->add_flag("--no-shard-arena", args->no_shard_arena,
                    "Decode shards into malloc's memory instead of the arena whose pages a background "
                    "thread faults in ahead of use");
  command
      ->add_option(
          "--spin-before-sleep", args->spin_before_sleep_us,
          "Microseconds a wait between the flying thread and the prefetcher polls before it "
          "sleeps (0: sleep at once; polling keeps the prefetch thread's core busy)")
      ->capture_default_str()
      ->check(whole_number_check(0, 1'000'000));
  command->add_flag("--preload", args->preload,
                    "Load every shard before the first step (needs --memory of at least the index's shards): "
                    "the all-resident reference; open-to-first-answer then excludes the preload");
  command
      ->add_option(
          "--query", args->query,
          "What each step asks: collide (does the object touch?), contacts (every contact pair "
          "with "
          "where the triangles meet and their normals), distance (the distance and closest points, "
          "0 when touching), toi (the first time of contact during the motion from the previous "
          "pose, "
          "translation linear and rotation by slerp)")
      ->capture_default_str()
      ->check(CLI::IsMember({"collide", "contacts", "distance", "toi"}));
  auto* max_distance = command
                           ->add_option("--max-distance", args->max_distance,
                                        "--query distance: distances beyond this (index units) are "
                                        "answered only as 'farther' "
                                        "(cheap in free space); default: measure any distance")
                           ->check(number_check(0, kLongestLength));
  auto* toi_tolerance = command
                            ->add_option("--toi-tolerance", args->toi_tolerance,
                                         "--query toi: the width of the certified bracket of the "
                                         "contact time, in the motion's time "
                                         "[0, 1] between two poses")
                            ->capture_default_str()
                            ->check(positive_number_check(1));
  command
      ->add_option("--obstacles", args->obstacles,
                   "Dynamic obstacles saved beside the index (DynamicObstacles::save, "
                   "tetrapage_obstacles_save): "
                   "their parts count as obstacles, the index parts they hide do not")
      ->check(existing_file_check());
  command->add_option("--answers", args->answers,
                      "Write the answers as CSV: step,collides for --query collide; one row per contact, or per "
                      "step with the distance or the time of impact, for the other queries (docs/USAGE.md)");
  command
      ->add_option("--check", args->check,
                   "Compare with these answers; exit non-zero on any disagreement")
      ->check(existing_file_check());
  command->add_option("--report", args->report, "Write figures as JSON");
  command->callback([args, max_distance, toi_tolerance] {
    refuse_options_of_other_queries(*args, *max_distance, *toi_tolerance);
    run_fly(*args);
  });
}

}  // namespace tetrapage::cli
