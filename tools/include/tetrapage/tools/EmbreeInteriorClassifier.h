#pragma once
/// @file EmbreeInteriorClassifier.h
/// Classifies points against closed parts by Embree ray parity (issue 6, "interiors"): from each
/// point, rays in several fixed directions count their crossings with each part's surface;
/// a part holds the point when the count is odd. The parts given are closed (EdgeParity), so a
/// ray can only be wrong where it passes through an edge or a vertex (Embree may count both
/// triangles there) or starts within float precision of a surface: the point is decided when
/// every ray agrees, and undecided otherwise (preprocess then moves it within its tet and asks
/// again). Embree works
/// in float: coordinates are taken relative to the centre of the triangles' box before rounding.
#include <memory>

#include "tetrapage/preprocess/InteriorClassifier.h"

namespace tetrapage {

class EmbreeInteriorClassifier final : public InteriorClassifier {
 public:
  /// @param rays the directions per point (2 to 5), all of which must agree.
  explicit EmbreeInteriorClassifier(unsigned rays = 3);
  ~EmbreeInteriorClassifier() override;
  std::uint64_t bytes_per_triangle() const override;
  void add_triangles(std::uint32_t part, std::span<const std::array<Vec3, 3>> triangles) override;
  /// @throw Error when Embree cannot build the scene (it names Embree's error).
  void classify(std::span<const Vec3> points, std::vector<PointInterior>& out) override;

  class Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

/// A factory for PreprocessOptions::interior_classifier.
InteriorClassifierFactory embree_interior_classifier(unsigned rays = 3);

}  // namespace tetrapage
