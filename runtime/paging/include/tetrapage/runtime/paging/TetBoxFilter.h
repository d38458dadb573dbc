#pragma once
/// @file TetBoxFilter.h
/// What a box search asks of a coarse tet before anything exact: its bounding box, and whether
/// one of four planes holding the tet leaves the whole box outside. Computed once when an index
/// opens (88 bytes a tet: a float box rounded outward and four float planes) so that a search
/// reads no corners and forms no normals.

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "tetrapage/formats/index/TetMesh.h"
#include "tetrapage/runtime/geometry/Box.h"
#include "tetrapage/runtime/geometry/FloatBox.h"

namespace tetrapage {

class TetBoxFilter {
 public:
  TetBoxFilter() = default;
  /// The boxes and planes of each of the mesh's tets (whose corners must be finite).
  explicit TetBoxFilter(const TetMesh& mesh);

  std::size_t tet_count() const { return bounds_.size(); }
  /// A box holding the tet (its bounding box rounded outward to floats; `tet` < tet_count(),
  /// unchecked).
  geometry::Box bounds(std::uint32_t tet) const { return bounds_[tet].box(); }
  /// Whether the tet's box meets `query` (a box rounded outward to floats, once for a search
  /// that asks many tets: no conversion per tet).
  bool bounds_overlap(std::uint32_t tet, const geometry::FloatBox& query) const {
    return geometry::boxes_overlap(bounds_[tet], query);
  }
  /// False only when the box lies strictly outside one of the tet's face planes (including
  /// every rounding): true for every tet that meets the box. `box` must be finite.
  bool planes_may_meet(std::uint32_t tet, const geometry::Box& box) const {
    return planes_may_meet(tet, box, magnitude(box));
  }
  /// The same with magnitude(box) computed by the caller (a search asks many tets of one box).
  bool planes_may_meet(std::uint32_t tet, const geometry::Box& box, double box_magnitude) const {
    // The box's farthest corner along a normal n, as n . centre + |n| . half-extents: no
    // branch per axis, and the four planes side by side (the centre's and the half extents'
    // roundings, 2^-52 of the magnitude, are within the margin).
    const Planes& planes = planes_[tet];
    double centre[3], half[3];
    for (int a = 0; a < 3; ++a) {
      centre[a] = 0.5 * (box.lo[a] + box.hi[a]);
      half[a] = 0.5 * (box.hi[a] - box.lo[a]);
    }
    const double margin = box_magnitude * kRelativeMargin;
    bool separated = false;
    for (int k = 0; k < 4; ++k) {
      double highest = 0;
      for (int a = 0; a < 3; ++a) {
        const double n = planes.normal[a][k];
        highest += n * centre[a] + std::fabs(n) * half[a];
      }
      separated |= highest < double(planes.offset[k]) - margin;
    }
    return !separated;
  }
  /// The bounding boxes overlap and planes_may_meet.
  bool may_meet(std::uint32_t tet, const geometry::Box& box) const {
    return geometry::boxes_overlap(bounds(tet), box) && planes_may_meet(tet, box);
  }
  /// The largest coordinate's magnitude, which bounds the planes' rounding.
  static double magnitude(const geometry::Box& box);
  std::size_t memory_bytes() const {
    return bounds_.capacity() * sizeof(geometry::FloatBox) + planes_.capacity() * sizeof(Planes);
  }

 private:
  // The roundings: normal . x in double, for |normal|_1 < 2, is off by less than 2^-48 of the
  // largest coordinate's magnitude (the query's centre and half extents included); both the
  // offset and the query are given 2^-45 of theirs.
  static constexpr double kRelativeMargin = 0x1p-45;
  // Face k's normal, pointing into the tet and scaled to about unit 1-norm, rounded to float
  // (any direction would do: the offset is taken from the rounded normal), and an offset no
  // larger than the smallest value of normal . x over the tet's corners, rounded down to float
  // (16 B a tet less, no slower). The boxes are floats too (24 B a tet less: 2.4 MiB at 100M
  // triangles, beside a shard budget that may be 64 MiB).
  struct Planes {
    std::array<std::array<float, 4>, 3> normal;  ///< normal[axis][face]
    std::array<float, 4> offset;
  };
  std::vector<geometry::FloatBox> bounds_;
  std::vector<Planes> planes_;
};

}  // namespace tetrapage
