#include "tetrapage/tools/StepTotals.h"

#include <algorithm>
#include <cstdio>

namespace tetrapage {

void StepTotals::add(const StepCounters& counters) {
  ++steps;
  searched_steps += counters.searched ? 1 : 0;
  tets_visited += counters.tets_visited;
  shards_touched += counters.shards_touched;
  candidates += counters.candidates;
  triangle_tests += counters.triangle_tests;
  if (counters.shards_touched == 0) return;
  ++near_steps;
  near_candidates += counters.candidates;
  near_triangle_tests += counters.triangle_tests;
}

std::string StepTotals::statement() const {
  const double all = double(std::max<std::uint64_t>(steps, 1));
  const double near = double(std::max<std::uint64_t>(near_steps, 1));
  char text[320];
  std::snprintf(text, sizeof text,
                "per step: %.1f tets visited, %.2f shards, %.1f candidates, %.1f triangle tests; "
                "near steps (a shard touched) %.1f %%: %.1f shards, %.1f candidates, %.1f triangle tests each",
                double(tets_visited) / all, double(shards_touched) / all, double(candidates) / all,
                double(triangle_tests) / all, 100.0 * double(near_steps) / all, double(shards_touched) / near,
                double(near_candidates) / near, double(near_triangle_tests) / near);
  return text;
}

void StepTotals::add_to(nlohmann::json& report) const {
  const double all = double(std::max<std::uint64_t>(steps, 1));
  const double near = double(std::max<std::uint64_t>(near_steps, 1));
  report["per_step"] = {{"searched", double(searched_steps) / all},
                        {"tets_visited", double(tets_visited) / all},
                        {"shards_touched", double(shards_touched) / all},
                        {"candidates", double(candidates) / all},
                        {"triangle_tests", double(triangle_tests) / all}};
  report["near_steps"] = near_steps;
  // Only near steps touch shards: all of them count here.
  report["per_near_step"] = {{"shards_touched", double(shards_touched) / near},
                             {"candidates", double(near_candidates) / near},
                             {"triangle_tests", double(near_triangle_tests) / near}};
}

}  // namespace tetrapage
