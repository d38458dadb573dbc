#pragma once
/// @file ObjectInteriorGrid.h
/// A closed flying object's own box cut into cells, each known to lie wholly inside the object,
/// wholly outside, or to meet its surface. "Is this obstacle vertex inside the object?" is then
/// one lookup for a point away from the surface, instead of a ray-parity test whose segment
/// crosses the whole object: in a dense model a large object encloses thousands of candidate
/// vertices per step, and those tests were most of the step's time.
///
/// Exact: a cell is "inside" or "outside" only when the exact triangle/box test finds no object
/// triangle meeting its closed box, so every point of it is on one side, and the side of each
/// group of face-adjacent surface-free cells is decided by an exact ray parity from one cell's
/// centre (in the object's own, unrounded coordinates).

#include <algorithm>
#include <cstdint>
#include <optional>
#include <vector>

#include "tetrapage/runtime/geometry/ObjectBVH.h"
#include "tetrapage/runtime/geometry/SegmentTriangle.h"

namespace tetrapage {

/// Which closed component of an object each triangle belongs to: insides are counted per
/// closed component (a multi-solid object, nested solids), and open components have none.
struct ClosedComponentOf {
  static constexpr std::uint32_t kOpen = 0xffffffffu;
  std::vector<std::uint32_t> of_triangle;  ///< per object triangle: its closed component, or kOpen
  std::uint32_t count = 0;                 ///< closed components
};

/// Whether `segment` crosses some closed component of the object an odd number of times,
/// counting the object's triangles whose boxes meet `query` (in the BVH's frame), each given
/// by `triangle_of(t)` (its own or its placed coordinates); nothing when the segment touches an
/// edge, a vertex or a closed component's triangle's plane, or ends on one (the caller tries
/// another direction).
template <class TriangleOf>
std::optional<bool> crossing_parity(const geometry::ObjectBVH& bvh, const ClosedComponentOf& closed,
                                    const geometry::Segment& segment, const geometry::Box& query,
                                    TriangleOf&& triangle_of) {
  bool generic = true;
  // Parities by closed component: one word for up to 64 of them, bytes beyond.
  std::uint64_t odd_bits = 0;
  std::vector<std::uint8_t> odd_bytes(closed.count > 64 ? closed.count : 0, 0);
  bvh.for_each_in_box(query, [&](std::uint32_t t) {
    const std::uint32_t component = closed.of_triangle[t];
    if (component == ClosedComponentOf::kOpen) return true;
    const auto hit = geometry::classify_segment_triangle(segment, triangle_of(t));
    if (!hit) return true;
    if (hit.contact != geometry::SegmentTriangleContact::interior || hit.at_endpoint) {
      generic = false;
      return false;
    }
    if (odd_bytes.empty())
      odd_bits ^= std::uint64_t(1) << component;
    else
      odd_bytes[component] ^= 1;
    return true;
  });
  if (!generic) return std::nullopt;
  return odd_bits != 0 || std::find(odd_bytes.begin(), odd_bytes.end(), 1) != odd_bytes.end();
}

class ObjectInteriorGrid {
 public:
  enum class Side : std::uint8_t { unknown, outside, inside };

  ObjectInteriorGrid() = default;
  /// Builds the grid over the object `bvh` (its triangles, object frame) whose closed
  /// components `closed` names (at least one), about 3 * cbrt(triangles) cells per axis (16 to
  /// 48). A cell is inside when inside some closed component.
  ObjectInteriorGrid(const geometry::ObjectBVH& bvh, const ClosedComponentOf& closed);

  /// The side of every point within `margin` (per coordinate) of `x` (object frame), or
  /// unknown when that cube reaches a cell meeting the surface, cells of both sides, or the
  /// outside of the grid's box.
  Side classify(const Vec3& x, double margin) const;

  std::size_t cells_per_axis() const { return n_; }
  /// Cells by side (for tests and reports).
  std::size_t count(Side side) const;

 private:
  std::size_t index(std::size_t i, std::size_t j, std::size_t k) const { return (k * n_ + j) * n_ + i; }
  // The cell along axis a holding coordinate v (clamped; callers check the box first).
  std::size_t cell_of(int a, double v) const;

  std::size_t n_ = 0;
  geometry::Box box_;
  std::array<std::vector<double>, 3> cuts_;
  std::vector<Side> sides_;
};

}  // namespace tetrapage
