// example.cpp - the tetrapage C++ API in one small program (example.c does the same in C).
//
//   tetrapage_example_cpp INDEX.tpi OBJECT.ply [POSES.csv [ACCURACY]]
//
// Opens an index, loads a flying object, and queries a few poses: those of a pose file, or by
// default five points along the diagonal of the model's box. Prints the version it was built
// with (`tetrapage 0.1.0`), one line per pose (`pose K: collides` or `pose K: free`) and up to
// five of its contacts, then a summary.

#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <vector>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/runtime/geometry/Accuracy.h"
#include "tetrapage/runtime/paging/CollisionIndex.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/version.h"

int main(int argc, char** argv) {
  if (argc < 3 || argc > 5) {
    std::cerr << "usage: " << argv[0] << " INDEX.tpi OBJECT.ply [POSES.csv [ACCURACY]]\n";
    return 2;
  }
  std::printf("tetrapage %s\n", TETRAPAGE_VERSION_STRING);
  try {
    tetrapage::CollisionIndexOptions index_options;
    index_options.memory_budget_bytes = std::uint64_t(256) << 20;
    // One index may serve many objects (each used from its own thread).
    const auto index = std::make_shared<const tetrapage::CollisionIndex>(argv[1], index_options);
    tetrapage::FlyingObject object(index, tetrapage::read_mesh(argv[2]));

    tetrapage::QueryOptions options;
    options.mode = tetrapage::QueryMode::all_contacts;
    if (argc == 5) options.accuracy = tetrapage::geometry::parse_accuracy(argv[4]);

    std::vector<tetrapage::Pose> poses;
    if (argc >= 4) {
      poses = tetrapage::read_poses(argv[3]);
    } else {
      const auto& box = index->header().bounds;
      for (int k = 0; k < 5; ++k) {
        const double f = 0.25 * k, half_angle = 0.2 * k;
        tetrapage::Pose pose;
        for (int a = 0; a < 3; ++a) pose.translation[a] = box.lo[a] + f * (box.hi[a] - box.lo[a]);
        pose.rotation = {std::cos(half_angle), 0.0, 0.0, std::sin(half_angle)};
        poses.push_back(pose);
      }
    }

    tetrapage::QueryResult result;  // reused: no allocation per step once warmed up
    std::size_t collisions = 0;
    for (std::size_t k = 0; k < poses.size(); ++k) {
      object.query(poses[k], options, result);
      collisions += result.collides;
      std::printf("pose %zu: %s", k, result.collides ? "collides" : "free");
      if (result.collides) std::printf(", %zu contacts", result.contacts.size());
      std::printf("  (at %g %g %g)\n", poses[k].translation[0], poses[k].translation[1],
                  poses[k].translation[2]);
      for (std::size_t c = 0; c < result.contacts.size() && c < 5; ++c)
        std::printf("  environment part %u (%s) triangle %llu touches object triangle %u\n",
                    result.contacts[c].environment_part,
                    index->parts().path(result.contacts[c].environment_part).c_str(),
                    static_cast<unsigned long long>(result.contacts[c].environment_triangle),
                    result.contacts[c].object_triangle);
      if (result.contacts.size() > 5) std::printf("  ... %zu more\n", result.contacts.size() - 5);
    }
    std::printf("collisions: %zu of %zu poses\n", collisions, poses.size());
    return 0;
  } catch (const tetrapage::Error& e) {
    // IoError, FormatError and InputError all name the file and the value at fault.
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
}
