// `tetrapage check-interiors`: the runtime's inside/outside answers (stored interiors + crossings
// within one tet) against the CGAL oracle's, which finds the connected components, their
// closedness and insides by its own means, for random points in the model's box and in every
// closed component's box; and the components the index lists against the oracle's.

#include <chrono>
#include <cstdio>
#include <sstream>

#include "Commands.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/Progress.h"
#include "tetrapage/formats/mesh/Manifest.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/runtime/query/ObstacleInterior.h"
#include "tetrapage/tools/IndexAudit.h"
#include "tetrapage/tools/Random.h"
#include "tetrapage/tools/ReferenceCollider.h"

namespace tetrapage::cli {
namespace {

struct InteriorCheckArguments {
  std::filesystem::path index;
  std::vector<std::filesystem::path> inputs;
  std::uint64_t points = 100000;
  std::uint64_t seed = 1;
  std::filesystem::path report;
};

void run_check_interiors(const InteriorCheckArguments& args) {
  check_outputs_writable({args.report}, {args.index});
  auto index = std::make_shared<const CollisionIndex>(args.index);
  if (!index->has_interiors())
    throw InputError(args.index.string() +
                     ": the index stores no interiors (preprocess it with --interiors on)");
  const std::vector<std::filesystem::path> inputs =
      args.inputs.empty() ? source_inputs(index->header(), args.index) : args.inputs;
  TriangleSoup environment;
  for (const auto& input : inputs)
    environment.append(is_manifest_path(input) ? load_assembly(read_manifest(input))
                                               : read_mesh(input));
  if (environment.triangle_count() != index->header().input_triangles)
    throw InputError("the inputs hold " + std::to_string(environment.triangle_count()) +
                     " triangles, the index " + std::to_string(index->header().input_triangles) +
                     ": not the model of " + args.index.string());
  TriangleSoup probe;  // the oracle wants an object; only its parity query is used
  probe.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  probe.triangles = {{0, 1, 2}};
  probe.part_of = {0};
  probe.part_names = {"probe"};
  const ReferenceCollider oracle(environment, probe);
  std::vector<std::uint32_t> closed;
  for (std::uint32_t c = 0; c < index->component_count(); ++c)
    if (index->component_closed(c)) closed.push_back(c);
  const std::uint64_t closed_components = closed.size();
  std::uint64_t disagreements = 0;
  std::printf("components: index %u (%llu closed), oracle %zu (%zu closed)\n", index->component_count(),
              (unsigned long long)closed_components, oracle.environment_components(),
              oracle.environment_closed_components());
  if (index->component_count() != oracle.environment_components() ||
      closed_components != oracle.environment_closed_components()) {
    std::printf("disagreement: the index and the oracle count different components\n");
    ++disagreements;
  }
  // Half the points in the model's box, half in the closed components' boxes, in turn: every
  // closed component is probed, however small.
  const BoundingBox model_box = index->header().bounds;
  Random random(args.seed);
  std::uint32_t hint = 0;
  std::uint64_t inside = 0, unknown = 0, on_surface = 0;
  double runtime_seconds = 0;
  Progress progress("checking points", args.points, true);
  for (std::uint64_t i = 0; i < args.points; ++i) {
    const BoundingBox& box =
        i % 2 == 0 || closed.empty() ? model_box : index->component_bounds(closed[(i / 2) % closed.size()]);
    geometry::Point p;
    for (int a = 0; a < 3; ++a) p[a] = random.uniform(box.lo[a], box.hi[a]);
    const auto start = std::chrono::steady_clock::now();
    const ObstacleQuery answer = locate_in_obstacles(*index, hint, p);
    runtime_seconds +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (answer.containment == ObstacleContainment::unknown)
      ++unknown;
    else if (answer.containment == ObstacleContainment::on_surface)
      ++on_surface;
    else {
      const bool runtime_inside = answer.containment == ObstacleContainment::inside;
      const bool oracle_inside = oracle.inside_environment(p);
      inside += oracle_inside;
      if (runtime_inside != oracle_inside && ++disagreements <= 20)
        std::printf("disagreement at (%.17g, %.17g, %.17g): runtime %s, oracle %s\n", p[0], p[1],
                    p[2], runtime_inside ? "inside" : "outside",
                    oracle_inside ? "inside" : "outside");
    }
    if (i % 4096 == 0) progress.advance(std::min<std::uint64_t>(4096, args.points - i));
  }
  progress.finish();
  std::printf(
      "points %llu: inside %llu, unknown %llu (undecided tets or degenerate paths), on a surface "
      "%llu; "
      "runtime %.2f us/point\n",
      (unsigned long long)args.points, (unsigned long long)inside, (unsigned long long)unknown,
      (unsigned long long)on_surface,
      args.points ? runtime_seconds / double(args.points) * 1e6 : 0.0);
  std::printf("disagreements: %llu\n", (unsigned long long)disagreements);
  if (!args.report.empty())
    write_report(args.report, {{"index", args.index.string()},
                               {"points", args.points},
                               {"inside", inside},
                               {"unknown", unknown},
                               {"on_surface", on_surface},
                               {"disagreements", disagreements},
                               {"runtime_us_per_point",
                                args.points ? runtime_seconds / double(args.points) * 1e6 : 0.0}});
  if (disagreements > 0)
    throw Error(std::to_string(disagreements) + " disagreements between the runtime and the oracle");
}

}  // namespace

void add_interior_check_command(CLI::App& app) {
  auto args = std::make_shared<InteriorCheckArguments>();
  auto* command = app.add_subcommand(
      "check-interiors",
      "Check the index's interiors: for random points in the model's box and in each closed\n"
      "component's box, the runtime's inside/outside answer (stored reference points + crossings\n"
      "within one tet) against the CGAL oracle (its own components, closedness by is_closed,\n"
      "insides by Side_of_triangle_mesh); and the index's components against the oracle's.\n"
      "Prints `disagreements: K`; exits 0 only when K is 0.");
  command->add_option("index", args->index, "Index file (.tpi), preprocessed with --interiors on")
      ->required()
      ->check(existing_file_check());
  command
      ->add_option("inputs", args->inputs,
                   "The model's mesh files or manifests (default: those preprocess read)")
      ->check(existing_file_check());
  command
      ->add_option("--points", args->points,
                   "Random points (half in the model's box, half in closed components' boxes)")
      ->capture_default_str()
      ->check(whole_number_check(1, kMostPoints));
  command->add_option("--seed", args->seed, "Seed of the points")
      ->capture_default_str()
      ->check(seed_check());
  command->add_option("--report", args->report, "Write the figures as JSON");
  command->callback([args] { run_check_interiors(*args); });
}

}  // namespace tetrapage::cli
