#pragma once
/// @file RayParity.h
/// Which closed parts hold each of a set of points, decided exactly from one pass over the
/// parts' triangles (the study's footnote 3: the interiors that preprocess stores per tet).
///
/// A part holds a point when the upward vertical ray from it crosses the part's surface an odd
/// number of times; the surface is closed (EdgeParity), so the parity is the same for every
/// ray. The point is perturbed symbolically by (e, e^2, e^4), as orient3d_perturbed_query does,
/// so a ray through an edge or a vertex is counted once, consistently, on every input. A point
/// that lies on a triangle of a part is reported as on that part's surface: its answer would
/// depend on the perturbation (preprocess moves such a point and asks again).
///
/// Nothing of the triangles is kept: memory is 29 bytes per (point, part) pair asked.

#include <atomic>
#include <cstdint>
#include <span>
#include <vector>

#include "tetrapage/runtime/geometry/Shapes.h"

namespace tetrapage {

enum class VerticalRayCrossing : std::uint8_t {
  none,     ///< the ray from the perturbed point misses the triangle
  crosses,  ///< it crosses the triangle's interior, once
  touches,  ///< the point itself lies on the (closed) triangle
};

/// The upward vertical ray from q + (e, e^2, e^4), for an infinitesimal e > 0, against t.
/// Exact: every decision is an exact orientation sign.
VerticalRayCrossing vertical_ray_crossing(const geometry::Point& q, const geometry::Triangle& t);

/// Accumulates ray parities for (point, part) pairs; triangles may come in any order, from any
/// number of threads at once.
class RayParity {
 public:
  /// points_of_part[p]: the indices (into points) of the points to classify against part p
  /// (those in p's box: outside a part's box is outside the part). Parts with no points, or
  /// beyond the vector's size, are skipped cheaply.
  RayParity(std::span<const geometry::Point> points,
            const std::vector<std::vector<std::uint32_t>>& points_of_part);

  /// Whether part p has points to classify (its triangles are worth adding).
  bool wanted(std::uint32_t part) const {
    return part + 1 < offsets_.size() && offsets_[part] != offsets_[part + 1];
  }

  /// Folds in one triangle of part `part`.
  void add_triangle(std::uint32_t part, const geometry::Triangle& t);

  /// Calls visit(point, part, inside, on_surface) for every pair, part by part.
  template <class Visit>
  void for_each_answer(Visit&& visit) const {
    for (std::uint32_t p = 0; p + 1 < offsets_.size(); ++p)
      for (std::uint64_t i = offsets_[p]; i < offsets_[p + 1]; ++i) {
        const std::uint8_t state = state_[i].load(std::memory_order_relaxed);
        visit(point_index_[i], p, (state & kOdd) != 0, (state & kTouched) != 0);
      }
  }

  /// The number of (point, part) pairs.
  std::uint64_t pair_count() const { return point_index_.size(); }

 private:
  static constexpr std::uint8_t kOdd = 1, kTouched = 2;
  std::vector<std::uint64_t> offsets_;      ///< per part, into the pair arrays; size parts + 1
  std::vector<std::uint32_t> point_index_;  ///< per pair
  /// Per pair, sorted by x within a part (copied: a triangle reads a run of them).
  std::vector<geometry::Point> points_;
  std::vector<std::atomic<std::uint8_t>> state_;  ///< per pair: kOdd | kTouched
};

}  // namespace tetrapage
