#pragma once
/// @file StabbingNumbers.h
/// The study's average line stabbing number of a mesh (section 4.2.1): for random segments
/// between pairs of uniform points in the model's box (the study's unit cube), the number of
/// tets each segment meets divided by its length, averaged. Counted twice, independently: by
/// the runtime's walk (walk_segment: the tets it passes through) and by Embree (the faces the
/// segment crosses, plus one), and compared segment by segment.

#include <cstdint>
#include <vector>

#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/runtime/geometry/Shapes.h"
#include "tetrapage/tools/EmbreeMeshFaces.h"

namespace tetrapage {

struct StabbingOptions {
  std::uint64_t segments = 10'000;
  std::uint64_t seed = 1;
  /// Segments whose counts differ that the result keeps (all are counted).
  std::size_t max_listed = 100;
};

/// A segment on which the walk and Embree count different numbers of tets.
struct StabbingDifference {
  geometry::Point a{}, b{};
  std::uint64_t walk_tets = 0;
  std::uint64_t embree_tets = 0;
};

struct StabbingNumbers {
  std::uint64_t segments = 0;
  /// Mean over the segments of tets met per unit length (model units).
  double walk = 0;
  double embree = 0;
  /// Mean tets met per segment and mean segment length.
  double walk_tets_per_segment = 0;
  double mean_length = 0;
  /// Segments the walk could not follow to the end (leaving the mesh; none when the box lies
  /// inside the mesh, as preprocess's enlarged box guarantees).
  std::uint64_t incomplete_walks = 0;
  std::uint64_t differing = 0;
  std::vector<StabbingDifference> differences;
  double seconds = 0;
};

/// Measures the stabbing numbers of faces.mesh() over segments in `box` (deterministic for a
/// seed; each walk starts from the tet where the previous one ended).
/// @throw InputError if the box is empty, a single point, or not finite.
/// @throw Error as walk_segment, or if Embree fails.
StabbingNumbers measure_stabbing_numbers(const EmbreeMeshFaces& faces, const BoundingBox& box,
                                         const StabbingOptions& options = {});

}  // namespace tetrapage
