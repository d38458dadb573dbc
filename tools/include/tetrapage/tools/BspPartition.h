#pragma once
/// @file BspPartition.h
/// The study's random BSP tree (section 4.1): a box is cut into N disjoint leaf boxes. At each
/// of N-1 stages a leaf is picked at random among the "active" ones, one of its axes longer
/// than 2*alpha is picked at random, and the leaf is split perpendicular to that axis at a
/// point uniform in [min + alpha, max - alpha]. A leaf with no axis longer than 2*alpha is no
/// longer active. alpha keeps the leaves from becoming pancakes: every side produced by a
/// split is at least alpha long.

#include <cstddef>
#include <vector>

#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/tools/Random.h"

namespace tetrapage {

struct BspPartition {
  BoundingBox box;                  ///< the box that was partitioned
  double alpha = 0.0;               ///< the split margin that was used
  std::vector<BoundingBox> leaves;  ///< interior-disjoint, their union is `box`
};

/// alpha as a fraction of bsp_alpha_bound() used when none is given. Below the bound the
/// process can never run out of active leaves; 0.8 keeps a margin against rounding while
/// still forbidding any side shorter than 0.4 (volume/N)^(1/3), i.e. 40% of the side of the
/// average leaf (for the unit cube: alpha = 0.4 N^(-1/3)).
inline constexpr double default_bsp_alpha_fraction = 0.8;

/// The study's bound alpha < (1/2) N^(-1/3) generalised to a box of volume V:
/// (1/2) (V/N)^(1/3). Why it suffices: if every one of k < N leaves were inactive, each would
/// have all sides at most 2 alpha, so k (2 alpha)^3 >= V, i.e. alpha >= (1/2)(V/k)^(1/3) >
/// (1/2)(V/N)^(1/3). So below the bound some leaf is always active until N leaves exist.
double bsp_alpha_bound(const BoundingBox& box, std::size_t leaf_count);

/// Partitions `box` into exactly `leaf_count` leaves with the given alpha. The two children
/// of a split share the split coordinate bit for bit, so the leaves tile the box exactly.
/// Memory: 48 bytes per leaf plus 4 per active leaf. Deterministic for a given Random state.
/// @throw InputError if leaf_count is 0 or at least 2^32, if the box is empty, flat or not
///        finite, or if alpha is not in (0, bsp_alpha_bound(box, leaf_count)).
BspPartition random_bsp_partition(const BoundingBox& box, std::size_t leaf_count, Random& random,
                                  double alpha);

/// As above with alpha = default_bsp_alpha_fraction * bsp_alpha_bound(box, leaf_count).
/// @throw InputError as above.
BspPartition random_bsp_partition(const BoundingBox& box, std::size_t leaf_count, Random& random);

}  // namespace tetrapage
