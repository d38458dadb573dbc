#pragma once
/// @file ObjectSolid.h (private)
/// The solid that stands for the object in one step (shape hull or box, or swept motion):
/// built on the first candidate that needs it; does an environment triangle collide with it?

#include <array>
#include <cstdint>
#include <vector>

#include "Coherence.h"
#include "PlacedObject.h"
#include "tetrapage/runtime/geometry/Accuracy.h"
#include "tetrapage/runtime/geometry/Box.h"
#include "tetrapage/runtime/geometry/ConvexHull.h"
#include "tetrapage/runtime/geometry/Predicates.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/runtime/query/ObjectModel.h"

namespace tetrapage {

/// A box, or a convex hull as triangles (CGAL's hull, outward, coplanar facets triangulated)
/// with the orient3d sign of outside points.
struct ObjectSolid {
  enum class Kind : std::uint8_t { box, hull } kind = Kind::box;
  bool built = false;
  geometry::Box box;  ///< box: the solid; hull: the hull's box
  std::vector<geometry::Triangle> faces;
  std::vector<geometry::Box> face_boxes;
  /// zero for a flat hull (no inside: only its faces count)
  geometry::Sign outside = geometry::Sign::zero;
  // Scratch of the hull construction.
  std::vector<hull::Kernel::Point_3> points, hull_points;
  std::vector<std::array<std::size_t, 3>> hull_faces;

  /// The solid of this step's question: its world box, or the hull of the placed vertices,
  /// over both poses when the motion is swept and a previous pose exists.
  void build(const QueryOptions& options, const ObjectModel& model, PlacedObject& object,
             const Coherence& coherence);
  /// Does `environment` collide with the solid (within the accuracy's `reach`)?
  bool collides(const geometry::Triangle& environment, const geometry::Accuracy& accuracy,
                double reach) const;
};

}  // namespace tetrapage
