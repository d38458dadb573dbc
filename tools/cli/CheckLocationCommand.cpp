// `tetrapage check-location`: the runtime's point location against Embree (LocationCheck.h).

#include <chrono>
#include <cstdio>
#include <thread>

#include "Commands.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/index/IndexReader.h"
#include "tetrapage/tools/EmbreeMeshFaces.h"
#include "tetrapage/tools/LocationCheck.h"

namespace tetrapage::cli {
namespace {

struct CheckLocationArguments {
  std::filesystem::path index, report;
  std::uint64_t points = 1'000'000;
  std::uint64_t seed = 1;
  unsigned threads = 0;
};

std::string embree_answer(const LocationDisagreement& d) {
  std::string text;
  for (std::uint32_t t : d.embree_tets) text += (text.empty() ? "tet " : ", tet ") + std::to_string(t);
  if (d.embree_outside) text += text.empty() ? "outside" : ", outside";
  return text.empty() ? "nothing" : text;
}

void run_check_location(const CheckLocationArguments& args) {
  check_outputs_writable({args.report}, {args.index});
  const IndexReader reader(args.index);
  const TetMesh mesh = reader.read_mesh();
  const auto build_start = std::chrono::steady_clock::now();
  const EmbreeMeshFaces faces(mesh, args.threads);
  const double build_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - build_start).count();
  LocationPointOptions point_options;
  point_options.points = args.points;
  point_options.seed = args.seed;
  const auto draw_start = std::chrono::steady_clock::now();
  const LocationPointSet set = make_location_points(mesh, point_options);
  const double draw_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - draw_start).count();

  LocationCheckOptions check_options;
  check_options.threads = args.threads;
  check_options.progress = true;
  const LocationCheckSummary summary =
      check_locations(faces, set.points, runtime_locator(mesh), check_options);

  const unsigned threads = args.threads > 0 ? args.threads : std::thread::hardware_concurrency();
  std::printf("check-location %s: %zu tets, %zu faces in the Embree scene (built in %.3f s)\n",
              args.index.c_str(), mesh.tet_count(), faces.faces().size(), build_seconds);
  std::printf("points: %zu, seed %llu, drawn in %.2f s: random %llu (in the mesh box grown by %.1f%% per side), "
              "on faces %llu (%llu distinct, exact, of %llu tried), on edges %llu (%llu distinct, exact, of %llu tried), "
              "on vertices %llu (%llu distinct)\n",
              set.points.size(), (unsigned long long)args.seed, draw_seconds,
              (unsigned long long)set.count[0], 100 * point_options.outside_margin,
              (unsigned long long)set.count[1], (unsigned long long)set.distinct[1],
              (unsigned long long)set.attempts[1], (unsigned long long)set.count[2],
              (unsigned long long)set.distinct[2], (unsigned long long)set.attempts[2],
              (unsigned long long)set.count[3], (unsigned long long)set.distinct[3]);
  if (set.points.size() < args.points)
    std::printf("(exact points on faces or edges are rare on this mesh: %llu fewer points than asked)\n",
                (unsigned long long)(args.points - set.points.size()));
  for (std::size_t k = 0; k < kLocationPointKinds; ++k) {
    const LocationOutcomes& o = summary.by_kind[k];
    std::printf("  %-9s %9llu points: same tet %llu, ties decided by the exact predicates %llu, "
                "outside for both (proven by a hull face) %llu, disagreements %llu; "
                "Embree traces resynced %llu, ending with a choice %llu\n",
                to_string(LocationPointKind(k)), (unsigned long long)o.points,
                (unsigned long long)o.same_tet, (unsigned long long)o.exact_ties,
                (unsigned long long)o.outside, (unsigned long long)o.disagreements,
                (unsigned long long)o.resynced_traces, (unsigned long long)o.ambiguous_ends);
  }
  std::printf("Embree: %llu faces hit (%.1f per segment), %llu traces resynced, %llu ending with a choice of tets\n",
              (unsigned long long)summary.faces_hit,
              double(summary.faces_hit) / double(std::max<std::uint64_t>(1, summary.points)),
              (unsigned long long)summary.resynced_traces, (unsigned long long)summary.ambiguous_ends);
  const double points_per_second = summary.seconds > 0 ? double(summary.points) / summary.seconds : 0;
  std::printf("checked in %.2f s: %.0f points/s (%u threads; Embree trace + runtime walk + exact verdict)\n",
              summary.seconds, points_per_second, threads);
  for (const LocationDisagreement& d : summary.listed) {
    const std::string located =
        d.located_tet == TetMesh::no_neighbour ? "outside" : "tet " + std::to_string(d.located_tet);
    std::printf("disagreement: %s point (%.17g, %.17g, %.17g): located %s, Embree %s: %s\n",
                to_string(d.kind), d.point[0], d.point[1], d.point[2], located.c_str(),
                embree_answer(d).c_str(), d.reason.c_str());
  }
  if (summary.listed.size() < summary.disagreements)
    std::printf("(%llu more disagreements not listed)\n",
                (unsigned long long)(summary.disagreements - summary.listed.size()));
  std::printf("disagreements: %llu\n", (unsigned long long)summary.disagreements);
  std::fflush(stdout);

  if (!args.report.empty()) {
    nlohmann::json kinds = nlohmann::json::object();
    for (std::size_t k = 0; k < kLocationPointKinds; ++k) {
      const LocationOutcomes& o = summary.by_kind[k];
      kinds[to_string(LocationPointKind(k))] = {{"points", o.points},
                                                {"distinct", set.distinct[k]},
                                                {"attempts", set.attempts[k]},
                                                {"same_tet", o.same_tet},
                                                {"exact_ties", o.exact_ties},
                                                {"outside", o.outside},
                                                {"disagreements", o.disagreements},
                                                {"resynced_traces", o.resynced_traces},
                                                {"ambiguous_ends", o.ambiguous_ends}};
    }
    nlohmann::json listed = nlohmann::json::array();
    for (const LocationDisagreement& d : summary.listed)
      listed.push_back({{"kind", to_string(d.kind)},
                        {"point", {d.point[0], d.point[1], d.point[2]}},
                        {"located_tet", d.located_tet == TetMesh::no_neighbour ? nlohmann::json(nullptr)
                                                                                : nlohmann::json(d.located_tet)},
                        {"embree_tets", d.embree_tets},
                        {"embree_outside", d.embree_outside},
                        {"reason", d.reason}});
    write_report(args.report, {{"index", args.index.string()},
                               {"tets", mesh.tet_count()},
                               {"faces", faces.faces().size()},
                               {"seed", args.seed},
                               {"points", summary.points},
                               {"by_kind", kinds},
                               {"disagreements", summary.disagreements},
                               {"disagreement_list", listed},
                               {"faces_hit", summary.faces_hit},
                               {"resynced_traces", summary.resynced_traces},
                               {"ambiguous_ends", summary.ambiguous_ends},
                               {"threads", threads},
                               {"seconds", summary.seconds},
                               {"points_per_second", points_per_second}});
  }
  if (summary.disagreements > 0)
    throw Error(args.index.string() + ": " + std::to_string(summary.disagreements) +
                " points located differently by the runtime and by Embree");
}

}  // namespace

void add_check_location_command(CLI::App& app) {
  auto args = std::make_shared<CheckLocationArguments>();
  auto* command = app.add_subcommand(
      "check-location",
      "Check the runtime's point location (the walk) against Embree: random points in and\n"
      "around the mesh and points placed exactly on its faces, edges and vertices; a segment\n"
      "from a known tet to each point is shot through an Embree scene of the mesh's faces and\n"
      "the faces it crosses name the tet. Ties (points on or within float error of a shared\n"
      "face, edge or vertex) are decided by the exact point-in-tet predicate.\n"
      "Prints `disagreements: K` and exits 0 only when K == 0.");
  command->add_option("index", args->index, "Index file (.tpi)")
      ->required()
      ->check(existing_file_check());
  command
      ->add_option("--points", args->points,
                   "Points to check: half random, 20% on faces, 20% on edges, 10% on vertices")
      ->capture_default_str()
      ->check(whole_number_check(1, kMostPoints));
  command->add_option("--seed", args->seed, "Seed of the points and start tets")
      ->capture_default_str()
      ->check(seed_check());
  command->add_option("--threads", args->threads, "Worker threads (0: all cores)")
      ->capture_default_str()
      ->check(whole_number_check(0, kMostThreads));
  command->add_option("--report", args->report, "Write the figures and every disagreement as JSON");
  command->callback([args] { run_check_location(*args); });
}

}  // namespace tetrapage::cli
