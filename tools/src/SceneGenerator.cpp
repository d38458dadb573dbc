#include "tetrapage/tools/SceneGenerator.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "tetrapage/formats/Error.h"
#include "tetrapage/formats/Pose.h"
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

void check_options(const SceneOptions& options) {
  if (options.triangles == 0 || options.triangles > max_scene_triangles)
    throw InputError("scene: --triangles " + std::to_string(options.triangles) +
                     " is out of range [1, " + std::to_string(max_scene_triangles) + "]");
  if (!(options.leaves_per_copy >= 1.0) || !(options.leaves_per_copy <= 1000.0))
    throw InputError("scene: leaves per copy " + std::to_string(options.leaves_per_copy) +
                     " is out of range [1, 1000]");
  if (!(options.fill > 0.0) || !(options.fill <= 1.0))
    throw InputError("scene: fill " + std::to_string(options.fill) + " is out of range (0, 1]");
}

}  // namespace

std::vector<std::size_t> plan_scene_copies(const MeshLibrary& library, std::uint64_t triangles,
                                           Random& random) {
  if (triangles == 0 || triangles > max_scene_triangles)
    throw InputError("scene: target of " + std::to_string(triangles) +
                     " triangles is out of range [1, " + std::to_string(max_scene_triangles) + "]");
  // Library indices by triangle count (then name order, which the library already has), so
  // that "the meshes that fit" is a prefix.
  std::vector<std::size_t> by_size(library.size());
  std::iota(by_size.begin(), by_size.end(), std::size_t{0});
  std::stable_sort(by_size.begin(), by_size.end(), [&](std::size_t a, std::size_t b) {
    return library[a].triangle_count() < library[b].triangle_count();
  });

  std::vector<std::size_t> plan;
  std::uint64_t total = 0;
  while (total < triangles) {
    const std::uint64_t remaining = triangles - total;
    const auto fitting = std::upper_bound(
        by_size.begin(), by_size.end(), remaining,
        [&](std::uint64_t budget, std::size_t m) { return budget < library[m].triangle_count(); });
    const auto fitting_count = static_cast<std::size_t>(fitting - by_size.begin());
    std::size_t mesh;
    if (fitting_count > 0) {
      mesh = by_size[random.below(fitting_count)];
    } else {
      const std::size_t smallest = by_size.front();
      // Overshoot only when that is closer to the target than stopping short (or when the
      // scene would otherwise be empty).
      if (!plan.empty() && 2 * remaining < library[smallest].triangle_count()) break;
      mesh = smallest;
    }
    plan.push_back(mesh);
    total += library[mesh].triangle_count();
  }
  return plan;
}

SceneSummary generate_scene(const MeshLibrary& library, const SceneOptions& options,
                            MeshWriter& writer, Progress& progress) {
  check_options(options);
  Random random(options.seed);
  const std::vector<std::size_t> plan = plan_scene_copies(library, options.triangles, random);

  const auto leaf_count =
      static_cast<std::size_t>(std::ceil(options.leaves_per_copy * double(plan.size())));
  const BoundingBox unit_cube{{0.0, 0.0, 0.0}, {1.0, 1.0, 1.0}};
  BspPartition bsp = random_bsp_partition(unit_cube, leaf_count, random);
  const std::vector<std::uint32_t> chosen = random_subset(bsp.leaves.size(), plan.size(), random);

  SceneSummary summary;
  summary.leaves = bsp.leaves.size();
  summary.alpha = bsp.alpha;
  summary.copies.reserve(plan.size());

  std::vector<Vec3> placed;  // scratch, reused: the largest mesh's vertices at most
  const Vec3 origin{0.0, 0.0, 0.0};
  for (std::size_t k = 0; k < plan.size(); ++k) {
    const LibraryMesh& mesh = library[plan[k]];
    const BoundingBox& leaf = bsp.leaves[chosen[k]];
    const auto rotation = rotation_matrix(random_rotation(random));

    placed.resize(mesh.soup.vertices.size());
    BoundingBox rotated;
    for (std::size_t v = 0; v < placed.size(); ++v) {
      placed[v] = apply_pose(rotation, origin, mesh.soup.vertices[v]);
      rotated.extend(placed[v]);
    }
    // Uniform scale: the rotated copy's box fits `fill` of the leaf along the tightest axis.
    const Vec3 rotated_size = rotated.size();
    const Vec3 leaf_size = leaf.size();
    double scale = 1e300;
    for (int a = 0; a < 3; ++a)
      if (rotated_size[a] > 0.0) scale = std::min(scale, leaf_size[a] / rotated_size[a]);
    if (scale == 1e300) scale = 1.0;  // a single point: any scale keeps it inside
    scale *= options.fill;
    const Vec3 from = rotated.center();
    const Vec3 to = leaf.center();

    SceneCopy copy;
    copy.mesh = plan[k];
    copy.leaf = leaf;
    copy.triangles = mesh.triangle_count();
    for (auto& p : placed) {
      for (int a = 0; a < 3; ++a) p[a] = to[a] + scale * (p[a] - from[a]);
      copy.placed.extend(p);
    }
    writer.add_part(placed, mesh.soup.triangles);

    summary.triangles += copy.triangles;
    summary.vertices += placed.size();
    summary.bounds.extend(copy.placed);
    summary.copies.push_back(copy);
    progress.advance(copy.triangles);
  }
  return summary;
}

}  // namespace tetrapage
