#pragma once
/// @file TetBoxFilter.h
/// What a box search asks of a coarse tet before anything exact: its bounding box, and whether
/// one of four planes holding the tet leaves the whole box outside. Computed once when an index
/// opens (80 bytes a tet beyond the box) so that a search reads no corners and forms no normals.

#include <array>
#include <cstdint>
#include <vector>

#include "tetrapage/formats/TetMesh.h"
#include "tetrapage/runtime/geometry/Box.h"

namespace tetrapage {

class TetBoxFilter {
 public:
  TetBoxFilter() = default;
  /// The boxes and planes of each of the mesh's tets (whose corners must be finite).
  explicit TetBoxFilter(const TetMesh& mesh);

  std::size_t tet_count() const { return bounds_.size(); }
  /// The tet's bounding box (`tet` < tet_count(), unchecked).
  const geometry::Box& bounds(std::uint32_t tet) const { return bounds_[tet]; }
  /// False only when the box lies strictly outside one of the tet's face planes (including
  /// every rounding): true for every tet that meets the box. `box` must be finite.
  bool planes_may_meet(std::uint32_t tet, const geometry::Box& box) const {
    return planes_may_meet(tet, box, magnitude(box));
  }
  /// The same with magnitude(box) computed by the caller (a search asks many tets of one box).
  bool planes_may_meet(std::uint32_t tet, const geometry::Box& box, double box_magnitude) const;
  /// The bounding boxes overlap and planes_may_meet.
  bool may_meet(std::uint32_t tet, const geometry::Box& box) const {
    return geometry::boxes_overlap(bounds_[tet], box) && planes_may_meet(tet, box);
  }
  /// The largest coordinate's magnitude, which bounds the planes' rounding.
  static double magnitude(const geometry::Box& box);
  std::size_t memory_bytes() const { return bounds_.capacity() * sizeof(geometry::Box) + planes_.capacity() * sizeof(Planes); }

 private:
  // Face k's normal, pointing into the tet and scaled to about unit 1-norm, rounded to float
  // (any direction would do: the offset is taken from the rounded normal), and an offset no
  // larger than the smallest value of normal . x over the tet's corners.
  struct Planes {
    std::array<std::array<float, 3>, 4> normal;
    std::array<double, 4> offset;
  };
  std::vector<geometry::Box> bounds_;
  std::vector<Planes> planes_;
};

}  // namespace tetrapage
