#pragma once
/// @file BoxMethods.h
/// The study's three "box" methods (section 3), with its parameters as defaults: a uniform
/// N x N x N grid of voxels (3.1), a 3d-tree with midpoint cuts (3.2) and a binary R-tree with
/// median splits of the centroids (3.3).

#include <memory>
#include <span>

#include "tetrapage/study/StudyMethod.h"

namespace tetrapage::study {

struct GridOptions {
  unsigned cells_per_axis = 40;  ///< N
};

/// How the 3d-tree picks the axis of a cut (section 3.2); n1, n2: triangles in the children.
enum class KdAxisRule : std::uint8_t {
  min_max_count,      ///< (a) minimise max(n1, n2)
  min_count_gap,      ///< (b) minimise |n1 - n2|
  min_count_product,  ///< (c) minimise n1 * n2 (the study's choice)
  longest_side,       ///< (d) cut the longest side of the box
};

struct KdTreeOptions {
  unsigned leaf_triangles = 10;  ///< K: a box with fewer triangles is a leaf
  KdAxisRule axis_rule = KdAxisRule::min_count_product;
  unsigned no_gain_splits = 5;   ///< splits allowed on a path where a child keeps every triangle
  unsigned max_depth = 64;
};

/// How the R-tree picks the axis of a median split (section 3.3); V1, V2: the volumes of the
/// children's boxes.
enum class RTreeSplitRule : std::uint8_t {
  min_max_volume,  ///< (a) minimise max(V1, V2) (the study's choice)
  min_volume_sum,  ///< (b) minimise V1 + V2
};

struct RTreeOptions {
  unsigned leaf_triangles = 1;  ///< K
  RTreeSplitRule split_rule = RTreeSplitRule::min_max_volume;
};

/// @throw InputError for no obstacles, non-finite coordinates or a zero parameter.
std::unique_ptr<StudyMethod> make_grid_method(std::span<const geometry::Triangle> obstacles,
                                              const GridOptions& options = {});
std::unique_ptr<StudyMethod> make_kd_tree_method(std::span<const geometry::Triangle> obstacles,
                                                 const KdTreeOptions& options = {});
std::unique_ptr<StudyMethod> make_r_tree_method(std::span<const geometry::Triangle> obstacles,
                                                const RTreeOptions& options = {});

}  // namespace tetrapage::study
