#pragma once
// `tetrapage fly`'s arguments and the parts its one-object and several-object runs share
// (FlyCommand.cpp, FlyGroup.cpp).

#include <chrono>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "TessellationArguments.h"
#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/runtime/paging/CollisionIndex.h"
#include "tetrapage/runtime/query/DynamicObstacles.h"
#include "tetrapage/runtime/query/FlyingObject.h"

namespace tetrapage::cli {

struct FlyArguments {
  std::filesystem::path index, answers, check, report, contacts, obstacles;
  /// One object and its pose file, or several (an ObjectGroup): as many of each.
  std::vector<std::filesystem::path> objects, paths;
  std::string object_unit;
  double object_scale = 1.0;
  TessellationArguments tessellation;
  std::string memory;  // add_memory_option sets the default
  std::string accuracy = "exact";
  std::string query = "collide";
  double max_distance = std::numeric_limits<double>::infinity();
  double toi_tolerance = 1e-4;
  bool all_contacts = false;
  std::uint64_t max_contacts = kDefaultMaxContacts;
  bool no_prefetch = false;
  bool prefetch_ahead = false;
  bool no_shard_arena = false;
  unsigned spin_before_sleep_us = 200;
  bool preload = false;
};

/// The flying object `path`, in the index's unit (times --object-scale) when both state theirs.
TriangleSoup load_object(const FlyArguments& args, const std::filesystem::path& path);
/// The index's options: --memory and the paging flags.
CollisionIndexOptions fly_index_options(const FlyArguments& args);
/// The dynamic obstacles saved in --obstacles (DynamicObstacles::save), or null without it.
std::shared_ptr<const DynamicObstacles> load_obstacles(const FlyArguments& args,
                                                        const std::shared_ptr<const CollisionIndex>& index);
/// Several objects flying at once: an ObjectGroup step per pose (--query collide only).
void run_fly_group(const FlyArguments& args);

}  // namespace tetrapage::cli
