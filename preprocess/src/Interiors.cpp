#include "Interiors.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <limits>
#include <mutex>
#include <string>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/Progress.h"
#include "tetrapage/preprocess/RayParity.h"
#include "tetrapage/runtime/geometry/Box.h"
#include "tetrapage/runtime/geometry/PointTetrahedron.h"
#include "tetrapage/runtime/query/MeshWalk.h"

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
                   " of part '" + model.part_paths[model.components[component].part] +
                   "'; pass --accept-undecided to store the tet as undecided (containment there is "
                   "then unknown)");
}

// Each tet's reference point, found by the walk (NaN in `reference_points` for a tet without
// one; `points` then holds its first corner and `has_point` 0).
void find_reference_points(const TetMesh& mesh, std::vector<Vec3>& points,
                           std::vector<std::uint8_t>& has_point,
                           std::vector<double>& reference_points) {
  const std::size_t tet_count = mesh.tet_count();
  points.resize(tet_count);
  has_point.assign(tet_count, 0);
  reference_points.resize(3 * tet_count);
  tbb::parallel_for(std::size_t(0), tet_count, [&](std::size_t t) {
    const auto reference = walk_reference_point(mesh, std::uint32_t(t));
    has_point[t] = reference.has_value();
    points[t] = reference ? *reference : mesh.vertices[mesh.tets[t][0]];
    for (int a = 0; a < 3; ++a)
      reference_points[3 * t + a] =
          reference ? (*reference)[a] : std::numeric_limits<double>::quiet_NaN();
  });
}

// A pass classifies against as many components as its (point, component) pairs allow: a quarter
// of the budget (RayParity holds 29 bytes per pair, the plan as much again).
std::uint64_t interior_pairs_per_pass(const PreprocessOptions& options) {
  return options.interior_pairs_per_pass != 0
             ? options.interior_pairs_per_pass
             : std::max<std::uint64_t>(1, options.memory_bytes / 4 / 64);
}

// What the classification passes share: the model, the tets' points, and per tet what the
// passes found.
struct Classification {
  Classification(IngestedModel& of_model, const PreprocessOptions& with_options,
                 const std::vector<bool>& closed_components, std::vector<Vec3>& tet_points)
      : model(of_model),
        options(with_options),
        closed(closed_components),
        points(tet_points),
        pairs_per_pass(interior_pairs_per_pass(with_options)),
        inside(tet_points.size()),
        undecided(tet_points.size(), 0),
        on_component(tet_points.size(), kInteriorUndecided) {}

  IngestedModel& model;
  const PreprocessOptions& options;
  const std::vector<bool>& closed;
  std::vector<Vec3>& points;  // per tet: its reference point (its first corner if none)
  std::uint64_t pairs_per_pass;
  std::vector<std::vector<std::uint32_t>> inside;
  std::vector<std::uint8_t> undecided;
  // Per tet, a closed component whose surface its last reference point lay on (for the error).
  std::vector<std::uint32_t> on_component;
  std::uint64_t passes = 0;
};

// The passes over the given tets (sorted by x): the closed components whose box holds some of
// their points (outside a component's box is outside the component), in passes of at most
// pairs_per_pass pairs; `of_component` gets each component's tets.
std::vector<std::vector<std::uint32_t>> plan_passes(
    const Classification& c, const std::vector<std::uint32_t>& tets,
    std::vector<std::vector<std::uint32_t>>& of_component) {
  std::vector<std::vector<std::uint32_t>> pass_components(1);
  std::uint64_t pass_pairs = 0;
  for (std::size_t p = 0; p < c.model.components.size(); ++p) {
    if (!c.closed[p]) continue;
    const BoundingBox& b = c.model.components[p].bounds;
    auto it = std::lower_bound(tets.begin(), tets.end(), b.lo[0],
                               [&](std::uint32_t t, double x) { return c.points[t][0] < x; });
    for (; it != tets.end() && c.points[*it][0] <= b.hi[0]; ++it)
      if (geometry::box_contains(b, c.points[*it])) of_component[p].push_back(*it);
    if (of_component[p].empty()) continue;
    if (pass_pairs > 0 && pass_pairs + of_component[p].size() > c.pairs_per_pass) {
      pass_components.emplace_back();
      pass_pairs = 0;
    }
    pass_components.back().push_back(std::uint32_t(p));
    pass_pairs += of_component[p].size();
  }
  if (pass_components.back().empty()) pass_components.pop_back();
  return pass_components;
}

// The soups in memory, to the parity: cut into tasks, the triangles of components not asked
// about skipped before their records are made (blocks of every record, made on one thread, were
// a third of this stage).
void add_in_memory_triangles(const IngestedModel& model, RayParity& parity, Progress& progress) {
  std::vector<InMemoryTask> tasks = in_memory_tasks(model.soups);
  std::mutex progress_mutex;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tasks.size(), 1),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t k = range.begin(); k < range.end(); ++k) {
                        const InMemoryTask& task = tasks[k];
                        for (std::size_t t = task.first; t < task.first + task.count; ++t) {
                          const std::uint32_t component = model.soups.piece_part(task.piece, t);
                          if (parity.wanted(component))
                            parity.add_triangle(component,
                                                model.soups.piece_record(task.piece, t).triangle);
                        }
                        const std::lock_guard lock(progress_mutex);
                        progress.advance(task.count);
                      }
                    });
}

// The spilled soups, to the parity: block by block, each on all threads.
void add_spilled_triangles(IngestedModel& model, RayParity& parity, Progress& progress) {
  model.soups.for_each_block(std::size_t(1) << 16, [&](std::span<const TriangleRecord> block) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, block.size(), 2048),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        for (std::size_t i = range.begin(); i < range.end(); ++i)
                          if (parity.wanted(block[i].part))
                            parity.add_triangle(block[i].part, block[i].triangle);
                      });
    progress.advance(block.size());
  });
}

// Classifies the given tets' reference points against every closed component whose box holds
// them, one stream of the soups per pass.
void classify(Classification& c, std::vector<std::uint32_t> tets, bool show_progress) {
  std::sort(tets.begin(), tets.end(),
            [&](std::uint32_t a, std::uint32_t b) { return c.points[a][0] < c.points[b][0]; });
  for (const std::uint32_t t : tets) c.inside[t].clear(), c.undecided[t] = 0;
  const std::size_t components = c.model.components.size();
  std::vector<std::vector<std::uint32_t>> of_component(components);
  const std::vector<std::vector<std::uint32_t>> pass_components =
      plan_passes(c, tets, of_component);
  Progress progress("classifying interiors", c.model.triangle_count * pass_components.size(),
                    c.options.progress && show_progress,
                    show_progress ? c.options.on_progress : ProgressCallback{});
  for (const auto& pass : pass_components) {
    ++c.passes;
    std::vector<std::vector<std::uint32_t>> asked(components);
    for (const std::uint32_t p : pass) asked[p] = std::move(of_component[p]);
    RayParity parity(c.points, asked);
    asked.clear();
    if (!c.model.soups.spilled())
      add_in_memory_triangles(c.model, parity, progress);
    else
      add_spilled_triangles(c.model, parity, progress);
    parity.for_each_answer([&](std::uint32_t t, std::uint32_t p, bool odd, bool on_surface) {
      if (on_surface)
        c.undecided[t] = 1, c.on_component[t] = p;
      else if (odd)
        c.inside[t].push_back(p);
    });
  }
  progress.finish();
}

// A reference point on a closed component's surface is replaced by another point strictly inside
// its tet and classified again, in passes of its own (a tet's point must be the same for
// every component). Returns how many points moved.
std::uint64_t retry_with_other_points(Classification& c, const TetMesh& mesh,
                                      std::vector<double>& reference_points) {
  constexpr std::array<std::array<double, 4>, 3> kOtherPoints{
      {{0.31, 0.23, 0.27, 0.19}, {0.17, 0.37, 0.21, 0.25}, {0.29, 0.13, 0.39, 0.19}}};
  std::uint64_t moved = 0;
  for (const auto& w : kOtherPoints) {
    std::vector<std::uint32_t> retry;
    for (std::size_t t = 0; t < mesh.tet_count(); ++t) {
      if (c.undecided[t] == 0) continue;
      const auto corners = mesh.corners(t);
      Vec3 q;
      for (int a = 0; a < 3; ++a)
        q[a] = w[0] * corners[0][a] + w[1] * corners[1][a] + w[2] * corners[2][a] +
               w[3] * corners[3][a];
      if (geometry::locate_in_tetrahedron(q, corners).position !=
          geometry::TetrahedronPosition::inside)
        continue;
      c.points[t] = q;
      for (int a = 0; a < 3; ++a) reference_points[3 * t + a] = q[a];
      retry.push_back(std::uint32_t(t));
      ++moved;
    }
    if (retry.empty()) break;
    classify(c, std::move(retry), false);
  }
  return moved;
}

// The CSR tables by tet: each tet's inside components in order, or the undecided marker (an
// InputError unless options.accept_undecided); counts the tets in `summary`.
void fill_tables(Interiors& result, Classification& c, const TetMesh& mesh,
                 const std::vector<std::uint8_t>& has_point, PreprocessSummary& summary) {
  const std::size_t tet_count = mesh.tet_count();
  result.offsets.reserve(tet_count + 1);
  result.offsets.push_back(0);
  for (std::size_t t = 0; t < tet_count; ++t) {
    if (!has_point[t] || c.undecided[t] != 0) {
      if (!c.options.accept_undecided)
        throw_undecided(c.model, mesh, std::uint32_t(t), c.on_component[t]);
      result.components.push_back(kInteriorUndecided);
      ++summary.interior_undecided;
    } else {
      std::vector<std::uint32_t>& inside = c.inside[t];
      std::sort(inside.begin(), inside.end());
      result.components.insert(result.components.end(), inside.begin(), inside.end());
      if (!inside.empty()) ++summary.interior_tets;
    }
    result.offsets.push_back(result.components.size());
  }
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
  std::vector<Vec3> points;
  // Bytes, not vector<bool>: the parallel loop writes neighbouring entries.
  std::vector<std::uint8_t> has_point;
  find_reference_points(mesh, points, has_point, result.reference_points);
  Classification c(model, options, closed, points);
  std::vector<std::uint32_t> all(tet_count);
  for (std::size_t t = 0; t < tet_count; ++t) all[t] = std::uint32_t(t);
  classify(c, std::move(all), true);
  const std::uint64_t first_passes = c.passes;
  const std::uint64_t moved = retry_with_other_points(c, mesh, result.reference_points);
  fill_tables(result, c, mesh, has_point, summary);
  result.stored = true;
  summary.interiors =
      "stored (" + std::to_string(first_passes) + (first_passes == 1 ? " pass" : " passes") + ")";
  if (moved > 0)
    summary.interiors +=
        "; " + std::to_string(moved) + " reference points on a surface moved and classified again";
  return result;
}

}  // namespace tetrapage
