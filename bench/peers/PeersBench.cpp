// tetrapage_bench_peers: one flight replayed through FCL, Embree, CGAL's AABB tree and tetrapage's
// runtime (in memory and paged), single-threaded, each collider in a fresh process of its own
// so that its build time, resident memory and cold start are its own. Prints a Markdown table;
// --report writes the figures as JSON.
//
//   tetrapage_bench_peers SCENE OBJECT FLIGHT [ANSWERS.csv] [INDEX.tpi] [--memory 8M] [--report R.json]

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <oneapi/tbb/global_control.h>

#include "tetrapage/bench/BenchMachine.h"
#include "tetrapage/bench/CgalCollider.h"
#include "tetrapage/bench/EmbreePeerCollider.h"
#include "tetrapage/bench/FclCollider.h"
#include "tetrapage/bench/TetrapageCollider.h"
#include "tetrapage/formats/base/ByteSize.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/MemoryUsage.h"
#include "tetrapage/formats/base/Progress.h"
#include "tetrapage/formats/mesh/Manifest.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/tools/AnswerFile.h"
#include "tetrapage/tools/LatencySummary.h"
#include "tetrapage/tools/ReportFile.h"

extern char** environ;

namespace tetrapage {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// The colliders, by the names the command line and the report use.
const std::vector<std::string> kColliderNames = {"fcl",       "embree",          "cgal-surfaces", "cgal",
                                                 "tetrapage", "tetrapage-paged"};

struct Arguments {
  fs::path scene, object, flight, answers, index, report;
  std::vector<fs::path> optional_inputs;  // ANSWERS and INDEX, told apart by extension
  std::string memory;                     // empty: no paged run
  std::vector<std::string> colliders;     // empty: every one the inputs allow
  bool warmup = false;
  bool prefetch = false;
  // A child process: run this one collider and write its figures into `output`.
  std::string run_one;
  fs::path output;
};

bool needs_environment(const std::string& name) { return name.rfind("tetrapage", 0) != 0; }

std::unique_ptr<PeerCollider> make_collider(const std::string& name, const Arguments& args,
                                            const TriangleSoup* environment, const TriangleSoup& object) {
  if (name == "fcl") return std::make_unique<FclCollider>(*environment, object);
  if (name == "embree") return std::make_unique<EmbreePeerCollider>(*environment, object);
  if (name == "cgal-surfaces") return std::make_unique<CgalCollider>(*environment, object, CollisionQuestion::surfaces);
  if (name == "cgal")
    return std::make_unique<CgalCollider>(*environment, object, CollisionQuestion::surfaces_or_inside);
  TetrapageColliderOptions options;
  options.prefetch = args.prefetch;
  if (name == "tetrapage-paged") options.memory_budget_bytes = parse_byte_size(args.memory);
  return std::make_unique<TetrapageCollider>(args.index, object, options);
}

// One collider, in this process: build, replay every pose once (after an untimed pass when
// asked and the collider is in core), write the answers and the figures.
void run_one_collider(const Arguments& args) {
  // Single-threaded whatever the libraries would do with TBB.
  const oneapi::tbb::global_control one_thread(oneapi::tbb::global_control::max_allowed_parallelism, 1);
  const std::string& name = args.run_one;
  const TriangleSoup object = read_mesh(args.object);
  const std::vector<Pose> poses = read_poses(args.flight);
  std::optional<TriangleSoup> environment;
  if (needs_environment(name)) environment = load_inputs({args.scene});

  const std::uint64_t rss_before = resident_bytes();
  const auto build_start = std::chrono::steady_clock::now();
  auto collider = make_collider(name, args, environment ? &*environment : nullptr, object);
  const double build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - build_start).count();
  const std::uint64_t rss_after = resident_bytes();
  environment.reset();  // every collider keeps its own copy of what it needs

  const bool warm = args.warmup && name != "tetrapage-paged";
  if (warm)
    for (const Pose& pose : poses) (void)collider->collides(pose);

  std::vector<std::uint8_t> answers(poses.size());
  std::vector<double> seconds(poses.size());
  std::uint64_t collisions = 0;
  Progress progress("replaying (" + name + ")", poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const auto start = std::chrono::steady_clock::now();
    const bool hit = collider->collides(poses[i]);
    seconds[i] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    answers[i] = hit ? 1 : 0;
    collisions += answers[i];
    progress.advance();
  }
  progress.finish();
  double total = 0;
  for (double s : seconds) total += s;

  write_answers(args.output / (name + ".answers.csv"), answers);
  write_report(args.output / (name + ".json"),
               {{"collider", name},
                {"description", collider->description()},
                {"question", to_string(collider->question())},
                {"warmup_pass", warm},
                {"build_seconds", build_seconds},
                {"rss_before_build_bytes", rss_before},
                {"build_rss_growth_bytes", rss_after > rss_before ? rss_after - rss_before : 0},
                {"structure_bytes", collider->structure_bytes()},
                {"peak_rss_bytes", peak_resident_bytes()},
                {"steps", poses.size()},
                {"collisions", collisions},
                {"steps_per_second", total > 0 ? double(poses.size()) / total : 0.0},
                {"first_step_us", seconds.empty() ? 0.0 : seconds.front() * 1e6},
                {"latency_us", LatencySummary::of(seconds).to_json()},
                {"figures", collider->figures()}});
}

// Runs `argv` and waits for it. @throw Error when it cannot start or exits non-zero.
void run_child(const std::vector<std::string>& argv, const std::string& what) {
  std::vector<char*> pointers;
  for (const auto& a : argv) pointers.push_back(const_cast<char*>(a.c_str()));
  pointers.push_back(nullptr);
  pid_t pid = 0;
  const int error = posix_spawn(&pid, "/proc/self/exe", nullptr, nullptr, pointers.data(), environ);
  if (error != 0) throw Error("cannot start the " + what + " run: " + std::strerror(error));
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) throw Error("waiting for the " + what + " run: " + std::strerror(errno));
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw Error("the " + what + " run failed (" +
                (WIFEXITED(status) ? "exit " + std::to_string(WEXITSTATUS(status))
                                   : "signal " + std::to_string(WTERMSIG(status))) +
                "; its reason is on stderr above)");
}

json read_json(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw IoError("cannot read '" + path.string() + "'");
  return json::parse(in);
}

struct Disagreements {
  std::uint64_t false_negatives = 0, false_positives = 0;
  json to_json() const { return {{"false_negatives", false_negatives}, {"false_positives", false_positives}}; }
};

Disagreements compare(const std::vector<std::uint8_t>& answers, const std::vector<std::uint8_t>& expected) {
  Disagreements d;
  for (std::size_t i = 0; i < answers.size(); ++i) {
    d.false_negatives += (expected[i] && !answers[i]) ? 1 : 0;
    d.false_positives += (!expected[i] && answers[i]) ? 1 : 0;
  }
  return d;
}

std::string fixed(double value, int decimals) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
  return buffer;
}
std::string mib(double bytes) { return fixed(bytes / double(1 << 20), 1); }

// The machine and every timed build, before the table: a figure is read against both.
void print_machine_and_builds(const json& machine, const json& builds) {
  std::printf("- machine: %s, %lld logical cores, %s memory, %s; load average (1, 5, 15 min) %s at start, %s "
              "at end\n",
              machine["processor"].get<std::string>().c_str(), machine["logical_cores"].get<long long>(),
              machine["memory"].get<std::string>().c_str(), machine["kernel"].get<std::string>().c_str(),
              machine["load_average"].get<std::string>().c_str(),
              machine["load_average_at_end"].get<std::string>().c_str());
  for (const auto& build : builds) {
    std::string what = build["code"].get<std::string>();
    if (build.contains("compiler"))
      what += ": " + build["compiler"].get<std::string>() + ", " + build["build_type"].get<std::string>() + " (" +
              build["flags"].get<std::string>() + "), " + build["built_by"].get<std::string>();
    else
      what += " " + build["version"].get<std::string>() + ": " + build["package"].get<std::string>() + ", built by " +
              build["built_by"].get<std::string>() + ": " + build["flags"].get<std::string>();
    std::printf("- build of %s\n", what.c_str());
  }
  std::printf("\n");
}

void run_all(const Arguments& args) {
  check_writable(args.report);
  std::vector<std::string> colliders = args.colliders;
  if (colliders.empty())
    for (const auto& name : kColliderNames) {
      if (name == "tetrapage" && args.index.empty()) continue;
      if (name == "tetrapage-paged" && (args.index.empty() || args.memory.empty())) continue;
      colliders.push_back(name);
    }
  for (const auto& name : colliders) {
    if (name.rfind("tetrapage", 0) == 0 && args.index.empty())
      throw InputError("collider '" + name + "' needs an index (INDEX.tpi)");
    if (name == "tetrapage-paged" && args.memory.empty())
      throw InputError("collider 'tetrapage-paged' needs --memory");
  }
  if (!args.memory.empty()) (void)parse_byte_size(args.memory);  // a bad size fails now, not in a child

  const std::size_t steps = read_poses(args.flight).size();
  json machine = bench::machine_description();
  std::optional<std::vector<std::uint8_t>> oracle;
  std::string oracle_source;
  if (!args.answers.empty()) {
    oracle = read_answers(args.answers);
    oracle_source = args.answers.string();
    if (oracle->size() != steps)
      throw InputError(args.answers.string() + " holds " + std::to_string(oracle->size()) + " answers for " +
                       std::to_string(steps) + " poses in " + args.flight.string());
  }

  const fs::path work = fs::temp_directory_path() / ("tetrapage-peers-" + std::to_string(getpid()));
  fs::create_directories(work);
  struct RemoveOnExit {
    fs::path path;
    ~RemoveOnExit() {
      std::error_code ec;
      fs::remove_all(path, ec);
    }
  } remove_work{work};

  std::vector<json> runs;
  std::map<std::string, std::vector<std::uint8_t>> answers;
  for (const auto& name : colliders) {
    std::vector<std::string> argv = {"tetrapage_bench_peers", args.scene.string(), args.object.string(),
                                     args.flight.string(),    "--run-one",         name,
                                     "--output",              work.string()};
    if (!args.index.empty()) argv.push_back(args.index.string());
    if (!args.memory.empty()) argv.insert(argv.end(), {"--memory", args.memory});
    if (args.warmup) argv.push_back("--warmup");
    if (args.prefetch) argv.push_back("--prefetch");
    run_child(argv, name);
    runs.push_back(read_json(work / (name + ".json")));
    answers[name] = read_answers(work / (name + ".answers.csv"));
  }
  if (!oracle && answers.count("cgal")) {
    oracle = answers["cgal"];
    oracle_source = "the cgal run";
  }
  // The exact answer to the surfaces-only question, when the run that gives it is there.
  const std::vector<std::uint8_t>* exact_surfaces = answers.count("cgal-surfaces") ? &answers["cgal-surfaces"] : nullptr;
  std::uint64_t inside_only = 0;  // poses where the object is inside an obstacle, touching nothing
  if (oracle && exact_surfaces)
    for (std::size_t i = 0; i < steps; ++i) inside_only += ((*oracle)[i] && !(*exact_surfaces)[i]) ? 1 : 0;

  for (auto& run : runs) {
    const auto& mine = answers[run["collider"].get<std::string>()];
    json disagreements = json::object();
    if (oracle) disagreements["oracle"] = compare(mine, *oracle).to_json();
    const bool surfaces = run["question"] == "surfaces";
    const std::vector<std::uint8_t>* same = surfaces ? exact_surfaces : (oracle ? &*oracle : nullptr);
    if (same != nullptr) disagreements["same_question"] = compare(mine, *same).to_json();
    run["disagreements"] = disagreements;
  }

  std::printf("%zu poses of %s (object %s) through %s, single-threaded, one process per collider; %s\n\n", steps,
              args.flight.string().c_str(), args.object.string().c_str(), args.scene.string().c_str(),
              args.warmup ? "one untimed pass before the timed one (paged runs: none, cold)"
                          : "no warm-up pass: each collider is timed from its first pose after its build");
  machine["load_average_at_end"] = bench::load_average();
  const json builds = bench::build_description();
  print_machine_and_builds(machine, builds);
  std::printf("| collider | question | build s | build RSS MiB | structures MiB | peak RSS MiB | steps/s | p50 us | "
              "p95 us | p99 us | max us | collisions | FN / FP vs oracle | FN / FP vs exact, same question |\n");
  std::printf("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  auto disagreement_text = [](const json& run, const char* key) -> std::string {
    if (!run["disagreements"].contains(key)) return "-";
    const auto& d = run["disagreements"][key];
    return std::to_string(d["false_negatives"].get<std::uint64_t>()) + " / " +
           std::to_string(d["false_positives"].get<std::uint64_t>());
  };
  for (const auto& run : runs) {
    const auto& latency = run["latency_us"];
    const double structures = run["structure_bytes"].get<double>();
    std::printf("| %s | %s | %s | %s | %s | %s | %.0f | %s | %s | %s | %s | %llu | %s | %s |\n",
                run["collider"].get<std::string>().c_str(), run["question"].get<std::string>().c_str(),
                fixed(run["build_seconds"].get<double>(), 2).c_str(),
                mib(run["build_rss_growth_bytes"].get<double>()).c_str(), structures > 0 ? mib(structures).c_str() : "-",
                mib(run["peak_rss_bytes"].get<double>()).c_str(),
                run["steps_per_second"].get<double>(), fixed(latency["p50"].get<double>(), 1).c_str(),
                fixed(latency["p95"].get<double>(), 1).c_str(), fixed(latency["p99"].get<double>(), 1).c_str(),
                fixed(latency["max"].get<double>(), 0).c_str(), (unsigned long long)run["collisions"].get<std::uint64_t>(),
                disagreement_text(run, "oracle").c_str(), disagreement_text(run, "same_question").c_str());
  }
  std::printf("\n");
  for (const auto& run : runs) std::printf("- %s: %s\n", run["collider"].get<std::string>().c_str(),
                                           run["description"].get<std::string>().c_str());
  if (oracle) std::printf("- oracle: %s\n", oracle_source.c_str());
  if (oracle && exact_surfaces)
    std::printf("- %llu poses have the object inside an obstacle without touching it: a surfaces-only collider "
                "misses them by its question, not by error\n",
                (unsigned long long)inside_only);
  for (const auto& run : runs) {
    const auto& f = run["figures"];
    if (!f.contains("budget_bytes")) continue;
    std::printf("- %s: budget %s, index shards %s in %llu shards, preloaded %llu; during the flight: page-ins %llu "
                "(%s), hit rate %.4f, peak resident shards %s, page-in p50 %.0f us p99 %.0f us\n",
                run["collider"].get<std::string>().c_str(), format_byte_size(f["budget_bytes"].get<std::uint64_t>()).c_str(),
                format_byte_size(f["index_shard_bytes"].get<std::uint64_t>()).c_str(), (unsigned long long)f["shards"].get<std::uint64_t>(),
                (unsigned long long)f["preload_page_ins"].get<std::uint64_t>(),
                (unsigned long long)f["page_ins"].get<std::uint64_t>(), format_byte_size(f["bytes_read"].get<std::uint64_t>()).c_str(),
                f["cache_hit_rate"].get<double>(), format_byte_size(f["peak_resident_shard_bytes"].get<std::uint64_t>()).c_str(),
                f["page_in_latency_us"]["p50"].get<double>(), f["page_in_latency_us"]["p99"].get<double>());
    const auto& per_step = f["per_step"];
    const auto& phase = f["phase_seconds"];
    const double phases = std::max(1e-12, phase["locate"].get<double>() + phase["search"].get<double>() +
                                              phase["shards"].get<double>() + phase["tests"].get<double>());
    const auto& per_near_step = f["per_near_step"];
    std::printf("  per step: searched %.1f %% of steps, %.1f tets visited, %.2f shards, %.1f candidates, %.1f "
                "triangle tests; near steps (a shard touched) %.1f %%: %.1f shards each; time in locate %.0f %%, "
                "search %.0f %%, shards %.0f %%, tests %.0f %%\n",
                100 * per_step["searched"].get<double>(), per_step["tets_visited"].get<double>(),
                per_step["shards_touched"].get<double>(), per_step["candidates"].get<double>(),
                per_step["triangle_tests"].get<double>(),
                // Only near steps touch shards: their share is the ratio of the two shard counts.
                100 * per_step["shards_touched"].get<double>() /
                    std::max(1e-12, per_near_step["shards_touched"].get<double>()),
                per_near_step["shards_touched"].get<double>(), 100 * phase["locate"].get<double>() / phases,
                100 * phase["search"].get<double>() / phases, 100 * phase["shards"].get<double>() / phases,
                100 * phase["tests"].get<double>() / phases);
  }

  // Issue 5's targets: tetrapage in memory against the best peer; paged against in memory.
  const json* best_peer = nullptr;
  const json* in_memory = nullptr;
  const json* paged = nullptr;
  for (const auto& run : runs) {
    const auto name = run["collider"].get<std::string>();
    if (name == "tetrapage") in_memory = &run;
    else if (name == "tetrapage-paged") paged = &run;
    else if (best_peer == nullptr || run["steps_per_second"] > (*best_peer)["steps_per_second"]) best_peer = &run;
  }
  json ratios = json::object();
  if (in_memory && best_peer) {
    const double rate = (*in_memory)["steps_per_second"].get<double>() / (*best_peer)["steps_per_second"].get<double>();
    const double p99 = (*in_memory)["latency_us"]["p99"].get<double>() / (*best_peer)["latency_us"]["p99"].get<double>();
    ratios["best_peer"] = (*best_peer)["collider"];
    ratios["in_memory_over_best_peer_steps_per_second"] = rate;
    ratios["in_memory_over_best_peer_p99"] = p99;
    std::printf("- tetrapage in memory / best peer (%s): %.2fx the steps/s (target >= 2), %.2fx the p99 (target <= "
                "0.5)\n",
                (*best_peer)["collider"].get<std::string>().c_str(), rate, p99);
  }
  if (in_memory && paged) {
    const double rate = (*paged)["steps_per_second"].get<double>() / (*in_memory)["steps_per_second"].get<double>();
    ratios["paged_over_in_memory_steps_per_second"] = rate;
    std::printf("- tetrapage paged / in memory: %.2fx the steps/s (target >= 0.5)\n", rate);
  }

  if (!args.report.empty())
    write_report(args.report, {{"command", "bench peers"},
                               {"scene", args.scene.string()},
                               {"object", args.object.string()},
                               {"flight", args.flight.string()},
                               {"index", args.index.string()},
                               {"oracle", oracle_source},
                               {"steps", steps},
                               {"warmup_pass", args.warmup},
                               {"inside_only_poses", inside_only},
                               {"machine", machine},
                               {"builds", builds},
                               {"runs", runs},
                               {"ratios", ratios}});
}

}  // namespace
}  // namespace tetrapage

int main(int argc, char** argv) {
  using namespace tetrapage;
  CLI::App app{
      "Replays a flight through FCL (BVHModel<OBBRSS>), Embree's rtcCollide, CGAL's AABB tree (the exact oracle, and its\n"
      "surfaces-only test) and tetrapage's runtime (every shard in memory, and paged under --memory),\n"
      "single-threaded, each in a fresh process; prints build time, resident memory, steps per second,\n"
      "latency percentiles, collisions and disagreements with the oracle's answers."};
  Arguments args;
  app.add_option("scene", args.scene, "Environment: mesh file or manifest (what the index was made from)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("object", args.object, "Flying object mesh")->required()->check(CLI::ExistingFile);
  app.add_option("flight", args.flight, "Pose file (CSV tx,ty,tz,qw,qx,qy,qz)")->required()->check(CLI::ExistingFile);
  app.add_option("answers_and_index", args.optional_inputs,
                 "ANSWERS.csv (the oracle's, from `generate flight --answers`) and/or INDEX.tpi")
      ->expected(0, 2)
      ->check(CLI::ExistingFile);
  app.add_option("--memory", args.memory, "Shard budget of the paged run (e.g. 8M); no paged run without it");
  app.add_option("--colliders", args.colliders, "Subset to run: fcl, embree, cgal-surfaces, cgal, tetrapage, tetrapage-paged")
      ->delimiter(',')
      ->check(CLI::IsMember(kColliderNames));
  app.add_flag("--warmup", args.warmup, "One untimed pass before the timed one (in-core colliders only)");
  app.add_flag("--prefetch", args.prefetch, "Paged run with the background prefetcher (a second thread)");
  app.add_option("--report", args.report, "Write the figures as JSON");
  app.add_option("--run-one", args.run_one, "(internal) run this collider in this process")
      ->group("")
      ->check(CLI::IsMember(kColliderNames));
  app.add_option("--output", args.output, "(internal) folder for --run-one's figures")->group("");
  try {
    app.parse(argc, argv);
    for (const auto& input : args.optional_inputs) {
      auto& slot = input.extension() == ".tpi" ? args.index : args.answers;
      if (!slot.empty()) throw InputError("two " + std::string(&slot == &args.index ? "indexes" : "answer files") +
                                          " given: '" + slot.string() + "' and '" + input.string() + "'");
      slot = input;
    }
    if (!args.run_one.empty())
      run_one_collider(args);
    else
      run_all(args);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tetrapage_bench_peers: %s\n", e.what());
    return 1;
  }
  return 0;
}
