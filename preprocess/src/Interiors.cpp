#include "Interiors.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <limits>
#include <mutex>
#include <string>

#include "tetrapage/formats/Error.h"
#include "tetrapage/formats/Progress.h"
#include "tetrapage/preprocess/RayParity.h"
#include "tetrapage/runtime/MeshWalk.h"
#include "tetrapage/runtime/geometry/Box.h"
#include "tetrapage/runtime/geometry/PointTetrahedron.h"

namespace tetrapage {
namespace {

// A tet whose inside could not be decided: the runtime would answer "unknown" there, and
// containment could be missed, so the preprocess stops unless the user accepts it.
[[noreturn]] void throw_undecided(const IngestedModel& model, const TetMesh& mesh,
                                  std::uint32_t tet, std::uint32_t component) {
  const auto c = mesh.corners(tet);
  char corner[128];
  std::snprintf(corner, sizeof corner, "(first corner %.9g, %.9g, %.9g)", c[0][0], c[0][1],
                c[0][2]);
  const std::string where = "tet " + std::to_string(tet) + " " + corner;
  if (component == kInteriorUndecided)
    throw InputError(
        "interiors: " + where +
        " has no point strictly inside it to classify; pass "
        "--accept-undecided to store it as undecided (containment there is then unknown)");
  throw InputError("interiors: every reference point tried in " + where +
                   " lies on the surface of closed component " + std::to_string(component) +
                   " of part '" + model.part_names[model.components[component].part] +
                   "'; pass --accept-undecided to store the tet as undecided (containment there is "
                   "then unknown)");
}

}  // namespace

Interiors classify_interiors(IngestedModel& model, const TetMesh& mesh,
                             const PreprocessOptions& options, PreprocessSummary& summary) {
  Interiors result;
  const std::size_t components = model.components.size();
  std::vector<bool> closed(components);
  for (std::size_t c = 0; c < components; ++c) {
    closed[c] = model.components[c].closed;
    summary.closed_components += closed[c];
  }
  if (!options.interiors) return result;
  if (summary.closed_components == 0) {
    summary.interiors = "none closed";
    return result;
  }
  const std::size_t tet_count = mesh.tet_count();
  std::vector<Vec3> points(tet_count);
  // Bytes, not vector<bool>: the parallel loop writes neighbouring entries.
  std::vector<std::uint8_t> has_point(tet_count, 0);
  result.reference_points.resize(3 * tet_count);
  tbb::parallel_for(std::size_t(0), tet_count, [&](std::size_t t) {
    const auto reference = walk_reference_point(mesh, std::uint32_t(t));
    has_point[t] = reference.has_value();
    points[t] = reference ? *reference : mesh.vertices[mesh.tets[t][0]];
    for (int a = 0; a < 3; ++a)
      result.reference_points[3 * t + a] =
          reference ? (*reference)[a] : std::numeric_limits<double>::quiet_NaN();
  });
  // A pass classifies against as many components as its (point, component) pairs allow: a quarter
  // of the budget (RayParity holds 29 bytes per pair, the plan as much again).
  const std::uint64_t pairs_per_pass =
      options.interior_pairs_per_pass != 0
          ? options.interior_pairs_per_pass
          : std::max<std::uint64_t>(1, options.memory_bytes / 4 / 64);
  std::vector<std::vector<std::uint32_t>> inside(tet_count);
  std::vector<std::uint8_t> undecided(tet_count, 0);
  // Per tet, a closed component whose surface its last reference point lay on (for the error).
  std::vector<std::uint32_t> on_component(tet_count, kInteriorUndecided);
  std::uint64_t passes = 0;
  // Classifies the given tets' reference points against every closed component whose box holds
  // them (outside a component's box is outside the component).
  auto classify = [&](std::vector<std::uint32_t> tets, bool show_progress) {
    std::sort(tets.begin(), tets.end(),
              [&](std::uint32_t a, std::uint32_t b) { return points[a][0] < points[b][0]; });
    for (const std::uint32_t t : tets) inside[t].clear(), undecided[t] = 0;
    std::vector<std::vector<std::uint32_t>> of_component(components);
    std::vector<std::vector<std::uint32_t>> pass_components(1);
    std::uint64_t pass_pairs = 0;
    for (std::size_t p = 0; p < components; ++p) {
      if (!closed[p]) continue;
      const BoundingBox& b = model.components[p].bounds;
      auto it = std::lower_bound(tets.begin(), tets.end(), b.lo[0],
                                 [&](std::uint32_t t, double x) { return points[t][0] < x; });
      for (; it != tets.end() && points[*it][0] <= b.hi[0]; ++it)
        if (geometry::box_contains(b, points[*it])) of_component[p].push_back(*it);
      if (of_component[p].empty()) continue;
      if (pass_pairs > 0 && pass_pairs + of_component[p].size() > pairs_per_pass) {
        pass_components.emplace_back();
        pass_pairs = 0;
      }
      pass_components.back().push_back(std::uint32_t(p));
      pass_pairs += of_component[p].size();
    }
    if (pass_components.back().empty()) pass_components.pop_back();
    Progress progress("classifying interiors", model.triangle_count * pass_components.size(),
                      options.progress && show_progress);
    for (const auto& pass : pass_components) {
      ++passes;
      std::vector<std::vector<std::uint32_t>> asked(components);
      for (const std::uint32_t p : pass) asked[p] = std::move(of_component[p]);
      RayParity parity(points, asked);
      asked.clear();
      if (!model.soups.spilled()) {
        // In memory: the soups cut into tasks, the triangles of components not asked about skipped
        // before their records are made (blocks of every record, made on one thread, were a
        // third of this stage).
        std::vector<InMemoryTask> tasks = in_memory_tasks(model.soups);
        std::mutex progress_mutex;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tasks.size(), 1),
                          [&](const tbb::blocked_range<std::size_t>& range) {
                            for (std::size_t k = range.begin(); k < range.end(); ++k) {
                              const InMemoryTask& task = tasks[k];
                              for (std::size_t t = task.first; t < task.first + task.count; ++t) {
                                const std::uint32_t component =
                                    model.soups.piece_part(task.piece, t);
                                if (parity.wanted(component))
                                  parity.add_triangle(
                                      component, model.soups.piece_record(task.piece, t).triangle);
                              }
                              const std::lock_guard lock(progress_mutex);
                              progress.advance(task.count);
                            }
                          });
      } else {
        model.soups.for_each_block(
            std::size_t(1) << 16, [&](std::span<const TriangleRecord> block) {
              tbb::parallel_for(tbb::blocked_range<std::size_t>(0, block.size(), 2048),
                                [&](const tbb::blocked_range<std::size_t>& range) {
                                  for (std::size_t i = range.begin(); i < range.end(); ++i)
                                    if (parity.wanted(block[i].part))
                                      parity.add_triangle(block[i].part, block[i].triangle);
                                });
              progress.advance(block.size());
            });
      }
      parity.for_each_answer([&](std::uint32_t t, std::uint32_t p, bool odd, bool on_surface) {
        if (on_surface)
          undecided[t] = 1, on_component[t] = p;
        else if (odd)
          inside[t].push_back(p);
      });
    }
    progress.finish();
  };
  std::vector<std::uint32_t> all(tet_count);
  for (std::size_t t = 0; t < tet_count; ++t) all[t] = std::uint32_t(t);
  classify(std::move(all), true);
  const std::uint64_t first_passes = passes;
  // A reference point on a closed component's surface is replaced by another point strictly inside
  // its tet and classified again, in passes of its own (a tet's point must be the same for
  // every component).
  constexpr std::array<std::array<double, 4>, 3> kOtherPoints{
      {{0.31, 0.23, 0.27, 0.19}, {0.17, 0.37, 0.21, 0.25}, {0.29, 0.13, 0.39, 0.19}}};
  std::uint64_t moved = 0;
  for (const auto& w : kOtherPoints) {
    std::vector<std::uint32_t> retry;
    for (std::size_t t = 0; t < tet_count; ++t) {
      if (undecided[t] == 0) continue;
      const auto c = mesh.corners(t);
      Vec3 q;
      for (int a = 0; a < 3; ++a)
        q[a] = w[0] * c[0][a] + w[1] * c[1][a] + w[2] * c[2][a] + w[3] * c[3][a];
      if (geometry::locate_in_tetrahedron(q, c).position != geometry::TetrahedronPosition::inside)
        continue;
      points[t] = q;
      for (int a = 0; a < 3; ++a) result.reference_points[3 * t + a] = q[a];
      retry.push_back(std::uint32_t(t));
      ++moved;
    }
    if (retry.empty()) break;
    classify(std::move(retry), false);
  }

  result.offsets.reserve(tet_count + 1);
  result.offsets.push_back(0);
  for (std::size_t t = 0; t < tet_count; ++t) {
    if (!has_point[t] || undecided[t] != 0) {
      if (!options.accept_undecided)
        throw_undecided(model, mesh, std::uint32_t(t), on_component[t]);
      result.components.push_back(kInteriorUndecided);
      ++summary.interior_undecided;
    } else {
      std::sort(inside[t].begin(), inside[t].end());
      result.components.insert(result.components.end(), inside[t].begin(), inside[t].end());
      if (!inside[t].empty()) ++summary.interior_tets;
    }
    result.offsets.push_back(result.components.size());
  }
  result.stored = true;
  summary.interiors =
      "stored (" + std::to_string(first_passes) + (first_passes == 1 ? " pass" : " passes") + ")";
  if (moved > 0)
    summary.interiors +=
        "; " + std::to_string(moved) + " reference points on a surface moved and classified again";
  return result;
}

}  // namespace tetrapage
