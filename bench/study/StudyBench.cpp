// tetrapage_bench_study: the study's flight benchmark (Held, Klosowski, Mitchell, section 4)
// on today's hardware. Its environment groups (terrains, tetras, scenes) x its six flying
// objects; one 10,000-step billiard path per pair, replayed identically through the four
// methods (grid, 3d-tree, R-tree, conforming mesh), tetrapage's hybrid (in memory, and paged
// with --memory) and the peers (Embree rtcCollide, FCL, CGAL AABB_tree), single-threaded, in
// one process. Writes study.json, study.csv, study.md (Tables 1, 3-8 the study's way) and, when
// gnuplot is installed, PNG plots.
//
//   tetrapage_bench_study --out DIR [--quick] [--steps N] [--groups ...] [--objects ...]

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <oneapi/tbb/global_control.h>

#include "tetrapage/bench/CgalCollider.h"
#include "tetrapage/bench/EmbreePeerCollider.h"
#include "tetrapage/bench/FclCollider.h"
#include "tetrapage/bench/StudyCollider.h"
#include "tetrapage/bench/TetrapageCollider.h"
#include "tetrapage/formats/base/ByteSize.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/Progress.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/preprocess/Preprocess.h"
#include "tetrapage/study/BoxMethods.h"
#include "tetrapage/study/MeshMethod.h"
#include "tetrapage/tools/FlightGenerator.h"
#include "tetrapage/tools/LatencySummary.h"
#include "tetrapage/tools/MeshLibrary.h"
#include "tetrapage/tools/ObjectGenerator.h"
#include "tetrapage/tools/ReferenceCollider.h"
#include "tetrapage/tools/ReportFile.h"
#include "tetrapage/tools/StudyEnvironment.h"

namespace tetrapage {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

const std::vector<std::string> kStudyMethods = {"grid", "3d-tree", "r-tree", "mesh"};
const std::vector<std::string> kAllMethods = {"grid",   "3d-tree", "r-tree", "mesh", "hybrid",
                                              "hybrid-paged", "embree", "fcl", "cgal"};

struct Options {
  fs::path out;
  bool quick = false;
  std::size_t steps = 10000;
  std::vector<std::string> groups{"terrains", "tetras", "scenes"};
  std::vector<std::uint64_t> objects;  // empty: the study's six (three with --quick)
  std::vector<std::string> methods;    // empty: every one (hybrid-paged only with --memory)
  std::string memory;                  // the paged hybrid's budget
  std::size_t table8_placements = 20;
  double table8_seconds = 0.05;  // per method and placement, at least one repetition
  std::uint64_t seed = 1;
  // The methods' parameters (the study's values by default).
  study::GridOptions grid;
  study::KdTreeOptions kd_tree;
  study::RTreeOptions r_tree;
  study::MeshMethodOptions mesh;
  unsigned terrain_grid_points = 10;  // the study's extra Steiner grid for terrain meshes
  bool figure2 = true;                // the mesh method on each library mesh alone
};

struct EnvironmentSpec {
  std::string group, name;
  EnvironmentKind kind;
  std::uint64_t triangles, seed;
};

std::vector<EnvironmentSpec> environments(const Options& o) {
  std::vector<EnvironmentSpec> specs;
  auto wants = [&](const std::string& g) { return std::find(o.groups.begin(), o.groups.end(), g) != o.groups.end(); };
  if (wants("terrains"))
    // The study sampled 1201 x 1201 DEMs down to 120 x 120 (28,322 triangles).
    for (std::uint64_t seed : o.quick ? std::vector<std::uint64_t>{1} : std::vector<std::uint64_t>{1, 2, 3})
      specs.push_back({"terrains", "terrain" + std::to_string(seed), EnvironmentKind::terrain, o.quick ? 2000u : 28322u, seed});
  if (wants("tetras"))
    for (std::uint64_t n : o.quick ? std::vector<std::uint64_t>{25, 250}
                                   : std::vector<std::uint64_t>{25, 100, 250, 500, 1000, 2000, 4000, 16000})
      specs.push_back({"tetras", "tetras" + std::to_string(n), EnvironmentKind::tetras, 4 * n, n});
  if (wants("scenes")) {
    const std::vector<std::uint64_t> sizes =
        o.quick ? std::vector<std::uint64_t>{3000} : std::vector<std::uint64_t>{10000, 20000, 40000};
    for (std::size_t i = 0; i < sizes.size(); ++i)
      specs.push_back({"scenes", "scene" + std::to_string(sizes[i] / 1000) + "k", EnvironmentKind::scene, sizes[i], 10 + i});
  }
  return specs;
}


double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

std::string fixed(double value, int decimals) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
  return buffer;
}

// A rate for tables: 3 significant digits, with k / M.
std::string rate(double value) {
  if (value >= 1e6) return fixed(value / 1e6, value >= 1e7 ? 1 : 2) + "M";
  if (value >= 1e3) return fixed(value / 1e3, value >= 1e4 ? 1 : 2) + "k";
  return fixed(value, 0);
}

// One environment: its triangles, the study methods built over it, its hybrid index.
struct Environment {
  EnvironmentSpec spec;
  fs::path file, index;
  TriangleSoup soup;
  std::map<std::string, std::shared_ptr<study::StudyMethod>> study_methods;
  json record;
};

Environment load_environment(const EnvironmentSpec& spec, const Options& o, const std::vector<std::string>& methods) {
  Environment env;
  env.spec = spec;
  const fs::path folder = o.out / "environments";
  fs::create_directories(folder);
  env.file = folder / (spec.name + ".ply");
  if (!fs::exists(env.file)) {
    MeshWriter writer(env.file);
    generate_environment(spec.kind, spec.triangles, spec.seed, writer);
    writer.commit();
  }
  env.soup = read_mesh(env.file);
  env.record = {{"group", spec.group},
                {"name", spec.name},
                {"file", env.file.string()},
                {"triangles", env.soup.triangle_count()},
                {"vertices", env.soup.vertices.size()}};
  const auto triangles = env.soup.all_corners();
  auto wants = [&](const std::string& m) { return std::find(methods.begin(), methods.end(), m) != methods.end(); };
  json stats = json::object();
  auto add = [&](const std::string& name, std::unique_ptr<study::StudyMethod> method) {
    const study::StudyStatistics s = method->statistics();
    stats[name] = {{"parameters", method->parameters()}, {"stored_triangles", s.stored_triangles},
                   {"height", s.height},                 {"bytes", s.bytes},
                   {"build_seconds", s.build_seconds},   {"details", s.details}};
    env.study_methods[name] = std::move(method);
  };
  if (wants("grid")) add("grid", study::make_grid_method(triangles, o.grid));
  if (wants("3d-tree")) add("3d-tree", study::make_kd_tree_method(triangles, o.kd_tree));
  if (wants("r-tree")) add("r-tree", study::make_r_tree_method(triangles, o.r_tree));
  if (wants("mesh")) {
    study::MeshMethodOptions mesh_options = o.mesh;
    // The study added a 10 x 10 x 10 grid of Steiner points to its terrains' meshes.
    if (spec.group == "terrains") mesh_options.grid_points = o.terrain_grid_points;
    add("mesh", study::make_mesh_method(triangles, mesh_options));
  }
  env.record["methods"] = stats;
  if (wants("hybrid") || wants("hybrid-paged")) {
    env.index = folder / (spec.name + ".tpi");
    PreprocessOptions p;
    p.precision = StoredPrecision::float64;
    p.region_triangles = std::max<std::size_t>(64, env.soup.triangle_count() / 64);
    p.interiors = true;
    const auto start = Clock::now();
    const PreprocessSummary summary = preprocess({env.file}, env.index, p);
    env.record["hybrid"] = {{"preprocess_seconds", seconds_since(start)},
                            {"regions", summary.regions},
                            {"empty_regions", summary.empty_regions},
                            {"grid_shards", summary.grid_shards},
                            {"rtree_shards", summary.rtree_shards},
                            {"stored_triangles", summary.stored_triangles},
                            {"region_triangles", p.region_triangles}};
  }
  return env;
}

std::unique_ptr<PeerCollider> make_collider(const std::string& name, const Environment& env, const TriangleSoup& object,
                                            const Options& o) {
  if (const auto it = env.study_methods.find(name); it != env.study_methods.end())
    return std::make_unique<StudyCollider>(it->second, object);
  if (name == "embree") return std::make_unique<EmbreePeerCollider>(env.soup, object);
  if (name == "fcl") return std::make_unique<FclCollider>(env.soup, object);
  if (name == "cgal") return std::make_unique<CgalCollider>(env.soup, object, CollisionQuestion::surfaces);
  TetrapageColliderOptions options;
  if (name == "hybrid-paged") options.memory_budget_bytes = parse_byte_size(o.memory);
  if (name == "hybrid" || name == "hybrid-paged") return std::make_unique<TetrapageCollider>(env.index, object, options);
  throw InputError("unknown method '" + name + "'");
}

// Replays the poses through one collider; per step: seconds, answer, and for the study's
// methods whether phase II ran.
struct Replay {
  std::vector<double> seconds;
  std::vector<std::uint8_t> answers, full_checks;
};

Replay replay(PeerCollider& collider, const std::vector<Pose>& poses) {
  Replay r;
  r.seconds.resize(poses.size());
  r.answers.resize(poses.size());
  auto* study = dynamic_cast<StudyCollider*>(&collider);
  if (study) r.full_checks.resize(poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const std::uint64_t before = study ? study->counters().full_checks : 0;
    const auto start = Clock::now();
    r.answers[i] = collider.collides(poses[i]) ? 1 : 0;
    r.seconds[i] = seconds_since(start);
    if (study) r.full_checks[i] = study->counters().full_checks > before ? 1 : 0;
  }
  return r;
}

// The study's fN/s: the frame rate of a flight in which 5 % of the steps need a full-resolution
// check, from this flight's mean step times with and without one.
double normalised_rate(const std::vector<double>& seconds, const std::vector<std::uint8_t>& full) {
  double with = 0, without = 0;
  std::size_t n_with = 0, n_without = 0;
  for (std::size_t i = 0; i < seconds.size(); ++i) (full[i] ? (with += seconds[i], ++n_with) : (without += seconds[i], ++n_without));
  if (n_with == 0 || n_without == 0) {
    const double total = with + without;
    return total > 0 ? double(seconds.size()) / total : 0.0;
  }
  return 1.0 / (0.95 * without / double(n_without) + 0.05 * with / double(n_with));
}

json run_pair(Environment& env, const fs::path& object_file, std::uint64_t object_triangles, const Options& o,
              const std::vector<std::string>& methods) {
  const TriangleSoup object = read_mesh(object_file);
  const ReferenceCollider oracle(env.soup, object);
  FlightOptions flight_options;
  flight_options.steps = o.steps;
  flight_options.seed = o.seed + object_triangles;
  flight_options.displacement = 0.005;  // the study's step in its unit cube
  const Flight flight = generate_billiard_flight(oracle, flight_options);
  std::vector<std::uint8_t> surfaces(flight.poses.size());
  for (std::size_t i = 0; i < flight.poses.size(); ++i) surfaces[i] = oracle.surfaces_touch(flight.poses[i]) ? 1 : 0;

  json pair = {{"environment", env.spec.name},
               {"group", env.spec.group},
               {"object_triangles", object_triangles},
               {"steps", flight.poses.size()},
               {"collisions", flight.collisions},
               {"surface_collisions", std::count(surfaces.begin(), surfaces.end(), 1)}};
  // The steps that need a full-resolution check: phase I of the R-tree (or another box
  // method) found a witness. The same for the three box methods by construction.
  std::vector<std::uint8_t> full_steps;
  std::vector<json> runs;
  std::vector<Replay> replays;
  std::vector<std::unique_ptr<PeerCollider>> colliders;  // kept for Table 8: built once
  for (const auto& name : methods) {
    const auto build_start = Clock::now();
    auto& collider = colliders.emplace_back(make_collider(name, env, object, o));
    const double build_seconds = seconds_since(build_start);
    Replay r = replay(*collider, flight.poses);
    json run = {{"method", name},
                {"description", collider->description()},
                {"question", to_string(collider->question())},
                {"build_seconds", build_seconds},
                {"structure_bytes", collider->structure_bytes()}};
    const auto& expected = collider->question() == CollisionQuestion::surfaces ? surfaces : flight.collides;
    std::uint64_t fn = 0, fp = 0, hits = 0;
    for (std::size_t i = 0; i < expected.size(); ++i) {
      fn += expected[i] && !r.answers[i];
      fp += !expected[i] && r.answers[i];
      hits += r.answers[i];
    }
    run["collisions"] = hits;
    run["false_negatives"] = fn;
    run["false_positives"] = fp;
    if (auto* study = dynamic_cast<StudyCollider*>(collider.get())) {
      const auto& c = study->counters();
      const double steps = double(std::max<std::uint64_t>(1, c.queries));
      run["per_step"] = {{"full_checks", double(c.full_checks) / steps},
                         {"cells_visited", double(c.cells_visited) / steps},
                         {"nodes_visited", double(c.nodes_visited) / steps},
                         {"tets_occupied", double(c.tets_occupied) / steps},
                         {"triangle_tests", double(c.triangle_tests) / steps}};
      if (full_steps.empty() || name == "r-tree") full_steps = r.full_checks;
    }
    runs.push_back(std::move(run));
    replays.push_back(std::move(r));
  }
  if (full_steps.empty()) full_steps.assign(flight.poses.size(), 0);
  const auto full_count = std::count(full_steps.begin(), full_steps.end(), 1);
  pair["full_checks"] = full_count;
  for (std::size_t m = 0; m < runs.size(); ++m) {
    const auto& s = replays[m].seconds;
    double total = 0;
    for (double x : s) total += x;
    runs[m]["steps_per_second"] = total > 0 ? double(s.size()) / total : 0.0;
    runs[m]["normalised_steps_per_second"] = normalised_rate(s, full_steps);
    runs[m]["latency_us"] = LatencySummary::of(s).to_json();
  }
  // Table 8: full-resolution checks per second, on up to N colliding placements, each timed
  // over repetitions.
  std::vector<std::size_t> colliding;
  for (std::size_t i = 0; i < surfaces.size() && colliding.size() < o.table8_placements; ++i)
    if (surfaces[i]) colliding.push_back(i);
  pair["table8_placements"] = colliding.size();
  if (!colliding.empty())
    for (std::size_t m = 0; m < runs.size(); ++m) {
      PeerCollider* collider = colliders[m].get();
      double total = 0;
      std::uint64_t checks = 0;
      for (const std::size_t i : colliding) {
        const auto start = Clock::now();
        std::uint64_t repeats = 0;
        do {
          (void)collider->collides(flight.poses[i]);
          ++repeats;
        } while (seconds_since(start) < o.table8_seconds / double(colliding.size()));
        total += seconds_since(start);
        checks += repeats;
      }
      runs[m]["full_checks_per_second"] = double(checks) / total;
    }
  pair["runs"] = runs;
  return pair;
}

// Close ties (within 5 %) share a place, as in the study.
constexpr double kTie = 0.95;

// Places 1, 2, ... of the methods by normalised rate; a method within 5 % of the one ahead
// shares its place.
std::map<std::string, int> places(const json& pair, const std::vector<std::string>& among) {
  std::vector<std::pair<double, std::string>> rates;
  for (const auto& run : pair["runs"])
    if (std::find(among.begin(), among.end(), run["method"].get<std::string>()) != among.end())
      rates.push_back({run["normalised_steps_per_second"].get<double>(), run["method"]});
  std::sort(rates.rbegin(), rates.rend());
  std::map<std::string, int> out;
  for (std::size_t i = 0; i < rates.size(); ++i)
    out[rates[i].second] = (i > 0 && rates[i].first >= kTie * rates[i - 1].first) ? out[rates[i - 1].second] : int(i) + 1;
  return out;
}

const json* find_run(const json& pair, const std::string& method) {
  for (const auto& run : pair["runs"])
    if (run["method"] == method) return &run;
  return nullptr;
}

void write_markdown(const fs::path& path, const json& report, const std::vector<std::string>& methods) {
  std::ofstream out(path);
  const auto& envs = report["environments"];
  const auto& pairs = report["pairs"];
  out << "# The study's tables, reproduced\n\n" << report["summary"].get<std::string>() << "\n\n";

  out << "## Table 1: environments and mesh statistics\n\n"
      << "| group | environment | #V | #T | mesh #V | Steiner growth | #M tets | tets/vertex | #(stab) | rounds | "
         "non-conforming | grid #Tst | 3d-tree #Tst | 3d-tree Hght | R-tree Hght | hybrid regions | hybrid #Tst |\n"
      << "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const auto& e : envs) {
    const json& m = e["methods"];
    auto get = [&](const char* method, const char* key, int decimals = 0) -> std::string {
      if (!m.contains(method)) return "-";
      const json* v = &m[method];
      if (v->contains(key)) return fixed((*v)[key].get<double>(), decimals);
      if ((*v)["details"].contains(key)) {
        const json& d = (*v)["details"][key];
        return d.is_boolean() ? (d.get<bool>() ? "yes" : "no") : fixed(d.get<double>(), decimals);
      }
      return "-";
    };
    out << "| " << e["group"].get<std::string>() << " | " << e["name"].get<std::string>() << " | "
        << e["vertices"] << " | " << e["triangles"] << " | " << get("mesh", "vertices") << " | "
        << get("mesh", "growth_factor", 2) << " | " << get("mesh", "tets") << " | " << get("mesh", "tets_per_vertex", 2)
        << " | " << get("mesh", "average_stabbing_number", 1) << " | " << get("mesh", "rounds") << " | "
        << get("mesh", "non_conforming_triangles") << " | " << get("grid", "stored_triangles") << " | "
        << get("3d-tree", "stored_triangles") << " | " << get("3d-tree", "height") << " | " << get("r-tree", "height")
        << " | " << (e.contains("hybrid") ? std::to_string(e["hybrid"]["regions"].get<std::uint64_t>()) : "-") << " | "
        << (e.contains("hybrid") ? std::to_string(e["hybrid"]["stored_triangles"].get<std::uint64_t>()) : "-")
        << " |\n";
  }

  if (report.contains("figure2")) {
    out << "\n## Figure 2: the mesh method on each library mesh alone\n\n| mesh | #T | #V | mesh #V | growth | tets | "
           "rounds | non-conforming | degenerate | stopped | build s |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|\n";
    for (const auto& r : report["figure2"]) {
      const auto& d = r["details"];
      out << "| " << r["mesh"].get<std::string>() << " | " << r["triangles"] << " | " << d.value("original_vertices", 0)
          << " | " << d.value("vertices", 0) << " | " << fixed(d.value("growth_factor", 0.0), 2) << " | "
          << d.value("tets", 0) << " | " << d.value("rounds", 0) << " | " << d.value("non_conforming_triangles", 0)
          << " | " << d.value("degenerate_triangles", 0) << " | " << d.value("stopped", std::string("-")) << " | "
          << fixed(r["build_seconds"].get<double>(), 2) << " |\n";
    }
  }

  for (const std::string group : {"terrains", "tetras", "scenes"}) {
    bool any = false;
    for (const auto& p : pairs) any = any || p["group"] == group;
    if (!any) continue;
    out << "\n## Tables 5-7 (" << group << "): f/s and fN/s per method\n\n"
        << "fN/s: the rate of a flight with 5 % full-resolution checks (section 4.2.2). nO: tets the mesh "
           "method's box search enumerates per step; cV: voxels the grid visits; nV: nodes the trees visit.\n\n"
        << "| environment | object | full checks % | collisions |";
    for (const auto& m : methods) out << " " << m << " f/s | fN/s |";
    out << " mesh nO | grid cV | 3d-tree nV | R-tree nV |\n|---|---:|---:|---:|";
    for (std::size_t i = 0; i < methods.size(); ++i) out << "---:|---:|";
    out << "---:|---:|---:|---:|\n";
    for (const auto& p : pairs) {
      if (p["group"] != group) continue;
      out << "| " << p["environment"].get<std::string>() << " | " << p["object_triangles"] << " | "
          << fixed(100.0 * p["full_checks"].get<double>() / p["steps"].get<double>(), 1) << " | "
          << p["surface_collisions"] << " |";
      for (const auto& m : methods) {
        const json* run = find_run(p, m);
        if (!run) {
          out << " - | - |";
          continue;
        }
        out << " " << rate((*run)["steps_per_second"].get<double>()) << " | "
            << rate((*run)["normalised_steps_per_second"].get<double>()) << " |";
      }
      auto per_step = [&](const char* method, const char* key) -> std::string {
        const json* run = find_run(p, method);
        return run && run->contains("per_step") ? fixed((*run)["per_step"][key].get<double>(), 1) : "-";
      };
      out << " " << per_step("mesh", "tets_occupied") << " | " << per_step("grid", "cells_visited") << " | "
          << per_step("3d-tree", "nodes_visited") << " | " << per_step("r-tree", "nodes_visited") << " |\n";
    }
  }

  // Tables 3 and 4, the study's way over its four methods, then over every method run.
  for (const bool four : {true, false}) {
    std::vector<std::string> among;
    for (const auto& m : methods)
      if (!four || std::find(kStudyMethods.begin(), kStudyMethods.end(), m) != kStudyMethods.end())
        among.push_back(m);
    if (among.size() < 2) continue;
    std::map<std::string, std::map<std::string, int>> wins, scores;  // group -> method -> n
    for (const auto& p : pairs) {
      const auto place = places(p, among);
      for (const auto& [method, rank] : place) {
        wins[p["group"]][method] += rank == 1;
        scores[p["group"]][method] += rank;
        wins["all"][method] += rank == 1;
        scores["all"][method] += rank;
      }
    }
    for (const bool is_wins : {true, false}) {
      out << "\n## Table " << (is_wins ? "3: wins" : "4: scores (place 1, 2, ... summed; lower is better)")
          << (four ? ", the four methods" : ", every method run") << "\n\n| group |";
      for (const auto& m : among) out << " " << m << " |";
      out << "\n|---|";
      for (std::size_t i = 0; i < among.size(); ++i) out << "---:|";
      out << "\n";
      for (const auto& [group, counts] : is_wins ? wins : scores) {
        out << "| " << group << " |";
        for (const auto& m : among) out << " " << (counts.count(m) ? counts.at(m) : 0) << " |";
        out << "\n";
      }
    }
  }

  out << "\n## Table 8: full-resolution checks per second\n\n"
      << "Each method timed on up to 20 colliding placements of the flight, repeated; the first and last "
         "environment of each group.\n\n| environment | object |";
  for (const auto& m : methods) out << " " << m << " |";
  out << "\n|---|---:|";
  for (std::size_t i = 0; i < methods.size(); ++i) out << "---:|";
  out << "\n";
  std::map<std::string, std::pair<std::string, std::string>> first_last;
  for (const auto& e : envs) {
    auto& fl = first_last[e["group"]];
    if (fl.first.empty()) fl.first = e["name"];
    fl.second = e["name"];
  }
  for (const auto& p : pairs) {
    const auto& fl = first_last[p["group"]];
    if (p["environment"] != fl.first && p["environment"] != fl.second) continue;
    if (p["table8_placements"].get<std::uint64_t>() == 0) continue;
    out << "| " << p["environment"].get<std::string>() << " | " << p["object_triangles"] << " |";
    for (const auto& m : methods) {
      const json* run = find_run(p, m);
      out << " " << (run && run->contains("full_checks_per_second") ? rate((*run)["full_checks_per_second"].get<double>()) : "-")
          << " |";
    }
    out << "\n";
  }

  out << "\n## Answers against the exact oracle (false negatives / false positives, over all pairs)\n\n| method | "
         "question | FN | FP |\n|---|---|---:|---:|\n";
  for (const auto& m : methods) {
    std::uint64_t fn = 0, fp = 0;
    std::string question;
    for (const auto& p : pairs)
      if (const json* run = find_run(p, m)) {
        fn += (*run)["false_negatives"].get<std::uint64_t>();
        fp += (*run)["false_positives"].get<std::uint64_t>();
        question = (*run)["question"];
      }
    out << "| " << m << " | " << question << " | " << fn << " | " << fp << " |\n";
  }
}

void write_csv(const fs::path& path, const json& report) {
  std::ofstream out(path);
  out << "group,environment,object_triangles,steps,full_checks,surface_collisions,method,steps_per_second,"
         "normalised_steps_per_second,p50_us,p99_us,full_checks_per_second,cells_visited,nodes_visited,"
         "tets_occupied,false_negatives,false_positives\n";
  for (const auto& p : report["pairs"])
    for (const auto& r : p["runs"]) {
      auto per_step = [&](const char* key) { return r.contains("per_step") ? fixed(r["per_step"][key].get<double>(), 2) : ""; };
      out << p["group"].get<std::string>() << "," << p["environment"].get<std::string>() << "," << p["object_triangles"]
          << "," << p["steps"] << "," << p["full_checks"] << "," << p["surface_collisions"] << ","
          << r["method"].get<std::string>() << "," << fixed(r["steps_per_second"].get<double>(), 1) << ","
          << fixed(r["normalised_steps_per_second"].get<double>(), 1) << "," << fixed(r["latency_us"]["p50"].get<double>(), 2)
          << "," << fixed(r["latency_us"]["p99"].get<double>(), 2) << ","
          << (r.contains("full_checks_per_second") ? fixed(r["full_checks_per_second"].get<double>(), 1) : "") << ","
          << per_step("cells_visited") << "," << per_step("nodes_visited") << "," << per_step("tets_occupied") << ","
          << r["false_negatives"] << "," << r["false_positives"] << "\n";
    }
}

// PNG plots through gnuplot, when it is installed: fN/s against object size per group, and the
// study's Figures 1, 3 and 4 (Steiner growth, tets, stabbing number against vertices).
void write_plots(const fs::path& folder, const json& report, const std::vector<std::string>& methods) {
  const fs::path data = folder / "plots";
  fs::create_directories(data);
  std::ofstream script(data / "plots.gp");
  script << "set terminal pngcairo size 900,560 font ',10'\nset grid\nset key outside right\nset logscale xy\n";
  for (const std::string group : {"terrains", "tetras", "scenes"}) {
    std::map<std::string, std::map<std::uint64_t, std::vector<double>>> by_method;
    for (const auto& p : report["pairs"])
      if (p["group"] == group)
        for (const auto& r : p["runs"])
          by_method[r["method"]][p["object_triangles"].get<std::uint64_t>()].push_back(
              r["normalised_steps_per_second"].get<double>());
    if (by_method.empty()) continue;
    std::ofstream dat(data / (group + ".dat"));
    for (const auto& m : methods) {
      if (!by_method.count(m)) continue;
      dat << "# " << m << "\n";
      for (const auto& [size, rates] : by_method[m]) {
        double log_sum = 0;
        for (double r : rates) log_sum += std::log(std::max(r, 1e-9));
        dat << size << " " << std::exp(log_sum / double(rates.size())) << "\n";
      }
      dat << "\n\n";
    }
    script << "set output '" << group << "-fps.png'\nset title 'fN/s (geometric mean over the " << group
           << ") against flying-object triangles'\nset xlabel 'object triangles'\nset ylabel 'normalised steps per second'\nplot ";
    int index = 0;
    for (const auto& m : methods) {
      if (!by_method.count(m)) continue;
      // One colour per method (gnuplot's default cycle repeats after eight).
      static const char* const colours[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
                                             "#8c564b", "#e377c2", "#7f7f7f", "#17becf"};
      const auto slot = std::size_t(std::find(kAllMethods.begin(), kAllMethods.end(), m) - kAllMethods.begin());
      script << (index ? ", " : "") << "'" << group << ".dat' index " << index << " with linespoints lw 2 lc rgb '"
             << colours[slot % 9] << "' title '" << m << "'";
      ++index;
    }
    script << "\n";
  }
  std::ofstream mesh(data / "mesh.dat");
  bool any_mesh = false;
  for (const auto& e : report["environments"])
    if (e["methods"].contains("mesh")) {
      const auto& d = e["methods"]["mesh"]["details"];
      mesh << e["vertices"] << " " << d.value("growth_factor", 0.0) << " " << d.value("tets", 0.0) << " "
           << d.value("average_stabbing_number", 0.0) << " " << e["group"].get<std::string>() << "\n";
      any_mesh = true;
    }
  if (any_mesh)
    script << "unset logscale\nset logscale x\nset output 'figure1-steiner.png'\nset title 'Figure 1: vertices after "
              "Steiner points / original vertices'\nset xlabel 'original vertices'\nset ylabel 'growth factor'\nplot "
              "'mesh.dat' using 1:2 with points pt 7 title 'environments'\n"
              "set logscale xy\nset output 'figure3-tets.png'\nset title 'Figure 3: tetrahedra against vertices'\nset "
              "ylabel 'tets'\nplot 'mesh.dat' using 1:3 with points pt 7 title 'environments', 6.5*x title '6.5 n'\n"
              "unset logscale y\nset output 'figure4-stabbing.png'\nset title 'Figure 4: average stabbing number'\nset "
              "ylabel 'tets crossed per unit length'\nplot 'mesh.dat' using 1:4 with points pt 7 title 'environments'\n";
  script.close();
  mesh.close();  // gnuplot reads it next
  const std::string command = "cd '" + data.string() + "' && gnuplot plots.gp 2>gnuplot.log";
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) {
    std::fprintf(stderr, "gnuplot not found: plot data and script left in %s\n", data.string().c_str());
    return;
  }
  if (std::system(command.c_str()) != 0)
    std::fprintf(stderr, "gnuplot failed: see %s\n", (data / "gnuplot.log").string().c_str());
}

// The study's Figure 2: the conforming mesh of each real mesh alone (the library's, many with
// self-intersections and near-coplanar faces), scaled into the unit cube.
json library_mesh_growth(const MeshLibrary& library, const Options& o) {
  json rows = json::array();
  Progress progress("figure 2 (library meshes)", library.size());
  for (std::size_t m = 0; m < library.size(); ++m) {
    const LibraryMesh& mesh = library[m];
    const Vec3 size = mesh.bounds.size();
    const double scale = 1.0 / std::max({size[0], size[1], size[2], 1e-300});
    std::vector<geometry::Triangle> triangles = mesh.soup.all_corners();
    for (auto& c : triangles)
      for (auto& p : c)
        for (int a = 0; a < 3; ++a) p[a] = (p[a] - mesh.bounds.lo[a]) * scale;
    const auto method = study::make_mesh_method(triangles, o.mesh);
    const study::StudyStatistics s = method->statistics();
    rows.push_back({{"mesh", mesh.name}, {"triangles", triangles.size()}, {"details", s.details},
                    {"build_seconds", s.build_seconds}});
    progress.advance();
  }
  progress.finish();
  return rows;
}

void run(const Options& o) {
  const oneapi::tbb::global_control one_thread(oneapi::tbb::global_control::max_allowed_parallelism, 1);
  fs::create_directories(o.out);
  std::vector<std::string> methods = o.methods;
  if (methods.empty())
    for (const auto& m : kAllMethods)
      if (m != "hybrid-paged" || !o.memory.empty()) methods.push_back(m);
  for (const auto& m : methods)
    if (m == "hybrid-paged" && o.memory.empty()) throw InputError("method 'hybrid-paged' needs --memory");
  if (!o.memory.empty()) (void)parse_byte_size(o.memory);
  std::vector<std::uint64_t> objects = o.objects;
  if (objects.empty())
    objects = o.quick ? std::vector<std::uint64_t>{4, 116, 496}
                      : std::vector<std::uint64_t>{4, 116, 496, 2094, 5152, 14643};
  const MeshLibrary library = MeshLibrary::load_default();
  fs::create_directories(o.out / "objects");
  std::vector<fs::path> object_files;
  for (const std::uint64_t n : objects) {
    const fs::path path = o.out / "objects" / ("object" + std::to_string(n) + ".ply");
    if (!fs::exists(path)) {
      ObjectOptions options;
      options.triangles = n;
      const GeneratedObject object = generate_object(options, &library);
      MeshWriter writer(path);
      writer.add_part(object.soup.vertices, object.soup.triangles);
      writer.commit();
    }
    object_files.push_back(path);
  }
  const auto specs = environments(o);
  if (specs.empty()) throw InputError("no environment group selected (terrains, tetras, scenes)");
  json report = {{"command", "bench study"}, {"steps", o.steps}, {"quick", o.quick}, {"methods", methods},
                 {"objects", objects}};
  json env_records = json::array(), pairs = json::array();
  const auto start = Clock::now();
  Progress progress("study flights", specs.size() * objects.size());
  for (const auto& spec : specs) {
    Environment env = load_environment(spec, o, methods);
    for (std::size_t k = 0; k < objects.size(); ++k) {
      pairs.push_back(run_pair(env, object_files[k], objects[k], o, methods));
      progress.advance();
    }
    env_records.push_back(env.record);
  }
  progress.finish();
  report["environments"] = env_records;
  report["pairs"] = pairs;
  if (o.figure2 && std::find(methods.begin(), methods.end(), "mesh") != methods.end())
    report["figure2"] = library_mesh_growth(library, o);
  report["seconds"] = seconds_since(start);
  report["summary"] = std::to_string(specs.size()) + " environments x " + std::to_string(objects.size()) +
                      " objects, " + std::to_string(o.steps) + "-step billiard flights, one thread, in one process; " +
                      fixed(report["seconds"].get<double>(), 0) + " s in all. Command: tetrapage_bench_study --out " +
                      o.out.string() + (o.quick ? " --quick" : "") + (o.memory.empty() ? "" : " --memory " + o.memory);
  write_report(o.out / "study.json", report);
  write_csv(o.out / "study.csv", report);
  write_markdown(o.out / "study.md", report, methods);
  write_plots(o.out, report, methods);
  std::printf("%s\nwrote %s/study.{json,csv,md} and plots/\n", report["summary"].get<std::string>().c_str(),
              o.out.string().c_str());
}

}  // namespace
}  // namespace tetrapage

int main(int argc, char** argv) {
  using namespace tetrapage;
  CLI::App app{
      "The study's flight benchmark: its environment groups (terrains, tetras, scenes) x its six flying\n"
      "objects, one billiard flight per pair replayed through the grid, 3d-tree, R-tree and conforming mesh,\n"
      "tetrapage's hybrid (in memory; paged with --memory) and the peers (Embree rtcCollide, FCL, CGAL\n"
      "AABB_tree), single-threaded. Writes study.json, study.csv, study.md (Tables 1, 3-8) and PNG plots."};
  Options o;
  app.add_option("--out", o.out, "Output folder (environments and objects are generated there once)")->required();
  app.add_flag("--quick", o.quick, "Small sizes: one terrain, two tetras, one scene, three objects");
  app.add_option("--steps", o.steps, "Steps per flight (the study: 10000)")->check(CLI::Range(10, 10'000'000));
  app.add_option("--groups", o.groups, "Environment groups")->delimiter(',')->check(CLI::IsMember({"terrains", "tetras", "scenes"}));
  app.add_option("--objects", o.objects, "Flying-object triangle counts (default: the study's 4,116,496,2094,5152,14643)")
      ->delimiter(',');
  app.add_option("--methods", o.methods, "Methods to run (default: all)")->delimiter(',')->check(CLI::IsMember(kAllMethods));
  app.add_option("--memory", o.memory, "Budget of the paged hybrid run (e.g. 8M); none without it");
  app.add_option("--seed", o.seed, "Seed of the flights");
  app.add_option("--grid-n", o.grid.cells_per_axis, "Grid: N x N x N voxels")->capture_default_str();
  app.add_option("--kd-leaf", o.kd_tree.leaf_triangles, "3d-tree: K, the leaf threshold")->capture_default_str();
  std::string kd_axis = "c", r_split = "a";
  app.add_option("--kd-axis", kd_axis,
                 "3d-tree axis rule: a (min max(n1,n2)), b (min |n1-n2|), c (min n1*n2), d (longest side)")
      ->check(CLI::IsMember({"a", "b", "c", "d"}))
      ->capture_default_str();
  app.add_option("--kd-no-gain", o.kd_tree.no_gain_splits, "3d-tree: no-gain splits allowed on a path")
      ->capture_default_str();
  app.add_option("--rtree-leaf", o.r_tree.leaf_triangles, "R-tree: K, triangles per leaf")->capture_default_str();
  app.add_option("--rtree-split", r_split, "R-tree split rule: a (min max(V1,V2)), b (min V1+V2)")
      ->check(CLI::IsMember({"a", "b"}))
      ->capture_default_str();
  app.add_option("--mesh-rounds", o.mesh.max_rounds, "Mesh: rounds of Steiner points at most")->capture_default_str();
  app.add_option("--mesh-growth", o.mesh.max_growth, "Mesh: stop inserting beyond this vertex growth")
      ->capture_default_str();
  app.add_option("--terrain-grid", o.terrain_grid_points, "Mesh: extra n x n x n Steiner grid for terrains (0: none)")
      ->capture_default_str();
  bool no_figure2 = false;
  app.add_flag("--no-figure2", no_figure2, "Skip Figure 2 (the mesh method on each library mesh)");
  try {
    app.parse(argc, argv);
    o.kd_tree.axis_rule = kd_axis == "a"   ? study::KdAxisRule::min_max_count
                          : kd_axis == "b" ? study::KdAxisRule::min_count_gap
                          : kd_axis == "c" ? study::KdAxisRule::min_count_product
                                           : study::KdAxisRule::longest_side;
    o.r_tree.split_rule = r_split == "a" ? study::RTreeSplitRule::min_max_volume : study::RTreeSplitRule::min_volume_sum;
    o.figure2 = !no_figure2 && !o.quick;
    run(o);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tetrapage_bench_study: %s\n", e.what());
    return 1;
  }
  return 0;
}
