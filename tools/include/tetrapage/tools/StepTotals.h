#pragma once
/// @file StepTotals.h
/// What a flight's steps did, summed from the runtime's step counters: per step, and per near
/// step (one that touched a shard: its box met a shard's reach and the object's own box, so
/// phase I ran over the shard). `fly` and the peers' harness report both alike.

#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "tetrapage/runtime/query/FlyingObject.h"

namespace tetrapage {

struct StepTotals {
  std::uint64_t steps = 0, searched_steps = 0, near_steps = 0;
  std::uint64_t tets_visited = 0, shards_touched = 0, candidates = 0, triangle_tests = 0;
  /// Over the near steps only (dynamic obstacles give candidates to other steps too).
  std::uint64_t near_candidates = 0, near_triangle_tests = 0;

  void add(const StepCounters& counters);
  /// "per step: ...; near steps (a shard touched) ...": one line, without a newline.
  std::string statement() const;
  /// Sets `per_step`, `near_steps` and `per_near_step` in `report`.
  void add_to(nlohmann::json& report) const;
};

}  // namespace tetrapage
