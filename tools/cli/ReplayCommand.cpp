// `tetrapage replay`: fly a pose file through a mesh in core with the reference oracle.

#include <chrono>
#include <cstdio>

#include "Commands.h"
#include "tetrapage/formats/MemoryUsage.h"
#include "tetrapage/formats/Error.h"
#include "tetrapage/formats/Manifest.h"
#include "tetrapage/formats/MeshReader.h"
#include "tetrapage/tools/AnswerCheck.h"
#include "tetrapage/tools/AnswerFile.h"
#include "tetrapage/tools/LatencySummary.h"
#include "tetrapage/tools/ReferenceCollider.h"

namespace tetrapage::cli {
namespace {

struct ReplayArguments {
  std::filesystem::path environment, object, path, answers, check, report;
};

void run_replay(const ReplayArguments& args) {
  for (const auto* output : {&args.answers, &args.report}) check_writable(*output);
  const TriangleSoup environment = load_inputs({args.environment});
  const TriangleSoup object = read_mesh(args.object);
  const std::vector<Pose> poses = read_poses(args.path);
  AnswerCheck check(args.check, poses.size(), "reference");
  const auto build_start = std::chrono::steady_clock::now();
  const ReferenceCollider oracle(environment, object);
  const double build_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - build_start).count();

  std::vector<std::uint8_t> answers(poses.size());
  std::vector<double> seconds(poses.size());
  std::uint64_t collisions = 0, inside = 0;
  Progress progress("replaying (reference)", poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const auto start = std::chrono::steady_clock::now();
    const auto answer = oracle.query(poses[i]);
    seconds[i] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    answers[i] = answer.collides ? 1 : 0;
    collisions += answers[i];
    inside += answer.object_inside ? 1 : 0;
    check.record(i, answers[i]);
    progress.advance();
  }
  progress.finish();
  double total = 0;
  for (double s : seconds) total += s;
  const double steps_per_second = total > 0 ? double(poses.size()) / total : 0;
  const auto latency = LatencySummary::of(seconds);
  std::printf(
      "replay (reference oracle, in core): %zu steps, %llu collisions (%llu with the object "
      "inside an obstacle)\n"
      "%.0f steps/s, latency p50 %.1f us, p95 %.1f us, p99 %.1f us, max %.1f us; tree build %.2f s\n",
      poses.size(), static_cast<unsigned long long>(collisions),
      static_cast<unsigned long long>(inside), steps_per_second, latency.p50_us, latency.p95_us,
      latency.p99_us, latency.max_us, build_seconds);
  if (!args.answers.empty()) write_answers(args.answers, answers);
  if (!args.report.empty())
    write_report(args.report, {{"command", "replay"},
                               {"steps", poses.size()},
                               {"collisions", collisions},
                               {"object_inside", inside},
                               {"steps_per_second", steps_per_second},
                               {"latency_us", latency.to_json()},
                               {"build_seconds", build_seconds},
                               {"disagreements", check.disagreements()},
                               {"peak_rss_bytes", peak_resident_bytes()}});
  check.finish();
}

}  // namespace

void add_replay_command(CLI::App& app) {
  auto args = std::make_shared<ReplayArguments>();
  auto* command = app.add_subcommand(
      "replay",
      "Fly a pose file through a mesh in core with the reference oracle (CGAL AABB_tree,\n"
      "exact predicates) and print steps per second, latency percentiles and collisions.");
  command->add_option("environment", args->environment, "Environment: mesh file or manifest")
      ->required()
      ->check(CLI::ExistingFile);
  command->add_option("--object", args->object, "Flying object mesh")->required()->check(CLI::ExistingFile);
  command->add_option("--path", args->path, "Pose file (CSV tx,ty,tz,qw,qx,qy,qz)")
      ->required()
      ->check(CLI::ExistingFile);
  command->add_option("--answers", args->answers, "Write the answers (CSV step,collides)");
  command->add_option("--check", args->check,
                      "Compare with these answers; exit non-zero on any disagreement")
      ->check(CLI::ExistingFile);
  command->add_option("--report", args->report, "Write figures as JSON");
  command->callback([args] { run_replay(*args); });
}

}  // namespace tetrapage::cli
