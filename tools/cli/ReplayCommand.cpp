// `tetrapage replay`: fly a pose file through a mesh in core with a reference collider.

#include <chrono>
#include <cstdio>
#include <optional>

#include "Commands.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/MemoryUsage.h"
#include "tetrapage/formats/mesh/Manifest.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/tools/AnswerCheck.h"
#include "tetrapage/tools/AnswerFile.h"
#include "tetrapage/tools/EmbreeCollider.h"
#include "tetrapage/tools/LatencySummary.h"
#include "tetrapage/tools/ReferenceCollider.h"

namespace tetrapage::cli {
namespace {

struct ReplayArguments {
  std::filesystem::path environment, object, path, answers, check, report;
  std::string reference = "cgal";
  unsigned threads = 0;
};

// One reference's answer to one pose, as the replay loop counts it.
struct StepAnswer {
  bool collides = false;
  bool object_inside = false;    // the object inside a closed part (the oracle only)
  bool obstacle_inside = false;  // an environment triangle inside the closed object (idem)
  std::uint64_t candidates = 0;
};

void run_replay(const ReplayArguments& args) {
  check_outputs_writable({args.answers, args.report}, {args.environment, args.object, args.path, args.check});
  const bool embree = args.reference == "embree";
  const TriangleSoup environment = load_inputs({args.environment});
  const TriangleSoup object = load_inputs({args.object});  // a mesh, STEP file or manifest
  const std::vector<Pose> poses = read_poses(args.path);
  AnswerCheck check(args.check, poses.size(), embree ? "embree" : "reference");

  // Only the chosen reference is built; its build time is what the report calls build time.
  std::optional<ReferenceCollider> oracle;
  std::optional<EmbreeCollider> embree_collider;
  const auto build_start = std::chrono::steady_clock::now();
  if (embree)
    embree_collider.emplace(environment, object, args.threads);
  else
    oracle.emplace(environment, object);
  const double build_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - build_start).count();
  const auto answer_pose = [&](const Pose& pose) {
    if (embree) {
      const auto answer = embree_collider->query(pose);
      return StepAnswer{answer.surfaces_touch, false, false, answer.candidate_pairs};
    }
    const auto answer = oracle->query(pose);
    return StepAnswer{answer.collides, answer.object_inside, answer.obstacle_inside, answer.candidates};
  };

  std::vector<std::uint8_t> answers(poses.size());
  std::vector<double> seconds(poses.size());
  std::uint64_t collisions = 0, inside = 0, swallowed = 0, candidates = 0;
  Progress progress(embree ? "replaying (Embree rtcCollide)" : "replaying (reference)", poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const auto start = std::chrono::steady_clock::now();
    const StepAnswer answer = answer_pose(poses[i]);
    seconds[i] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    answers[i] = answer.collides ? 1 : 0;
    collisions += answers[i];
    inside += answer.object_inside ? 1 : 0;
    swallowed += answer.obstacle_inside ? 1 : 0;
    candidates += answer.candidates;
    check.record(i, answers[i]);
    progress.advance();
  }
  progress.finish();
  double total = 0;
  for (double s : seconds) total += s;
  const double steps_per_second = total > 0 ? double(poses.size()) / total : 0;
  const double mean_candidates = poses.empty() ? 0 : double(candidates) / double(poses.size());
  const auto latency = LatencySummary::of(seconds);
  if (embree)
    std::printf(
        "replay (Embree rtcCollide, exact pair tests, in core): %zu steps, %llu collisions "
        "(surfaces touching; one body wholly inside the other is not seen)\n"
        "%.1f candidate pairs per step\n",
        poses.size(), static_cast<unsigned long long>(collisions), mean_candidates);
  else
    std::printf(
        "replay (reference oracle, in core): %zu steps, %llu collisions (%llu with the object "
        "inside an obstacle, %llu with an obstacle inside the object)\n"
        "%.1f candidate triangles per step\n",
        poses.size(), static_cast<unsigned long long>(collisions),
        static_cast<unsigned long long>(inside), static_cast<unsigned long long>(swallowed), mean_candidates);
  std::printf("%.0f steps/s, latency p50 %.1f us, p95 %.1f us, p99 %.1f us, max %.1f us; %s build %.2f s\n",
              steps_per_second, latency.p50_us, latency.p95_us, latency.p99_us, latency.max_us,
              embree ? "Embree scene" : "tree", build_seconds);
  if (!args.answers.empty()) write_answers(args.answers, answers);
  if (!args.report.empty()) {
    nlohmann::json report{{"command", "replay"},
                          {"reference", args.reference},
                          {"steps", poses.size()},
                          {"collisions", collisions},
                          {"candidates_per_step", mean_candidates},
                          {"steps_per_second", steps_per_second},
                          {"latency_us", latency.to_json()},
                          {"build_seconds", build_seconds},
                          {"peak_rss_bytes", peak_resident_bytes()}};
    // Embree sees surfaces only: the containments are the oracle's figures.
    if (!embree) {
      report["object_inside"] = inside;
      report["obstacle_inside"] = swallowed;
    }
    if (check.checking()) report["disagreements"] = check.disagreements();
    write_report(args.report, report);
  }
  check.finish();
}

}  // namespace

void add_replay_command(CLI::App& app) {
  auto args = std::make_shared<ReplayArguments>();
  auto* command = app.add_subcommand(
      "replay",
      "Fly a pose file through a mesh in core with a reference collider and print steps per\n"
      "second, latency percentiles and collisions. References: the exact oracle (CGAL\n"
      "AABB_tree, exact predicates; default) or Embree's rtcCollide with exact pair tests.");
  command->add_option("environment", args->environment, "Environment: mesh file or manifest")
      ->required()
      ->check(existing_file_check());
  command->add_option("--object", args->object, "Flying object: a mesh, a STEP or IGES file, or a manifest (.json)")
      ->required()
      ->check(existing_file_check());
  command->add_option("--path", args->path, "Pose file (CSV tx,ty,tz,qw,qx,qy,qz)")
      ->required()
      ->check(existing_file_check());
  command->add_option("--answers", args->answers, "Write the answers (CSV step,collides)");
  command
      ->add_option("--check", args->check,
                   "Compare with these answers; exit non-zero on any disagreement")
      ->check(existing_file_check());
  command->add_option("--reference", args->reference,
                      "cgal: the exact oracle (surfaces touch, or one body inside the other);\n"
                      "embree: rtcCollide candidates decided exactly (surfaces touch only)")
      ->check(CLI::IsMember({"cgal", "embree"}));
  command->add_option("--threads", args->threads, "Embree's threads (0: all; --reference embree)")
      ->check(whole_number_check(0, kMostThreads));
  command->add_option("--report", args->report, "Write figures as JSON");
  command->callback([args] { run_replay(*args); });
}

}  // namespace tetrapage::cli
