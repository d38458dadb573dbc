#include "tetrapage/tools/TetrasGenerator.h"

#include <cmath>
#include <numeric>
#include <string>
#include <vector>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/tools/BspPartition.h"
#include "tetrapage/tools/Random.h"

namespace tetrapage {
namespace {

// Six times the signed volume: det(b - a, c - a, d - a).
double orientation(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
  const double vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
  const double wx = d[0] - a[0], wy = d[1] - a[1], wz = d[2] - a[2];
  return ux * (vy * wz - vz * wy) - uy * (vx * wz - vz * wx) + uz * (vx * wy - vy * wx);
}

void check_options(const TetrasOptions& options) {
  if (options.triangles == 0 || options.triangles > max_tetras_triangles)
    throw InputError("tetras: --triangles " + std::to_string(options.triangles) +
                     " is out of range [1, " + std::to_string(max_tetras_triangles) + "]");
  if (!(options.leaves_per_tetra >= 1.0) || !(options.leaves_per_tetra <= 1000.0))
    throw InputError("tetras: leaves per tetrahedron " + std::to_string(options.leaves_per_tetra) +
                     " is out of range [1, 1000]");
  // The largest tetrahedron in a box has 1/3 of its volume; stay far below that so that the
  // redraw loop ends quickly.
  if (!(options.min_volume_fraction >= 0.0) || !(options.min_volume_fraction <= 0.05))
    throw InputError("tetras: minimum volume fraction " +
                     std::to_string(options.min_volume_fraction) + " is out of range [0, 0.05]");
  if (!(options.margin >= 0.0) || !(options.margin < 0.5))
    throw InputError("tetras: margin " + std::to_string(options.margin) +
                     " is out of range [0, 0.5)");
}

}  // namespace

TetrasSummary generate_tetras(const TetrasOptions& options, MeshWriter& writer,
                              Progress& progress) {
  check_options(options);
  Random random(options.seed);
  const std::uint64_t tetra_count = std::max<std::uint64_t>(1, (options.triangles + 2) / 4);
  const auto leaf_count =
      static_cast<std::size_t>(std::ceil(options.leaves_per_tetra * double(tetra_count)));
  const BoundingBox unit_cube{{0.0, 0.0, 0.0}, {1.0, 1.0, 1.0}};
  const BspPartition bsp = random_bsp_partition(unit_cube, leaf_count, random);

  TetrasSummary summary;
  summary.leaves = bsp.leaves.size();
  summary.alpha = bsp.alpha;

  // Random subset of the leaves, picked one at a time (partial Fisher-Yates) and filled in
  // that order, so each tetrahedron is written as soon as it is drawn.
  std::vector<std::uint32_t> order(bsp.leaves.size());
  std::iota(order.begin(), order.end(), 0u);

  // Faces of a positively oriented tetrahedron (a, b, c, d), each facing away from the
  // corner it omits.
  const TriangleIndices faces[4] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  std::array<Vec3, 4> corners;
  for (std::uint64_t t = 0; t < tetra_count; ++t) {
    const std::size_t j = t + random.below(order.size() - t);
    std::swap(order[t], order[j]);
    const BoundingBox& leaf = bsp.leaves[order[t]];

    Vec3 lo, hi;
    for (int a = 0; a < 3; ++a) {
      const double inset = options.margin * (leaf.hi[a] - leaf.lo[a]);
      lo[a] = leaf.lo[a] + inset;
      hi[a] = leaf.hi[a] - inset;
    }
    const double box_volume = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
    const double least = 6.0 * options.min_volume_fraction * box_volume;
    double six_volume = 0.0;
    // The acceptance rate is above 2/3 at the default fraction; the cap only guards a loop
    // that could otherwise not end for a degenerate box.
    for (int attempt = 0;; ++attempt) {
      for (auto& corner : corners)
        for (int a = 0; a < 3; ++a) corner[a] = random.uniform(lo[a], hi[a]);
      six_volume = orientation(corners[0], corners[1], corners[2], corners[3]);
      if (std::abs(six_volume) >= least && six_volume != 0.0) break;
      ++summary.redraws;
      if (attempt == 1'000'000)
        throw InputError("tetras: no tetrahedron of volume fraction " +
                         std::to_string(options.min_volume_fraction) + " found in leaf " +
                         std::to_string(order[t]));
    }
    // The volume is a fixed fraction of the box, far above rounding, so the sign is exact.
    if (six_volume < 0.0) std::swap(corners[0], corners[1]);
    writer.add_part(corners, faces, "tetra#" + std::to_string(t));

    BoundingBox tetra_bounds;
    for (const auto& corner : corners) tetra_bounds.extend(corner);
    summary.bounds.extend(tetra_bounds);
    summary.tetras += 1;
    summary.triangles += 4;
    summary.vertices += 4;
    progress.advance(4);
  }
  return summary;
}

}  // namespace tetrapage
