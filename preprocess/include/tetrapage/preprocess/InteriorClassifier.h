#pragma once
/// @file InteriorClassifier.h
/// What preprocess needs to store the interiors of closed obstacles (the study's footnote 3):
/// the coarse tets do not conform to the obstacles, so a region can lie partly inside one. For
/// each tet, a reference point is classified against every closed part, and the runtime later
/// decides whether any point of that tet is inside by the parity of crossings between the
/// tet's own triangles and the segment from the reference point (DESIGN.md: the runtime does
/// not shoot rays through the whole model). The classifier is a ray-shooting engine behind
/// this interface, so that preprocess does not depend on it (tools give Embree's).
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "tetrapage/formats/TriangleSoup.h"

namespace tetrapage {

/// The closed parts that hold one point.
struct PointInterior {
  /// False when the rays disagreed (an open or self-overlapping surface, or a point within the
  /// engine's precision of a surface): such a point is counted and never used.
  bool decided = true;
  std::vector<std::uint32_t> parts;  ///< closed parts whose surface has odd parity around it
};

class InteriorClassifier {
 public:
  virtual ~InteriorClassifier() = default;
  /// Bytes held per added triangle (to decide whether the closed parts fit the --memory budget).
  virtual std::uint64_t bytes_per_triangle() const = 0;
  /// Adds triangles of closed part `part` (any number of calls, any part order).
  virtual void add_triangles(std::uint32_t part,
                             std::span<const std::array<Vec3, 3>> triangles) = 0;
  /// Classifies the points (after all triangles were added); out[i] answers points[i].
  virtual void classify(std::span<const Vec3> points, std::vector<PointInterior>& out) = 0;
};

using InteriorClassifierFactory = std::function<std::unique_ptr<InteriorClassifier>()>;

}  // namespace tetrapage
