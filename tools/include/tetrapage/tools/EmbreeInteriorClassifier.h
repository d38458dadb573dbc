#pragma once
/// @file EmbreeInteriorClassifier.h
/// Classifies points against closed parts by Embree ray parity: from each point, rays in
/// several fixed directions count their crossings with each part's surface; a part holds the
/// point when the count is odd. Preprocess classifies exactly (RayParity.h); this independent
/// engine checks it in the tests. The parts given are closed (EdgeParity), so a
/// ray can only be wrong where it passes through an edge or a vertex (Embree may count both
/// triangles there) or starts within float precision of a surface: the point is decided when
/// every ray agrees, and undecided otherwise. Embree works
/// in float: coordinates are taken relative to the centre of the triangles' box before rounding.
#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "tetrapage/formats/base/TriangleSoup.h"

namespace tetrapage {

/// The closed parts that hold one point.
struct PointInterior {
  /// False when the rays disagreed (an open or self-overlapping surface, or a point within
  /// float precision of a surface).
  bool decided = true;
  std::vector<std::uint32_t> parts;  ///< closed parts whose surface has odd parity around it
};

class EmbreeInteriorClassifier final {
 public:
  /// @param rays the directions per point (2 to 5), all of which must agree.
  explicit EmbreeInteriorClassifier(unsigned rays = 3);
  ~EmbreeInteriorClassifier();
  /// Adds triangles of closed part `part` (any number of calls, any part order).
  void add_triangles(std::uint32_t part, std::span<const std::array<Vec3, 3>> triangles);
  /// Classifies the points (after all triangles were added); out[i] answers points[i].
  /// @throw Error when Embree cannot build the scene (it names Embree's error).
  void classify(std::span<const Vec3> points, std::vector<PointInterior>& out);

  class Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace tetrapage
