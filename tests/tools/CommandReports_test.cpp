// The commands' --report files hold a key only where it means something: figures of a feature
// the run did not use (a --check, --contacts, --preload, --obstacles, the prefetcher, float
// storage, interiors, the oracle's containments, a replay) are absent, not zeros, and present
// when the feature was used; a --memory not given is kDefaultMemoryBudget.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "../ResidentMemory.h"
#include "RunCli.h"
#include "TestFiles.h"
#include "tetrapage/formats/base/ByteSize.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/runtime/paging/CollisionIndex.h"
#include "tetrapage/runtime/query/DynamicObstacles.h"
#include "tetrapage/runtime/query/ObjectModel.h"

namespace tetrapage {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// One small model for every test: BSP boxes of tetrahedra (closed, so interiors are stored), a
// billiard flight with the oracle's answers, the index in double and in float.
class CommandReports : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // ctest runs each test in a process of its own, in parallel: one folder per process.
    folder_ = test::fresh_folder("command-reports", std::to_string(::getpid()));
    for (const std::string command :
         {"generate tetras --triangles 2000 --seed 5 -o environment.obj",
          "generate object --triangles 200 -o object.ply",
          "generate flight --env environment.obj --object object.ply --steps 300 --seed 5 -o "
          "flight.csv "
          "--answers answers.csv --report flight-env.json",
          "preprocess environment.obj -o double.tpi --precision double --threads 1 "
          "--region-triangles 200 "
          "--report preprocess-double.json",
          "preprocess environment.obj -o float.tpi --precision float --interiors off --threads 1 "
          "--region-triangles 200 --report preprocess-float.json",
          // One closed solid with tets inside it (the tetras' tiny solids may hold none).
          "preprocess object.ply -o solid.tpi --threads 1 --region-triangles 50 "
          "--report preprocess-solid.json"}) {
      const test::CliResult run = test::run_cli_in(folder_, command);
      ASSERT_EQ(run.status, 0) << command << ": " << run.err;
    }
  }

  static void TearDownTestSuite() { fs::remove_all(folder_); }

  // Runs a command that writes --report r.json and returns the report.
  static json report_of(const std::string& command) {
    fs::remove(folder_ / "r.json");
    const test::CliResult run = test::run_cli_in(folder_, command + " --report r.json");
    EXPECT_EQ(run.status, 0) << command << ": " << run.err;
    std::ifstream in(folder_ / "r.json");
    return in ? json::parse(in) : json::object();
  }

  static void expect_keys(const json& report, std::initializer_list<const char*> keys, bool present,
                          const std::string& run) {
    for (const char* key : keys)
      EXPECT_EQ(report.contains(key), present)
          << run << ": key '" << key << "' " << (present ? "missing" : "written");
  }

  static fs::path folder_;
};

fs::path CommandReports::folder_;

const std::string kFly = "fly double.tpi --object object.ply --path flight.csv";

TEST_F(CommandReports, FlyWritesTheFiguresOfWhatItRan) {
  const json plain = report_of(kFly);
  expect_keys(plain,
              {"disagreements", "contact_rows_written", "preload_seconds", "query_answers",
               "obstacles", "max_rounding_distance"},
              false, "fly");
  expect_keys(plain,
              {"collisions", "containments", "contacts", "steps_outside_model", "per_step",
               "near_steps", "per_near_step", "prefetch_loads", "prefetch_hits", "prefetch_ahead",
               "budget_bytes"},
              true, "fly");
  // Only near steps touch shards: the per-step and per-near-step shard counts agree.
  const auto near_steps = plain.at("near_steps").get<std::uint64_t>();
  EXPECT_GT(near_steps, 0u);
  EXPECT_LE(near_steps, plain.at("steps").get<std::uint64_t>());
  EXPECT_NEAR(plain.at("per_near_step").at("shards_touched").get<double>() * double(near_steps),
              plain.at("per_step").at("shards_touched").get<double>() *
                  plain.at("steps").get<double>(),
              1e-6 * plain.at("steps").get<double>());
  EXPECT_EQ(plain.at("budget_bytes").get<std::uint64_t>(), kDefaultMemoryBudget)
      << "the default --memory";
  EXPECT_GT(plain.at("collisions").get<std::uint64_t>(), 0u);

  const json checked = report_of(
      kFly + " --check answers.csv --contacts contacts.csv --preload --no-prefetch --memory 64M");
  expect_keys(checked, {"disagreements", "contact_rows_written", "preload_seconds"}, true,
              "fly --check ...");
  expect_keys(checked, {"prefetch_loads", "prefetch_hits", "prefetch_ahead"}, false,
              "fly --no-prefetch");
  EXPECT_EQ(checked.at("disagreements").get<std::uint64_t>(), 0u);
  EXPECT_EQ(checked.at("contact_rows_written").get<std::uint64_t>(),
            checked.at("collisions").get<std::uint64_t>())
      << "first hit: one contact row per colliding step";
  EXPECT_EQ(checked.at("budget_bytes").get<std::uint64_t>(), std::uint64_t(64) << 20);

  // Distance answers through its own result: no collision-query counters, its own figures.
  const json distance = report_of(kFly + " --query distance --max-distance 0.01");
  expect_keys(distance, {"query_answers"}, true, "fly --query distance");
  expect_keys(distance,
              {"containments", "contacts", "steps_outside_model", "per_step", "near_steps",
               "per_near_step"},
              false, "fly --query distance");
  const json& answers = distance.at("query_answers");
  EXPECT_EQ(answers.at("touching").get<std::uint64_t>() + answers.at("apart").get<std::uint64_t>() +
                answers.at("farther").get<std::uint64_t>(),
            distance.at("steps").get<std::uint64_t>());

  const json rounded = report_of("fly float.tpi --object object.ply --path flight.csv");
  expect_keys(rounded, {"max_rounding_distance"}, true, "fly on a float index");
  EXPECT_GT(rounded.at("max_rounding_distance").get<double>(), 0.0);
}

TEST_F(CommandReports, FlyStatesWhatItHoldsBesideTheShardsAndKeepsItsPromise) {
  // The promise: peak RSS <= --memory + what the process held before any work + 64 MiB.
  const test::CliResult run = test::run_cli_in(folder_, kFly + " --memory 16M --report r.json");
  ASSERT_EQ(run.status, 0) << run.err;
  EXPECT_NE(run.out.find("memory: peak RSS"), std::string::npos) << run.out;
  if (test::kResidentMemoryIsTheProgramsOwn) {
    EXPECT_NE(run.out.find(": kept"), std::string::npos) << run.out;
  }
  std::ifstream in(folder_ / "r.json");
  const json report = json::parse(in);
  const auto at_start = report.at("resident_at_start_bytes").get<std::uint64_t>();
  const auto opened = report.at("resident_after_open_bytes").get<std::uint64_t>();
  const auto peak = report.at("peak_rss_bytes").get<std::uint64_t>();
  EXPECT_GT(at_start, 0u);
  EXPECT_GE(opened, at_start);
  EXPECT_GE(peak, opened);
  EXPECT_EQ(report.at("promised_peak_bytes").get<std::uint64_t>(),
            (std::uint64_t(16) << 20) + at_start + kRuntimeOverheadAllowance);
  if (!test::kResidentMemoryIsTheProgramsOwn) return;
  EXPECT_LE(peak, report.at("promised_peak_bytes").get<std::uint64_t>());
  EXPECT_EQ(report.at("promise_exceeded_bytes").get<std::uint64_t>(), 0u);
}

// The CAD module (OpenCASCADE and Assimp, about 30 MiB of pages) is loaded only by a flight
// whose object needs it, and then before the reading "before any work": the promise counts it
// as the process's own instead of charging it to the 64 MiB beside the shards.
TEST_F(CommandReports, FlyCountsTheCadModuleAsItsOwnOnlyWhenTheObjectNeedsIt) {
  const json ply = report_of(kFly + " --memory 16M");
  const json step = report_of(
      "fly double.tpi --object /usr/share/opencascade/data/step/screw.step --path flight.csv "
      "--memory 16M");
  if (!test::kResidentMemoryIsTheProgramsOwn) GTEST_SKIP() << "resident memory is the sanitizer's";
  EXPECT_GT(step.at("resident_at_start_bytes").get<std::uint64_t>(),
            ply.at("resident_at_start_bytes").get<std::uint64_t>() + (std::uint64_t(10) << 20));
  EXPECT_EQ(step.at("promise_exceeded_bytes").get<std::uint64_t>(), 0u);
  EXPECT_EQ(ply.at("promise_exceeded_bytes").get<std::uint64_t>(), 0u);
}

TEST_F(CommandReports, FlyStatesTheObstaclesItWasGiven) {
  {
    const auto index = std::make_shared<const CollisionIndex>(folder_ / "double.tpi");
    DynamicObstacles obstacles(index);
    const auto crate = std::make_shared<const ObjectModel>(read_mesh(folder_ / "object.ply"));
    obstacles.insert(crate, Pose{{0.5, 0.5, 0.5}, {1, 0, 0, 0}}, "crate");
    obstacles.hide_part(0);
    obstacles.save(folder_ / "model.obstacles");
  }
  const json report = report_of(kFly + " --obstacles model.obstacles");
  ASSERT_TRUE(report.contains("obstacles"));
  EXPECT_EQ(report.at("obstacles").at("dynamic_parts").get<std::uint64_t>(), 1u);
  EXPECT_EQ(report.at("obstacles").at("hidden_index_parts").get<std::uint64_t>(), 1u);
}

TEST_F(CommandReports, ReplayStatesDisagreementsOnlyWhenChecking) {
  const std::string replay = "replay environment.obj --object object.ply --path flight.csv";
  const json oracle = report_of(replay);
  expect_keys(oracle, {"disagreements"}, false, "replay");
  expect_keys(oracle, {"object_inside", "obstacle_inside"}, true,
              "replay (the oracle sees containment)");
  const json embree = report_of(replay + " --reference embree --threads 1 --check answers.csv");
  expect_keys(embree, {"disagreements"}, true, "replay --check");
  expect_keys(embree, {"object_inside", "obstacle_inside"}, false,
              "replay --reference embree (surfaces only)");
}

TEST_F(CommandReports, GenerateFlightNamesItsJudgesInput) {
  std::ifstream in(folder_ / "flight-env.json");
  const json oracle = json::parse(in);
  expect_keys(oracle, {"environment", "environment_triangles"}, true, "generate flight --env");
  expect_keys(oracle, {"index", "budget_bytes"}, false, "generate flight --env");
  EXPECT_EQ(oracle.at("environment_triangles").get<std::uint64_t>(), 2000u);
  const json runtime = report_of(
      "generate flight --index double.tpi --object object.ply --steps 50 --seed 5 -o runtime.csv");
  expect_keys(runtime, {"index", "budget_bytes"}, true, "generate flight --index");
  expect_keys(runtime, {"environment", "environment_triangles"}, false, "generate flight --index");
  EXPECT_EQ(runtime.at("budget_bytes").get<std::uint64_t>(), kDefaultMemoryBudget)
      << "the default --memory";
}

TEST_F(CommandReports, RenderStatesAReplayOnlyWhenItRanOne) {
  const json kind = report_of("render double.tpi -o kind.png --size 60x40");
  expect_keys(kind, {"flight"}, false, "render --color kind");
  const json replay = report_of(
      "render double.tpi -o pages.png --size 60x40 --color page-ins --path flight.csv --object "
      "object.ply");
  ASSERT_TRUE(replay.contains("flight"));
  EXPECT_EQ(replay.at("flight").at("poses").get<std::uint64_t>(), 300u);
  EXPECT_EQ(replay.at("flight").at("budget_bytes").get<std::uint64_t>(), kDefaultMemoryBudget);
}

TEST_F(CommandReports, PreprocessAndInspectStateStorageAndInteriorsFiguresWhereThereAreSome) {
  std::ifstream double_in(folder_ / "preprocess-double.json"),
      float_in(folder_ / "preprocess-float.json");
  const json stored = json::parse(double_in), rounded = json::parse(float_in);
  EXPECT_EQ(stored.at("memory_budget_bytes").get<std::uint64_t>(), kDefaultMemoryBudget)
      << "the default --memory";
  // Plain meshes: no tessellation.
  expect_keys(stored, {"tessellation_deflection", "skipped_parts"}, false,
              "preprocess of an OBJ file");
  expect_keys(stored, {"max_rounding_distance", "float_shards"}, false,
              "preprocess --precision double");
  expect_keys(stored, {"interior_tets", "interior_undecided"}, true, "preprocess (interiors on)");
  std::ifstream solid_in(folder_ / "preprocess-solid.json");
  const json solid = json::parse(solid_in);
  EXPECT_GT(solid.at("interior_tets").get<std::uint64_t>(), 0u);
  EXPECT_LT(solid.at("interior_tets").get<std::uint64_t>(), solid.at("regions").get<std::uint64_t>());
  expect_keys(rounded, {"max_rounding_distance", "float_shards"}, true,
              "preprocess --precision float");
  expect_keys(rounded, {"interior_tets", "interior_undecided"}, false,
              "preprocess --interiors off");
  EXPECT_EQ(rounded.at("float_shards").get<std::uint64_t>(),
            rounded.at("grid_shards").get<std::uint64_t>() +
                rounded.at("rtree_shards").get<std::uint64_t>());

  expect_keys(report_of("inspect double.tpi --stabbing-segments 0"), {"max_rounding_distance"},
              false, "inspect of a double index");
  expect_keys(report_of("inspect double.tpi --stabbing-segments 0"), {"stabbing_number_walk"},
              false, "inspect --stabbing-segments 0");
  expect_keys(report_of("inspect float.tpi --stabbing-segments 0"), {"max_rounding_distance"}, true,
              "inspect of a float index");
}

TEST_F(CommandReports, InspectStatesWhatThePreprocessReportedUnderTheSummarysNames) {
  // The preprocess counted as it wrote; inspect reads the file back (IndexSummary, the figures
  // Python's Index.inspect() returns under the same names).
  std::ifstream in(folder_ / "preprocess-double.json");
  const json preprocess = json::parse(in);
  const json inspect = report_of("inspect double.tpi --stabbing-segments 0");
  EXPECT_EQ(inspect.at("triangles"), preprocess.at("triangles_read"));
  EXPECT_EQ(inspect.at("stored_triangles"), preprocess.at("stored_triangles"));
  EXPECT_EQ(inspect.at("tets"), preprocess.at("regions"));
  EXPECT_EQ(inspect.at("grid_shards"), preprocess.at("grid_shards"));
  EXPECT_EQ(inspect.at("rtree_shards"), preprocess.at("rtree_shards"));
  EXPECT_EQ(inspect.at("shards").get<std::uint64_t>(),
            preprocess.at("regions").get<std::uint64_t>() -
                preprocess.at("empty_regions").get<std::uint64_t>());
  EXPECT_EQ(inspect.at("parts"), preprocess.at("parts"));
  EXPECT_EQ(inspect.at("precision"), "double");
  EXPECT_EQ(inspect.at("interiors"), true);
  EXPECT_GT(inspect.at("shard_decoded_bytes").get<std::uint64_t>(), 0u);
  EXPECT_EQ(inspect.at("grid_stored_bytes").get<std::uint64_t>() +
                inspect.at("rtree_stored_bytes").get<std::uint64_t>(),
            inspect.at("shard_stored_bytes").get<std::uint64_t>());
  EXPECT_GE(inspect.at("closed_components").get<std::uint64_t>(), 1u);
  EXPECT_LE(inspect.at("closed_components"), inspect.at("components"));
  expect_keys(inspect, {"interior_tets_inside", "interior_tets_undecided", "part_list", "bounds"},
              true, "inspect of an index with interiors");
  expect_keys(report_of("inspect float.tpi --stabbing-segments 0"),
              {"interior_tets_inside", "interior_tets_undecided"}, false,
              "inspect of an index without interiors");
}

}  // namespace
}  // namespace tetrapage
