// tetrapage_bench_distance: distance and time of impact, tetrapage's runtime against FCL 0.7 on
// the same poses (issue 27, items 1 and 5). Single-threaded, one process, everything in
// memory: the index is preloaded under a budget above its size and every distance row runs one
// untimed pass before its timed one, so that no paging and no first touch is measured.
//
//   tetrapage_bench_distance SCENE OBJECT FLIGHT INDEX.tpi [--max-distance D] [--report R.json]
//
// Distance: FlyingObject::distance (certified bracket) against fcl::distance on BVHModel<OBBRSS>
// and <RSS> (exact request: nearest points, rel_err = abs_err = 0) and FCL's default request.
// Time of impact, over consecutive poses i-1 -> i: FlyingObject::time_of_impact against
// fcl::continuousCollide (conservative advancement), and the swept-hull query for reference.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <oneapi/tbb/global_control.h>

#include "tetrapage/bench/FclDistance.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/Manifest.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/tools/LatencySummary.h"
#include "tetrapage/tools/ReportFile.h"

namespace tetrapage {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

// "Everything in memory": a budget no index of this machine reaches, so nothing is evicted.
constexpr std::uint64_t kUnboundedBudget = std::uint64_t(1) << 40;
// FCL computes in floating point without a bound: its value may lie this far (relatively)
// outside tetrapage's certified bracket before it counts as a disagreement.
constexpr double kRelativeSlack = 1e-9;

struct Arguments {
  fs::path scene, object, flight, index, report;
  std::optional<double> max_distance;
  std::size_t impact_steps = 0;      // 0: every consecutive pair
  std::size_t fcl_ca_steps = 10;       // FCL's conservative advancement is slow: its rows' motions
  std::size_t naive_samples = 10;      // FCL's default request
};

double since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// One timed row: what ran, and the seconds of each of its steps.
struct Row {
  std::string name, description;
  std::vector<double> seconds;
  json extra = json::object();

  double steps_per_second() const {
    double total = 0;
    for (double s : seconds) total += s;
    return total > 0 ? double(seconds.size()) / total : 0.0;
  }
  json to_json() const {
    json j = {{"name", name},
              {"description", description},
              {"steps", seconds.size()},
              {"steps_per_second", steps_per_second()},
              {"latency_us", LatencySummary::of(seconds).to_json()}};
    if (!seconds.empty())  // the step to replay when the tail needs explaining
      j["slowest_step_offset"] = std::size_t(std::max_element(seconds.begin(), seconds.end()) - seconds.begin());
    j.update(extra);
    return j;
  }
};

// Runs step(i) for every i in [first, end), once untimed when `warm`, then timed.
template <class Step>
std::vector<double> time_steps(std::size_t first, std::size_t end, bool warm, Step&& step) {
  if (warm)
    for (std::size_t i = first; i < end; ++i) step(i);
  std::vector<double> seconds;
  seconds.reserve(end - first);
  for (std::size_t i = first; i < end; ++i) {
    const auto start = Clock::now();
    step(i);
    seconds.push_back(since(start));
  }
  return seconds;
}

double norm_of_difference(const Vec3& a, const Vec3& b) {
  return std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
}

// The inputs every row shares: the index in memory, the object and the poses.
struct Workload {
  std::shared_ptr<const CollisionIndex> index;
  TriangleSoup object;
  std::vector<Pose> poses;
};

Row tetrapage_distances(const Workload& w, const DistanceOptions& options, std::vector<DistanceResult>& results) {
  FlyingObject flying(w.index, w.object);
  results.assign(w.poses.size(), DistanceResult{});
  Row row;
  row.seconds = time_steps(0, w.poses.size(), true, [&](std::size_t i) { flying.distance(w.poses[i], options, results[i]); });
  std::uint64_t from_last_pair = 0, from_free_box = 0, farther = 0, pair_tests = 0;
  for (const auto& r : results) {
    from_last_pair += r.from_last_pair ? 1 : 0;
    from_free_box += r.from_free_box ? 1 : 0;
    farther += r.separation == Separation::farther ? 1 : 0;
    pair_tests += r.pair_tests;
  }
  const double n = double(std::max<std::size_t>(1, results.size()));
  row.extra = {{"from_last_pair_fraction", double(from_last_pair) / n},
               {"from_free_box_fraction", double(from_free_box) / n},
               {"farther_fraction", double(farther) / n},
               {"pair_tests_per_step", double(pair_tests) / n}};
  return row;
}

Row fcl_distances(FclDistance& fcl, const std::vector<Pose>& poses, bool exact, std::vector<FclDistanceAnswer>& answers) {
  answers.assign(poses.size(), FclDistanceAnswer{});
  Row row;
  row.seconds = time_steps(0, poses.size(), true, [&](std::size_t i) { answers[i] = fcl.distance(poses[i], exact); });
  return row;
}

// FCL's distances against tetrapage's certified brackets.
json distance_agreement(const std::vector<DistanceResult>& mine, const std::vector<FclDistanceAnswer>& fcl) {
  std::uint64_t apart = 0, outside = 0, below = 0, above = 0, contact = 0, contact_fcl_positive = 0, contained = 0,
                contained_fcl_positive = 0;
  double max_difference = 0, max_relative = 0;
  std::vector<double> relative;
  for (std::size_t i = 0; i < mine.size(); ++i) {
    const DistanceResult& r = mine[i];
    const double f = fcl[i].distance;
    if (r.separation == Separation::touching) {
      const bool containment = r.containment != Containment::none;
      (containment ? contained : contact) += 1;
      if (f > 0) (containment ? contained_fcl_positive : contact_fcl_positive) += 1;
      continue;
    }
    if (r.separation != Separation::apart) continue;
    ++apart;
    const bool low = f < r.lower_bound - kRelativeSlack * std::fabs(r.lower_bound);
    const bool high = f > r.upper_bound + kRelativeSlack * std::fabs(r.upper_bound);
    below += low ? 1 : 0;
    above += high ? 1 : 0;
    outside += (low || high) ? 1 : 0;
    const double difference = std::fabs(f - r.distance);
    max_difference = std::max(max_difference, difference);
    if (r.distance > 0) relative.push_back(difference / r.distance);
  }
  for (double x : relative) max_relative = std::max(max_relative, x);
  std::sort(relative.begin(), relative.end());
  return {{"apart_poses", apart},
          {"outside_bracket", outside},
          {"below_bracket", below},
          {"above_bracket", above},
          {"max_abs_difference", max_difference},
          {"median_relative_difference", relative.empty() ? 0.0 : relative[relative.size() / 2]},
          {"max_relative_difference", max_relative},
          {"touching_contact_poses", contact},
          {"touching_contact_fcl_positive", contact_fcl_positive},
          {"touching_containment_poses", contained},
          {"touching_containment_fcl_positive", contained_fcl_positive}};
}

// tetrapage's own consistency: the closest points at the distance reported, the bracket
// around it, and its widest width.
json distance_self_check(const std::vector<DistanceResult>& results) {
  std::uint64_t points_mismatch = 0, not_in_bracket = 0;
  double widest = 0, widest_relative = 0;
  for (const auto& r : results) {
    if (r.separation != Separation::apart) continue;
    const double between = norm_of_difference(r.on_environment, r.on_object);
    points_mismatch += std::fabs(between - r.distance) > 1e-12 * std::max(1.0, r.distance) ? 1 : 0;
    not_in_bracket += (r.distance < r.lower_bound || r.distance > r.upper_bound) ? 1 : 0;
    widest = std::max(widest, r.upper_bound - r.lower_bound);
    if (r.distance > 0) widest_relative = std::max(widest_relative, (r.upper_bound - r.lower_bound) / r.distance);
  }
  return {{"points_not_at_distance", points_mismatch},
          {"distance_not_in_bracket", not_in_bracket},
          {"widest_bracket", widest},
          {"widest_relative_bracket", widest_relative}};
}

// The bounded answers against the unbounded ones: "farther" must be certified, and an
// "apart" under D must overlap the unbounded bracket.
json bounded_consistency(const std::vector<DistanceResult>& bounded, const std::vector<DistanceResult>& full,
                         double max_distance) {
  std::uint64_t farther = 0, wrong_farther = 0, wrong_apart = 0, wrong_touching = 0;
  for (std::size_t i = 0; i < bounded.size(); ++i) {
    const DistanceResult &b = bounded[i], &f = full[i];
    if ((b.separation == Separation::touching) != (f.separation == Separation::touching)) ++wrong_touching;
    if (b.separation == Separation::farther) {
      ++farther;
      if (f.separation != Separation::farther && f.upper_bound < max_distance) ++wrong_farther;
    } else if (b.separation == Separation::apart && f.separation == Separation::apart) {
      if (b.upper_bound < f.lower_bound || f.upper_bound < b.lower_bound) ++wrong_apart;
    }
  }
  return {{"max_distance", max_distance},
          {"farther_poses", farther},
          {"farther_fraction", bounded.empty() ? 0.0 : double(farther) / double(bounded.size())},
          {"farther_but_closer_unbounded", wrong_farther},
          {"apart_brackets_disjoint", wrong_apart},
          {"touching_differs", wrong_touching}};
}

// Time of impact over the pairs (i-1, i), i in [1, end). No untimed pass: the index is
// preloaded and the distance rows ran first, so nothing is paged in here either.
Row tetrapage_impacts(const Workload& w, std::size_t end, std::vector<ImpactResult>& results) {
  FlyingObject flying(w.index, w.object);
  results.assign(end, ImpactResult{});
  Row row;
  row.seconds = time_steps(1, end, false, [&](std::size_t i) { results[i] = flying.time_of_impact(w.poses[i - 1], w.poses[i]); });
  std::uint64_t hits = 0, unresolved = 0, iterations = 0;
  for (std::size_t i = 1; i < end; ++i) {
    hits += results[i].impact == Impact::hit ? 1 : 0;
    unresolved += results[i].impact == Impact::unresolved ? 1 : 0;
    iterations += results[i].iterations;
  }
  row.extra = {{"hits", hits},
               {"unresolved", unresolved},
               {"distance_queries_per_step", double(iterations) / double(std::max<std::size_t>(1, end - 1))}};
  return row;
}

Row fcl_impacts(FclDistance& fcl, const std::vector<Pose>& poses, std::size_t end, FclImpactSolver solver,
               std::size_t samples, std::vector<FclImpactAnswer>& answers) {
  answers.assign(end, FclImpactAnswer{});
  Row row;
  row.seconds = time_steps(1, end, false, [&](std::size_t i) {
    answers[i] = fcl.time_of_impact(poses[i - 1], poses[i], solver, samples);
  });
  // FCL against itself: a motion whose end pose its own fcl::collide finds colliding must hit.
  std::uint64_t hits = 0, end_collides_no_hit = 0;
  for (std::size_t i = 1; i < end; ++i) {
    hits += answers[i].collides ? 1 : 0;
    end_collides_no_hit += (!answers[i].collides && fcl.collides(poses[i])) ? 1 : 0;
  }
  row.extra = {{"hits", hits}, {"no_hit_but_end_pose_collides_for_fcl", end_collides_no_hit}};
  return row;
}

// The swept hull of poses i-1 and i: the query at pose i after the one at pose i-1.
Row swept_hulls(const Workload& w, std::size_t end, std::vector<std::uint8_t>& hits) {
  FlyingObject flying(w.index, w.object);
  QueryOptions options;
  options.motion = Motion::swept;
  QueryResult result;
  flying.query(w.poses[0], options, result);  // the first query has no previous pose
  hits.assign(end, 0);
  Row row;
  row.seconds = time_steps(1, end, false, [&](std::size_t i) {
    flying.query(w.poses[i], options, result);
    hits[i] = result.collides ? 1 : 0;
  });
  std::uint64_t count = 0;
  for (auto h : hits) count += h;
  row.extra = {{"hits", count}};
  return row;
}

// FCL's continuous collision against tetrapage's bracket (free_until, contact_at].
json impact_agreement(const std::vector<ImpactResult>& mine, const std::vector<FclImpactAnswer>& fcl) {
  std::uint64_t both_hit = 0, both_none = 0, only_mine = 0, only_fcl = 0, unresolved = 0, early = 0, late = 0;
  std::vector<double> differences;
  for (std::size_t i = 1; i < std::min(mine.size(), fcl.size()); ++i) {
    const ImpactResult& r = mine[i];
    if (r.impact == Impact::unresolved) {
      ++unresolved;
      continue;
    }
    const bool hit = r.impact == Impact::hit;
    if (hit && fcl[i].collides) {
      ++both_hit;
      const double t = fcl[i].time_of_contact;
      early += t < r.free_until - 1e-9 ? 1 : 0;  // FCL: contact where tetrapage certifies none
      late += t > r.contact_at + 1e-9 ? 1 : 0;   // FCL: later than an exactly colliding pose
      differences.push_back(std::fabs(t - r.contact_at));
    } else if (hit) {
      ++only_mine;
    } else if (fcl[i].collides) {
      ++only_fcl;
    } else {
      ++both_none;
    }
  }
  std::sort(differences.begin(), differences.end());
  return {{"both_hit", both_hit},
          {"both_none", both_none},
          {"hit_only_tetrapage", only_mine},
          {"hit_only_fcl", only_fcl},
          {"tetrapage_unresolved", unresolved},
          {"fcl_time_before_free_until", early},
          {"fcl_time_after_contact_at", late},
          {"median_abs_time_difference", differences.empty() ? 0.0 : differences[differences.size() / 2]},
          {"max_abs_time_difference", differences.empty() ? 0.0 : differences.back()}};
}

// The swept hull holds both poses and, for a translation, the motion between: it may say yes
// where the object misses (concavities, corners), and with a rotation it may miss a contact.
json swept_agreement(const std::vector<ImpactResult>& mine, const std::vector<std::uint8_t>& swept) {
  std::uint64_t hull_only = 0, impact_only = 0, both = 0;
  for (std::size_t i = 1; i < mine.size(); ++i) {
    if (mine[i].impact == Impact::unresolved) continue;
    const bool hit = mine[i].impact == Impact::hit;
    both += (hit && swept[i]) ? 1 : 0;
    hull_only += (!hit && swept[i]) ? 1 : 0;
    impact_only += (hit && !swept[i]) ? 1 : 0;
  }
  return {{"both_hit", both}, {"hull_hit_without_impact", hull_only}, {"impact_missed_by_hull", impact_only}};
}

void print_row(const Row& row, const Row& reference, const std::string& agreement) {
  const LatencySummary l = LatencySummary::of(row.seconds);
  const double ratio = row.steps_per_second() > 0 ? reference.steps_per_second() / row.steps_per_second() : 0.0;
  std::printf("| %s | %.0f | %.1f | %.1f | %.0f | %.2f | %s |\n", row.name.c_str(), row.steps_per_second(), l.p50_us,
              l.p99_us, l.max_us, ratio, agreement.c_str());
}

std::string distance_agreement_text(const json& a) {
  char text[256];
  std::snprintf(text, sizeof text, "%llu of %llu (%llu below, %llu above); max rel. diff %.1e; %llu of %llu",
                (unsigned long long)a["outside_bracket"].get<std::uint64_t>(),
                (unsigned long long)a["apart_poses"].get<std::uint64_t>(),
                (unsigned long long)a["below_bracket"].get<std::uint64_t>(),
                (unsigned long long)a["above_bracket"].get<std::uint64_t>(), a["max_relative_difference"].get<double>(),
                (unsigned long long)a["touching_contact_fcl_positive"].get<std::uint64_t>(),
                (unsigned long long)a["touching_contact_poses"].get<std::uint64_t>());
  return text;
}

std::string impact_agreement_text(const json& a) {
  char text[256];
  std::snprintf(text, sizeof text, "%llu / %llu / %llu / %llu; %llu / %llu; %.1e / %.1e",
                (unsigned long long)a["both_hit"].get<std::uint64_t>(),
                (unsigned long long)a["both_none"].get<std::uint64_t>(),
                (unsigned long long)a["hit_only_tetrapage"].get<std::uint64_t>(),
                (unsigned long long)a["hit_only_fcl"].get<std::uint64_t>(),
                (unsigned long long)a["fcl_time_before_free_until"].get<std::uint64_t>(),
                (unsigned long long)a["fcl_time_after_contact_at"].get<std::uint64_t>(),
                a["median_abs_time_difference"].get<double>(), a["max_abs_time_difference"].get<double>());
  return text;
}

// The FCL peers, both bounding volumes, with their build times.
struct FclPeers {
  std::vector<std::unique_ptr<FclDistance>> models;
  std::vector<double> build_seconds;
};

FclPeers build_fcl(const fs::path& scene, const TriangleSoup& object) {
  const TriangleSoup environment = load_inputs({scene});
  FclPeers peers;
  for (FclVolume volume : {FclVolume::obbrss, FclVolume::rss}) {
    const auto start = Clock::now();
    peers.models.push_back(std::make_unique<FclDistance>(environment, object, volume));
    peers.build_seconds.push_back(since(start));
  }
  return peers;
}

json run_distance(const Workload& w, FclPeers& fcl, const Arguments& args) {
  std::vector<DistanceResult> mine;
  Row tetrapage = tetrapage_distances(w, {}, mine);
  tetrapage.name = "tetrapage distance";
  tetrapage.description = "FlyingObject::distance, exact, certified bracket, coherence, in memory";
  tetrapage.extra["self_check"] = distance_self_check(mine);
  std::vector<Row> rows;
  for (auto& model : fcl.models)
    for (bool exact : {true, false}) {
      if (!exact && model->volume() == FclVolume::rss) continue;  // the default request once is enough
      std::vector<FclDistanceAnswer> answers;
      Row row = fcl_distances(*model, w.poses, exact, answers);
      row.name = std::string("FCL ") + to_string(model->volume()) + (exact ? " exact" : " default request");
      row.description = exact ? "fcl::distance, DistanceRequest(true, true, 0, 0)" : "fcl::distance, DistanceRequest{}";
      row.extra["agreement"] = distance_agreement(mine, answers);
      rows.push_back(std::move(row));
    }
  std::printf("\n### Distance, %zu poses (one untimed pass before each timed one)\n\n", w.poses.size());
  std::printf("| row | steps/s | p50 us | p99 us | max us | tetrapage steps/s / row's | FCL outside tetrapage's bracket "
              "(of apart poses); max rel. diff; FCL > 0 where tetrapage touches (of contacts) |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---|\n");
  print_row(tetrapage, tetrapage, "-");
  for (const auto& row : rows) print_row(row, tetrapage, distance_agreement_text(row.extra["agreement"]));
  json bounded_json = nullptr;
  if (args.max_distance) {
    std::vector<DistanceResult> bounded;
    Row row = tetrapage_distances(w, DistanceOptions{*args.max_distance}, bounded);
    row.name = "tetrapage distance, max_distance " + std::to_string(*args.max_distance);
    row.description = "FlyingObject::distance with DistanceOptions{max_distance} (FCL has no such bound)";
    row.extra["consistency"] = bounded_consistency(bounded, mine, *args.max_distance);
    const json& c = row.extra["consistency"];
    char text[200];
    std::snprintf(text, sizeof text, "farther %.1f %%; vs unbounded: %llu wrong farther, %llu disjoint", 
                  100 * c["farther_fraction"].get<double>(), (unsigned long long)c["farther_but_closer_unbounded"].get<std::uint64_t>(),
                  (unsigned long long)c["apart_brackets_disjoint"].get<std::uint64_t>());
    print_row(row, tetrapage, text);
    bounded_json = row.to_json();
  }
  const json& self = tetrapage.extra["self_check"];
  std::printf("\n- tetrapage: %.1f %% of steps from the last pair, %.1f %% from a free box, %.1f pair tests per step; "
              "widest bracket %.1e (relative %.1e)\n",
              100 * tetrapage.extra["from_last_pair_fraction"].get<double>(),
              100 * tetrapage.extra["from_free_box_fraction"].get<double>(),
              tetrapage.extra["pair_tests_per_step"].get<double>(), self["widest_bracket"].get<double>(),
              self["widest_relative_bracket"].get<double>());
  json out = {{"tetrapage", tetrapage.to_json()}, {"fcl", json::array()}, {"bounded", bounded_json}};
  for (const auto& row : rows) out["fcl"].push_back(row.to_json());
  return out;
}

json run_impact(const Workload& w, FclPeers& fcl, const Arguments& args) {
  std::size_t end = w.poses.size();
  if (args.impact_steps > 0) end = std::min(end, args.impact_steps + 1);
  std::vector<ImpactResult> mine;
  Row tetrapage = tetrapage_impacts(w, end, mine);
  tetrapage.name = "tetrapage time_of_impact";
  tetrapage.description = "FlyingObject::time_of_impact, tolerance 1e-4 (default ImpactOptions)";
  const std::size_t ca_end = std::min(end, args.fcl_ca_steps + 1);
  std::vector<Row> rows;
  auto add_fcl_row = [&](FclDistance& model, FclImpactSolver solver, std::string name, std::string description) {
    std::vector<FclImpactAnswer> answers;
    const std::size_t fcl_end = solver == FclImpactSolver::naive ? end : ca_end;
    Row row = fcl_impacts(model, w.poses, fcl_end, solver, args.naive_samples, answers);
    row.name = std::move(name);
    row.description = std::move(description);
    row.extra["agreement"] = impact_agreement(mine, answers);
    rows.push_back(std::move(row));
  };
  for (auto& model : fcl.models)
    add_fcl_row(*model, FclImpactSolver::conservative_advancement,
                std::string("FCL ") + to_string(model->volume()) + " continuousCollide CA",
                "CCDC_CONSERVATIVE_ADVANCEMENT, InterpMotion about the origin (linear translation, slerp)");
  add_fcl_row(*fcl.models[0], FclImpactSolver::naive,
              "FCL OBBRSS continuousCollide naive, " + std::to_string(args.naive_samples) + " samples",
              "CCDC_NAIVE: fcl::collide at evenly spaced times (not certified)");
  std::vector<std::uint8_t> swept;
  Row hull = swept_hulls(w, end, swept);
  hull.name = "tetrapage swept hull (yes/no)";
  hull.description = "FlyingObject::query, Motion::swept: the convex hull of the object at both poses";
  hull.extra["agreement"] = swept_agreement(mine, swept);
  std::printf("\n### Time of impact, %zu motions (pose i-1 -> i; FCL's conservative advancement: the first %zu; no "
              "untimed pass, the index is preloaded)\n\n", end - 1, ca_end - 1);
  std::printf("| row | steps/s | p50 us | p99 us | max us | tetrapage steps/s / row's | hits both / neither / only "
              "tetrapage / only FCL; FCL time < free_until / > contact_at; median / max |FCL time - contact_at| |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---|\n");
  print_row(tetrapage, tetrapage, std::to_string(tetrapage.extra["hits"].get<std::uint64_t>()) + " hits, " +
                                      std::to_string(tetrapage.extra["unresolved"].get<std::uint64_t>()) + " unresolved, " +
                                      std::to_string(tetrapage.extra["distance_queries_per_step"].get<double>()) +
                                      " distance queries per motion");
  for (const auto& row : rows)
    print_row(row, tetrapage, impact_agreement_text(row.extra["agreement"]) + "; " +
                                  std::to_string(row.extra["no_hit_but_end_pose_collides_for_fcl"].get<std::uint64_t>()) +
                                  " no-hit motions end in a pose fcl::collide finds colliding");
  const json& s = hull.extra["agreement"];
  print_row(hull, tetrapage, std::to_string(hull.extra["hits"].get<std::uint64_t>()) + " hits; hull yes without impact " +
                                 std::to_string(s["hull_hit_without_impact"].get<std::uint64_t>()) +
                                 ", impact the hull missed " + std::to_string(s["impact_missed_by_hull"].get<std::uint64_t>()));
  json out = {{"tetrapage", tetrapage.to_json()}, {"fcl", json::array()}, {"swept_hull", hull.to_json()}};
  for (const auto& row : rows) out["fcl"].push_back(row.to_json());
  return out;
}

// Every contact pair with its geometry: tetrapage's all_contacts query and contact_geometry per
// pair (exact topology; points, segments or polygons, both normals) against FCL's collide with
// enable_contact (a point, a normal and a penetration depth per pair, decided in floating point).
json run_contacts(const Workload& w, FclPeers& fcl) {
  constexpr std::size_t kMost = 1u << 20;
  FlyingObject flying(w.index, w.object);
  std::vector<std::size_t> mine(w.poses.size()), theirs(w.poses.size());
  QueryResult result;
  Row tetrapage;
  tetrapage.name = "tetrapage all_contacts + contact_geometry";
  tetrapage.description = "FlyingObject::query (all_contacts) and contact_geometry of every pair";
  tetrapage.seconds = time_steps(0, w.poses.size(), true, [&](std::size_t i) {
    flying.query(w.poses[i], QueryOptions{.mode = QueryMode::all_contacts}, result);
    std::size_t shapes = 0;
    for (const Contact& contact : result.contacts)
      shapes += flying.contact_geometry(contact).shape != geometry::ContactShape::none ? 1 : 0;
    mine[i] = shapes;
  });
  std::vector<Row> rows;
  for (auto& model : fcl.models) {
    Row row;
    row.name = std::string("FCL ") + to_string(model->volume()) + " collide, enable_contact";
    row.description = "fcl::collide with CollisionRequest(2^20, true): every contact";
    row.seconds = time_steps(0, w.poses.size(), true, [&](std::size_t i) { theirs[i] = model->contacts(w.poses[i], kMost); });
    std::uint64_t differ = 0, steps = 0, pairs_mine = 0, pairs_fcl = 0;
    for (std::size_t i = 0; i < w.poses.size(); ++i) {
      differ += mine[i] != theirs[i] ? 1 : 0;
      steps += mine[i] > 0 ? 1 : 0;
      pairs_mine += mine[i];
      pairs_fcl += theirs[i];
    }
    row.extra = {{"steps_with_contacts", steps}, {"steps_where_counts_differ", differ},
                 {"pairs_tetrapage", pairs_mine}, {"pairs_fcl", pairs_fcl}};
    rows.push_back(std::move(row));
  }
  std::printf("\n### Contacts with their geometry, %zu poses (one untimed pass before each timed one)\n\n",
              w.poses.size());
  std::printf("| row | steps/s | p50 us | p99 us | max us | tetrapage steps/s / row's | contact pairs tetrapage / FCL; "
              "steps whose counts differ (of steps with contacts) |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---|\n");
  print_row(tetrapage, tetrapage, "-");
  for (const auto& row : rows) {
    const json& e = row.extra;
    print_row(row, tetrapage,
              std::to_string(e["pairs_tetrapage"].get<std::uint64_t>()) + " / " +
                  std::to_string(e["pairs_fcl"].get<std::uint64_t>()) + "; " +
                  std::to_string(e["steps_where_counts_differ"].get<std::uint64_t>()) + " (of " +
                  std::to_string(e["steps_with_contacts"].get<std::uint64_t>()) + ")");
  }
  json out = {{"tetrapage", tetrapage.to_json()}, {"fcl", json::array()}};
  for (const auto& row : rows) out["fcl"].push_back(row.to_json());
  return out;
}

void run(const Arguments& args) {
  check_writable(args.report);
  if (args.max_distance && !(*args.max_distance >= 0)) throw InputError("--max-distance must be >= 0");
  // Single-threaded whatever the libraries would do with TBB.
  const oneapi::tbb::global_control one_thread(oneapi::tbb::global_control::max_allowed_parallelism, 1);
  Workload w;
  w.object = read_mesh(args.object);
  w.poses = read_poses(args.flight);
  if (w.poses.size() < 2) throw InputError(args.flight.string() + " holds fewer than two poses");

  auto start = Clock::now();
  CollisionIndexOptions index_options;
  index_options.memory_budget_bytes = kUnboundedBudget;
  auto index = std::make_shared<const CollisionIndex>(args.index, index_options);
  index->preload();  // every shard in memory: no row pays a page-in
  w.index = index;
  const double index_seconds = since(start);
  FclPeers fcl = build_fcl(args.scene, w.object);

  std::printf("%zu poses of %s (object %s, %zu triangles) against %s (index %s), single-threaded, in memory\n",
              w.poses.size(), args.flight.string().c_str(), args.object.string().c_str(), w.object.triangles.size(),
              args.scene.string().c_str(), args.index.string().c_str());
  std::printf("- build: tetrapage index open + preload %.2f s; FCL OBBRSS %.2f s (%.1f MiB), RSS %.2f s (%.1f MiB)\n",
              index_seconds, fcl.build_seconds[0], double(fcl.models[0]->structure_bytes()) / double(1 << 20),
              fcl.build_seconds[1], double(fcl.models[1]->structure_bytes()) / double(1 << 20));
  const json distance = run_distance(w, fcl, args);
  const json impact = run_impact(w, fcl, args);
  const json contacts = run_contacts(w, fcl);
  if (!args.report.empty())
    write_report(args.report, {{"command", "bench distance"},
                               {"scene", args.scene.string()},
                               {"object", args.object.string()},
                               {"object_triangles", w.object.triangles.size()},
                               {"flight", args.flight.string()},
                               {"index", args.index.string()},
                               {"steps", w.poses.size()},
                               {"index_open_seconds", index_seconds},
                               {"fcl_build_seconds", {{"OBBRSS", fcl.build_seconds[0]}, {"RSS", fcl.build_seconds[1]}}},
                               {"fcl_structure_bytes",
                                {{"OBBRSS", fcl.models[0]->structure_bytes()}, {"RSS", fcl.models[1]->structure_bytes()}}},
                               {"distance", distance},
                               {"time_of_impact", impact},
                               {"contacts", contacts}});
}

}  // namespace
}  // namespace tetrapage

int main(int argc, char** argv) {
  using namespace tetrapage;
  CLI::App app{
      "Distance and time of impact on the same poses: tetrapage's FlyingObject::distance and time_of_impact (index\n"
      "in memory) against FCL 0.7's fcl::distance and fcl::continuousCollide (BVHModel<OBBRSS> and <RSS>), and the\n"
      "swept-hull query; single-threaded. Prints steps per second, latency and agreement."};
  Arguments args;
  app.add_option("scene", args.scene, "Environment: mesh file or manifest (what the index was made from)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("object", args.object, "Flying object mesh")->required()->check(CLI::ExistingFile);
  app.add_option("flight", args.flight, "Pose file (CSV tx,ty,tz,qw,qx,qy,qz)")->required()->check(CLI::ExistingFile);
  app.add_option("index", args.index, "The scene's index (.tpi)")->required()->check(CLI::ExistingFile);
  app.add_option("--max-distance", args.max_distance, "Also time tetrapage's distance bounded by this (FCL has no bound)");
  app.add_option("--impact-steps", args.impact_steps, "Time of impact on the first N motions only (0: all)");
  app.add_option("--fcl-ca-steps", args.fcl_ca_steps,
                 "FCL's conservative advancement on the first N motions only (default 10: it is slow)");
  app.add_option("--naive-samples", args.naive_samples, "Times sampled by FCL's naive continuous collision (default 10)")
      ->check(CLI::Range(std::size_t(2), std::size_t(10000)));
  app.add_option("--report", args.report, "Write the figures as JSON");
  try {
    app.parse(argc, argv);
    run(args);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tetrapage_bench_distance: %s\n", e.what());
    return 1;
  }
  return 0;
}
