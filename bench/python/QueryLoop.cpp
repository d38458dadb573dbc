// The C++ side of the Python overhead benchmark (overhead.py): the flight replayed through the
// C++ API as the module replays it, each pass timed as a whole (no clock per step), the index
// preloaded. Prints one line per way of asking, the median pass's microseconds per pose:
//   collides   FlyingObject::query (first hit), the answer kept
//   query      all contacts, and each contact's geometry (what FlyingObject.query returns)
//
//   tetrapage_bench_query_loop INDEX OBJECT FLIGHT [--repeat N]

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <vector>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/runtime/paging/CollisionIndex.h"
#include "tetrapage/runtime/query/FlyingObject.h"

namespace {

using namespace tetrapage;

// One pass over the poses by a new object (as a new Python object starts cold): seconds.
template <class Step>
double timed_pass(const std::shared_ptr<const CollisionIndex>& index, const TriangleSoup& object,
                  const std::vector<Pose>& poses, Step&& step) {
  FlyingObject flying(index, object);
  const auto start = std::chrono::steady_clock::now();
  for (const Pose& pose : poses) step(flying, pose);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app(
      "The flight through the C++ API, timed per pass: the reference of the Python module's "
      "overhead");
  std::string index_path, object_path, flight_path;
  std::size_t repeat = 5;
  app.add_option("index", index_path, "Index (.tpi)")->required()->check(CLI::ExistingFile);
  app.add_option("object", object_path, "Flying object mesh")->required()->check(CLI::ExistingFile);
  app.add_option("flight", flight_path, "Pose file")->required()->check(CLI::ExistingFile);
  app.add_option("--repeat", repeat, "Passes of each way of asking (the median is printed)")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    CollisionIndexOptions options;
    options.memory_budget_bytes = std::uint64_t(1) << 40;  // nothing is ever evicted
    const auto index = std::make_shared<const CollisionIndex>(index_path, options);
    index->preload();
    const TriangleSoup object = read_mesh(object_path);
    const std::vector<Pose> poses = read_poses(flight_path);
    std::vector<double> collides_seconds, query_seconds;
    std::uint64_t collisions = 0, contacts = 0;
    for (std::size_t pass = 0; pass < std::max<std::size_t>(repeat, 1); ++pass) {
      collisions = 0;
      QueryResult result;
      collides_seconds.push_back(
          timed_pass(index, object, poses, [&](FlyingObject& f, const Pose& p) {
            f.query(p, {}, result);
            collisions += result.collides;
          }));
      contacts = 0;
      QueryOptions all;
      all.mode = QueryMode::all_contacts;
      query_seconds.push_back(timed_pass(index, object, poses, [&](FlyingObject& f, const Pose& p) {
        f.query(p, all, result);
        for (const Contact& c : result.contacts) contacts += f.contact_geometry(c).count > 0;
      }));
    }
    const double per_pose = 1e6 / double(poses.size());
    std::printf("poses %zu, collisions %llu, contacts with geometry %llu\n", poses.size(),
                static_cast<unsigned long long>(collisions),
                static_cast<unsigned long long>(contacts));
    std::printf("collides %.4f us/pose\n", median(collides_seconds) * per_pose);
    std::printf("query %.4f us/pose\n", median(query_seconds) * per_pose);
    return 0;
  } catch (const Error& error) {
    std::fprintf(stderr, "tetrapage_bench_query_loop: %s\n", error.what());
    return 1;
  }
}
