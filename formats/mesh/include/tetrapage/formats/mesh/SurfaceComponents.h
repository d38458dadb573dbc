#pragma once
/// @file SurfaceComponents.h
/// The connected components of a soup's surfaces: within each part, triangles that share a
/// vertex (vertices at identical coordinates are shared, -0.0 is 0.0) belong to one component.
/// A file very often holds many solids, some closed and some open, so closedness, insides and
/// containment are decided per component, never per file or part.

#include <cstdint>
#include <vector>

#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/formats/mesh/EdgeParity.h"

namespace tetrapage {

struct SurfaceComponent {
  std::uint32_t part = 0;  ///< the soup's part it belongs to
  /// Every edge (an unordered pair of vertex positions) is used an even number of times
  /// (EdgeParity), so ray parity gives it an inside, self-intersecting or not.
  bool closed = false;
  std::uint64_t triangles = 0;
  std::uint64_t first_triangle = 0;  ///< the soup's index of its first triangle
  BoundingBox bounds;
  Vec3 vertex{};  ///< the first corner of its first triangle: one point of the component
};

struct SurfaceComponents {
  std::vector<std::uint32_t> component_of;  ///< per triangle
  /// Numbered in the order of their first triangles (the same soup gives the same numbers).
  std::vector<SurfaceComponent> components;
  /// Per component, its edges folded: components of one surface found apart (in chunks of a
  /// file) unite by merging theirs.
  std::vector<EdgeParity> parities;

  std::size_t closed_count() const;
};

/// Finds the components of `soup` (linear time: one hash of each distinct vertex position).
SurfaceComponents find_surface_components(const TriangleSoup& soup);

/// The bytes find_surface_components allocates at its peak for a soup of `vertices` vertex
/// entries and `triangles` triangles (the soup not counted): its tables, arrays counted twice
/// while they grow, distinct positions taken as the vertices of an indexed soup and a sixth of
/// an STL's corners, and one component per 64 triangles (a file of many tiny solids holds more).
std::uint64_t surface_components_bytes(std::uint64_t vertices, std::uint64_t triangles);

}  // namespace tetrapage
