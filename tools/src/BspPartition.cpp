#include "tetrapage/tools/BspPartition.h"

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "tetrapage/formats/base/Error.h"

namespace tetrapage {
namespace {

double box_volume(const BoundingBox& box) {
  const Vec3 size = box.size();
  return size[0] * size[1] * size[2];
}

void check_box(const BoundingBox& box) {
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(box.lo[a]) || !std::isfinite(box.hi[a]))
      throw InputError("BSP partition: the box is not finite along axis " + std::to_string(a));
    if (!(box.hi[a] > box.lo[a]))
      throw InputError("BSP partition: the box is empty or flat along axis " + std::to_string(a) +
                       " (lo " + std::to_string(box.lo[a]) + ", hi " + std::to_string(box.hi[a]) +
                       ")");
  }
}

}  // namespace

double bsp_alpha_bound(const BoundingBox& box, std::size_t leaf_count) {
  if (leaf_count == 0) throw InputError("BSP partition: the number of leaves must be at least 1");
  check_box(box);
  return 0.5 * std::cbrt(box_volume(box) / double(leaf_count));
}

BspPartition random_bsp_partition(const BoundingBox& box, std::size_t leaf_count, Random& random,
                                  double alpha) {
  const double bound = bsp_alpha_bound(box, leaf_count);
  if (leaf_count > std::numeric_limits<std::uint32_t>::max())
    throw InputError("BSP partition: " + std::to_string(leaf_count) +
                     " leaves requested, at most 2^32 - 1 are supported");
  if (!(alpha > 0.0) || !(alpha < bound))
    throw InputError("BSP partition: alpha " + std::to_string(alpha) + " is not in (0, " +
                     std::to_string(bound) + ") for " + std::to_string(leaf_count) + " leaves");

  BspPartition partition;
  partition.box = box;
  partition.alpha = alpha;
  partition.leaves.reserve(leaf_count);
  partition.leaves.push_back(box);

  const auto splittable_axes = [alpha](const BoundingBox& leaf, int axes[3]) {
    int count = 0;
    for (int a = 0; a < 3; ++a)
      if (leaf.hi[a] - leaf.lo[a] > 2.0 * alpha) axes[count++] = a;
    return count;
  };

  // Indices of the active leaves; the order is deterministic (swap-remove on pick).
  std::vector<std::uint32_t> active;
  int axes[3];
  if (splittable_axes(box, axes) > 0) active.push_back(0);

  while (partition.leaves.size() < leaf_count) {
    // Cannot happen below the bound (see bsp_alpha_bound); kept as a guard against rounding.
    if (active.empty())
      throw InputError("BSP partition: no active leaf left after " +
                       std::to_string(partition.leaves.size()) + " leaves with alpha " +
                       std::to_string(alpha));
    const std::size_t pick = random.below(active.size());
    const std::uint32_t index = active[pick];
    active[pick] = active.back();
    active.pop_back();

    const BoundingBox parent = partition.leaves[index];
    const int axis_count = splittable_axes(parent, axes);
    const int axis = axes[random.below(std::uint64_t(axis_count))];
    const double lo = parent.lo[axis] + alpha;
    const double hi = parent.hi[axis] - alpha;
    const double split = lo + (hi - lo) * random.uniform();

    BoundingBox lower = parent;
    BoundingBox upper = parent;
    lower.hi[axis] = split;
    upper.lo[axis] = split;
    partition.leaves[index] = lower;
    const auto upper_index = static_cast<std::uint32_t>(partition.leaves.size());
    partition.leaves.push_back(upper);
    if (splittable_axes(lower, axes) > 0) active.push_back(index);
    if (splittable_axes(upper, axes) > 0) active.push_back(upper_index);
  }
  return partition;
}

BspPartition random_bsp_partition(const BoundingBox& box, std::size_t leaf_count, Random& random) {
  const double alpha = default_bsp_alpha_fraction * bsp_alpha_bound(box, leaf_count);
  return random_bsp_partition(box, leaf_count, random, alpha);
}

}  // namespace tetrapage
