#include "tetrapage/tools/SceneGenerator.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <optional>
#include <span>
#include <string>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/formats/mesh/SurfaceComponents.h"
#include "tetrapage/tools/BspPartition.h"

namespace tetrapage {
namespace {

// Uniform over rotations: a normalised 4D Gaussian is uniform on the unit quaternions.
std::array<double, 4> random_rotation(Random& random) {
  for (;;) {
    std::array<double, 4> q{random.normal(), random.normal(), random.normal(), random.normal()};
    const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (n > 1e-9) return {q[0] / n, q[1] / n, q[2] / n, q[3] / n};
  }
}

// Uniform on the unit sphere, for the same reason in 3D.
Vec3 random_direction(Random& random) {
  for (;;) {
    const Vec3 d{random.normal(), random.normal(), random.normal()};
    const double n = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (n > 1e-9) return {d[0] / n, d[1] / n, d[2] / n};
  }
}

void check_open_fraction(double open_fraction) {
  if (!(open_fraction >= 0.0) || !(open_fraction <= 1.0)) {
    char value[32];
    std::snprintf(value, sizeof value, "%g", open_fraction);
    throw InputError(std::string("scene: --open-fraction ") + value + " is out of range [0, 1]");
  }
}

// The triangles an opened copy keeps, in their order: those with a corner on or below the
// plane, then only the largest connected piece of them (the first of the largest), so that an
// opened copy stays one connected shell even when the cut severs a leg.
void cut_open(const TriangleSoup& soup, const SceneCut& cut, std::vector<TriangleIndices>& kept) {
  std::vector<double> height(soup.vertices.size());
  double lo = 1e300, hi = -1e300;
  for (std::size_t v = 0; v < height.size(); ++v) {
    const Vec3& p = soup.vertices[v];
    height[v] = cut.direction[0] * p[0] + cut.direction[1] * p[1] + cut.direction[2] * p[2];
    lo = std::min(lo, height[v]);
    hi = std::max(hi, height[v]);
  }
  const double plane = lo + cut.height * (hi - lo);
  TriangleSoup below;
  below.vertices = soup.vertices;
  for (const auto& t : soup.triangles)
    if (std::min({height[t[0]], height[t[1]], height[t[2]]}) <= plane) below.triangles.push_back(t);
  const SurfaceComponents pieces = find_surface_components(below);
  std::size_t largest = 0;
  for (std::size_t c = 1; c < pieces.components.size(); ++c)
    if (pieces.components[c].triangles > pieces.components[largest].triangles) largest = c;
  kept.clear();
  for (std::size_t t = 0; t < below.triangles.size(); ++t)
    if (pieces.component_of[t] == largest) kept.push_back(below.triangles[t]);
}

// Renumbers `triangles` to the vertices they use, gathered in index order into `used`: an
// opened copy writes no vertex that none of its triangles uses.
void keep_used_vertices(const std::vector<Vec3>& vertices, std::vector<TriangleIndices>& triangles,
                        std::vector<Vec3>& used) {
  constexpr std::uint32_t unused = ~std::uint32_t{0};
  std::vector<std::uint32_t> index(vertices.size(), unused);
  for (const auto& t : triangles)
    for (auto v : t) index[v] = 0;
  used.clear();
  for (std::size_t v = 0; v < vertices.size(); ++v) {
    if (index[v] == unused) continue;
    index[v] = static_cast<std::uint32_t>(used.size());
    used.push_back(vertices[v]);
  }
  for (auto& t : triangles)
    for (auto& v : t) v = index[v];
}

// The next mesh of the plan for a remaining budget, or none when the plan is complete.
// `by_size`: library indices by triangle count, so that "the meshes that fit" is a prefix.
std::optional<std::size_t> next_mesh(const MeshLibrary& library,
                                     const std::vector<std::size_t>& by_size,
                                     std::uint64_t remaining, bool plan_empty, Random& random) {
  const auto fitting = std::upper_bound(
      by_size.begin(), by_size.end(), remaining,
      [&](std::uint64_t budget, std::size_t m) { return budget < library[m].triangle_count(); });
  const auto fitting_count = static_cast<std::size_t>(fitting - by_size.begin());
  if (fitting_count > 0) return by_size[random.below(fitting_count)];
  const std::size_t smallest = by_size.front();
  // Overshoot only when that is closer to the target than stopping short (or when the scene
  // would otherwise be empty).
  if (!plan_empty && 2 * remaining < library[smallest].triangle_count()) return std::nullopt;
  return smallest;
}

// Rotates, scales and centres a copy into its leaf: the rotated copy's box fits `fill` of
// the leaf along the tightest axis (a uniform scale). Returns the placed vertices' bounds.
BoundingBox place_copy(std::span<const Vec3> vertices, const BoundingBox& leaf, double fill,
                       Random& random, std::vector<Vec3>& placed) {
  const auto rotation = rotation_matrix(random_rotation(random));
  const Vec3 origin{0.0, 0.0, 0.0};
  placed.resize(vertices.size());
  BoundingBox rotated;
  for (std::size_t v = 0; v < placed.size(); ++v) {
    placed[v] = apply_pose(rotation, origin, vertices[v]);
    rotated.extend(placed[v]);
  }
  const Vec3 rotated_size = rotated.size();
  const Vec3 leaf_size = leaf.size();
  double scale = 1e300;
  for (int a = 0; a < 3; ++a)
    if (rotated_size[a] > 0.0) scale = std::min(scale, leaf_size[a] / rotated_size[a]);
  if (scale == 1e300) scale = 1.0;  // a single point: any scale keeps it inside
  scale *= fill;
  const Vec3 from = rotated.center();
  const Vec3 to = leaf.center();
  BoundingBox bounds;
  for (auto& p : placed) {
    for (int a = 0; a < 3; ++a) p[a] = to[a] + scale * (p[a] - from[a]);
    bounds.extend(p);
  }
  return bounds;
}

}  // namespace

void check_scene_options(const SceneOptions& options) {
  if (options.triangles == 0 || options.triangles > max_scene_triangles)
    throw InputError("scene: --triangles " + std::to_string(options.triangles) +
                     " is out of range [1, " + std::to_string(max_scene_triangles) + "]");
  if (!(options.leaves_per_copy >= 1.0) || !(options.leaves_per_copy <= 1000.0))
    throw InputError("scene: leaves per copy " + std::to_string(options.leaves_per_copy) +
                     " is out of range [1, 1000]");
  if (!(options.fill > 0.0) || !(options.fill <= 1.0))
    throw InputError("scene: fill " + std::to_string(options.fill) + " is out of range (0, 1]");
  check_open_fraction(options.open_fraction);
}

std::vector<PlannedCopy> plan_scene_copies(const MeshLibrary& library, std::uint64_t triangles,
                                           double open_fraction, Random& random) {
  if (triangles == 0 || triangles > max_scene_triangles)
    throw InputError("scene: target of " + std::to_string(triangles) +
                     " triangles is out of range [1, " + std::to_string(max_scene_triangles) + "]");
  check_open_fraction(open_fraction);
  // By triangle count (then name order, which the library already has).
  std::vector<std::size_t> by_size(library.size());
  std::iota(by_size.begin(), by_size.end(), std::size_t{0});
  std::stable_sort(by_size.begin(), by_size.end(), [&](std::size_t a, std::size_t b) {
    return library[a].triangle_count() < library[b].triangle_count();
  });
  // Drawn only when needed, so that a fraction of 0 gives the all-closed scenes' bytes.
  const double phase = open_fraction > 0.0 ? random.uniform() : 0.0;

  std::vector<PlannedCopy> plan;
  std::vector<TriangleIndices> kept;  // scratch: the largest mesh's triangles at most
  std::uint64_t total = 0;
  while (total < triangles) {
    const auto mesh = next_mesh(library, by_size, triangles - total, plan.empty(), random);
    if (!mesh) break;
    PlannedCopy copy;
    copy.mesh = *mesh;
    copy.triangles = library[*mesh].triangle_count();
    const double k = double(plan.size());
    if (std::floor((k + 1.0) * open_fraction + phase) > std::floor(k * open_fraction + phase)) {
      copy.cut = {random_direction(random), random.uniform(0.6, 0.9)};
      cut_open(library[*mesh].soup, copy.cut, kept);
      copy.open = kept.size() < copy.triangles;  // a cut that drops nothing leaves it closed
      copy.triangles = kept.size();
    }
    plan.push_back(copy);
    total += copy.triangles;
  }
  return plan;
}

SceneSummary generate_scene(const MeshLibrary& library, const SceneOptions& options,
                            MeshWriter& writer, Progress& progress) {
  check_scene_options(options);
  Random random(options.seed);
  const std::vector<PlannedCopy> plan =
      plan_scene_copies(library, options.triangles, options.open_fraction, random);

  const auto leaf_count =
      static_cast<std::size_t>(std::ceil(options.leaves_per_copy * double(plan.size())));
  const BoundingBox unit_cube{{0.0, 0.0, 0.0}, {1.0, 1.0, 1.0}};
  BspPartition bsp = random_bsp_partition(unit_cube, leaf_count, random);
  const std::vector<std::uint32_t> chosen = random_subset(bsp.leaves.size(), plan.size(), random);

  SceneSummary summary;
  summary.leaves = bsp.leaves.size();
  summary.alpha = bsp.alpha;
  summary.copies.reserve(plan.size());

  // Scratch, reused: the largest mesh's size at most, whatever the number of copies.
  std::vector<Vec3> placed, opened_vertices;
  std::vector<TriangleIndices> opened_triangles;
  std::vector<std::size_t> copies_of(library.size(), 0);
  for (std::size_t k = 0; k < plan.size(); ++k) {
    const TriangleSoup& soup = library[plan[k].mesh].soup;
    std::span<const Vec3> vertices = soup.vertices;
    std::span<const TriangleIndices> triangles = soup.triangles;
    if (plan[k].open) {
      // Cut again rather than keep the plan's triangles: memory does not grow with the copies.
      cut_open(soup, plan[k].cut, opened_triangles);
      keep_used_vertices(soup.vertices, opened_triangles, opened_vertices);
      vertices = opened_vertices;
      triangles = opened_triangles;
    }
    SceneCopy copy;
    copy.mesh = plan[k].mesh;
    copy.leaf = bsp.leaves[chosen[k]];
    copy.placed = place_copy(vertices, copy.leaf, options.fill, random, placed);
    copy.triangles = triangles.size();
    copy.open = plan[k].open;
    writer.add_part(placed, triangles,
                    library[copy.mesh].name + "#" + std::to_string(copies_of[copy.mesh]++));

    summary.triangles += copy.triangles;
    summary.vertices += placed.size();
    ++(copy.open ? summary.open_copies : summary.closed_copies);
    summary.bounds.extend(copy.placed);
    summary.copies.push_back(copy);
    progress.advance(copy.triangles);
  }
  return summary;
}

}  // namespace tetrapage
