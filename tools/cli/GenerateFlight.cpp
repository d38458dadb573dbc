// `tetrapage generate flight`: a billiard path decided by the reference oracle.

#include <chrono>
#include <cstdio>

#include "Commands.h"
#include "tetrapage/formats/base/ByteSize.h"
#include "tetrapage/formats/base/MemoryUsage.h"
#include "tetrapage/formats/mesh/Manifest.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/tools/AnswerFile.h"
#include "tetrapage/tools/FlightGenerator.h"
#include "tetrapage/tools/LatencySummary.h"
#include "tetrapage/tools/RuntimeJudge.h"

namespace tetrapage::cli {
namespace {

struct FlightArguments {
  std::filesystem::path environment, index, object, output, answers, report;
  std::string memory;  // add_memory_option sets the default
  FlightOptions options;
};

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The judge: the reference oracle over the environment, or the exact runtime over the index
// (paged under --memory) for models too large for the oracle.
struct Judge {
  std::unique_ptr<ReferenceCollider> oracle;
  std::unique_ptr<CollisionJudge> runtime;
};

Judge make_judge(const FlightArguments& args, const TriangleSoup& environment,
                 const TriangleSoup& object) {
  Judge judge;
  if (!args.environment.empty()) {
    judge.oracle = std::make_unique<ReferenceCollider>(environment, object);
    return judge;
  }
  CollisionIndexOptions index_options;
  index_options.memory_budget_bytes = parse_byte_size(args.memory);
  judge.runtime = std::make_unique<RuntimeJudge>(
      std::make_shared<const CollisionIndex>(args.index, index_options), object);
  return judge;
}

void run_generate_flight(const FlightArguments& args) {
  check_outputs_writable({args.output, args.answers, args.report}, {args.environment, args.index, args.object});
  if (args.environment.empty() == args.index.empty())
    throw InputError(args.environment.empty() ? "generate flight: give the environment (--env) or an index (--index)"
                                              : "generate flight: give --env or --index, not both");
  const auto start = std::chrono::steady_clock::now();
  std::vector<ReadReport> reports;
  TriangleSoup environment;
  if (!args.environment.empty()) {
    Progress reading("reading environment", 0);
    environment = load_inputs({args.environment}, &reports, reading);
    reading.finish();
  }
  const TriangleSoup object = load_inputs({args.object});  // a mesh, STEP file or manifest
  const double read_seconds = seconds_since(start);

  const auto build_start = std::chrono::steady_clock::now();
  const Judge judge = make_judge(args, environment, object);
  const auto& oracle = judge.oracle;
  const double build_seconds = seconds_since(build_start);

  Progress flying(oracle ? "flying (reference)" : "flying (runtime)", args.options.steps);
  const auto fly_start = std::chrono::steady_clock::now();
  const Flight flight = oracle ? generate_billiard_flight(*oracle, args.options, flying)
                               : generate_billiard_flight(*judge.runtime, args.options, flying);
  const double fly_seconds = seconds_since(fly_start);

  write_poses(args.output, flight.poses);
  if (!args.answers.empty()) write_answers(args.answers, flight.collides);

  double query_total = 0;
  for (double s : flight.query_seconds) query_total += s;
  const double steps_per_second = query_total > 0 ? double(flight.poses.size()) / query_total : 0;
  const auto latency = LatencySummary::of(flight.query_seconds);
  std::printf(
      "flight: %zu poses, %.9g model units per step (%s), at most %g radians; %llu collisions, "
      "%llu wall bounces, start after %llu attempts\n"
      "%s: %.0f steps/s, latency p50 %.1f us, p99 %.1f us, max %.1f us\n"
      "environment %zu triangles (read %.2f s, judge built in %.2f s), object %zu triangles; "
      "flight %.2f s\n"
      "wrote %s\n",
      flight.poses.size(), flight.displacement,
      args.options.displacement ? "--displacement" : "the environment's diagonal / 346",
      args.options.max_rotation, static_cast<unsigned long long>(flight.collisions),
      static_cast<unsigned long long>(flight.boundary_reversals),
      static_cast<unsigned long long>(flight.start_attempts),
      oracle ? "reference oracle (CGAL AABB_tree, exact predicates)" : "runtime (exact, paged)",
      steps_per_second, latency.p50_us, latency.p99_us, latency.max_us,
      oracle ? environment.triangle_count() : std::size_t(0), read_seconds, build_seconds,
      object.triangle_count(), fly_seconds, args.output.c_str());
  if (!args.report.empty()) {
    nlohmann::json report{{"command", "generate flight"},
                          {"judge", oracle ? "reference oracle" : "runtime"},
                          {"object", args.object.string()},
                          {"seed", args.options.seed},
                          {"steps", flight.poses.size()},
                          {"displacement", flight.displacement},
                          {"displacement_default", !args.options.displacement},
                          {"max_rotation", args.options.max_rotation},
                          {"collisions", flight.collisions},
                          {"boundary_reversals", flight.boundary_reversals},
                          {"start_attempts", flight.start_attempts},
                          {"steps_per_second", steps_per_second},
                          {"latency_us", latency.to_json()},
                          {"object_triangles", object.triangle_count()},
                          {"read_seconds", read_seconds},
                          {"build_seconds", build_seconds},
                          {"flight_seconds", fly_seconds},
                          {"peak_rss_bytes", peak_resident_bytes()}};
    // The oracle reads the environment; the runtime pages the index under --memory.
    if (oracle) {
      report["environment"] = args.environment.string();
      report["environment_triangles"] = environment.triangle_count();
    } else {
      report["index"] = args.index.string();
      report["budget_bytes"] = parse_byte_size(args.memory);
    }
    write_report(args.report, report);
  }
}

}  // namespace

void add_generate_flight_command(CLI::App& generate) {
  auto args = std::make_shared<FlightArguments>();
  auto* command = generate.add_subcommand(
      "flight",
      "Billiard flight (the study's section 4.1): the object starts at a random collision-free\n"
      "placement, moves --displacement per step with randomly perturbed direction and spin,\n"
      "reverses on collision and bounces off the environment's bounding box. Lengths are in the\n"
      "model's units (those of the environment and object files): by default a step is the\n"
      "environment's bounding-box diagonal / 346 (the study's 0.005 in its unit cube), so a\n"
      "model in millimetres flies as it would in metres. Collisions are decided by the\n"
      "reference oracle (CGAL AABB_tree, exact predicates), or with --index by tetrapage's exact\n"
      "runtime. Writes poses as CSV `tx,ty,tz,qw,qx,qy,qz` (translations in model units); the\n"
      "same seed gives the same file.");
  command->add_option("--env", args->environment, "Environment: a mesh file or a manifest (.json)")
      ->check(existing_file_check());
  command
      ->add_option(
          "--index", args->index,
          "Instead of --env: an index (.tpi), collisions decided by tetrapage's exact runtime "
          "(for models too large for the in-core oracle, ~150 B a triangle)")
      ->check(existing_file_check());
  add_memory_option(command, args->memory, "With --index: the runtime's budget of decoded shards");
  command->add_option("--object", args->object, "Flying object: a mesh, a STEP or IGES file, or a manifest (.json); its own frame, the "
                      "environment's units")
      ->required()
      ->check(existing_file_check());
  command->add_option("--steps", args->options.steps, "Number of poses written")
      ->capture_default_str()
      ->check(whole_number_check(1, 1ll << 32));
  command->add_option("--seed", args->options.seed, "Random seed")
      ->capture_default_str()
      ->check(seed_check());
  command
      ->add_option("--displacement", args->options.displacement,
                   "Distance moved per step, in model units. Default: the diagonal of the "
                   "environment's bounding box / 346 (0.005 for the unit cube)")
      ->check(positive_number_check(kLongestLength));
  command
      ->add_option("--max-rotation", args->options.max_rotation,
                   "Largest rotation per step, in radians")
      ->capture_default_str()
      ->check(number_check(0, 3.14159265358979));
  command->add_option("-o,--output", args->output, "Pose file to write (CSV)")->required();
  command->add_option("--answers", args->answers,
                      "Also write the oracle's answers (CSV `step,collides`)");
  command->add_option("--report", args->report, "Write figures as JSON");
  command->callback([args] { run_generate_flight(*args); });
}

}  // namespace tetrapage::cli
