#pragma once
/// @file ObjectGenerator.h
/// The study's flying objects (section 4.1, Table 2: 4, 116, 496, 2094, 5152 and 14643
/// triangles), scaled uniformly so that their bounding box fits a cube of side 0.05 and
/// centred at the origin (the object's own frame). Up to 4 triangles: a regular tetrahedron;
/// up to sphere_object_limit: a UV sphere; above: a real mesh simplified to about the
/// requested count by CGAL's edge-collapse simplification.

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/tools/MeshLibrary.h"

namespace tetrapage {

/// Largest triangle count that gives a UV sphere rather than a real mesh.
inline constexpr std::uint64_t sphere_object_limit = 200;
/// Largest accepted ObjectOptions::triangles.
inline constexpr std::uint64_t max_object_triangles = 10'000'000;

struct ObjectOptions {
  std::uint64_t triangles = 116;  ///< the study's sphere ("socbal") by default
  /// Without a seed, the real mesh is the one with the fewest triangles at or above the
  /// request (ties by name); with a seed, a random one among all at or above the request.
  /// Tetrahedron and spheres do not depend on it.
  std::optional<std::uint64_t> seed;
  double size = 0.05;  ///< side of the cube the object is fitted into
};

struct GeneratedObject {
  TriangleSoup soup;  ///< one part, named after `source`
  /// "tetrahedron", "uv-sphere 12x6" (slices x stacks), or the mesh name followed by
  /// " simplified" / " subdivided N times, simplified" / " as is".
  std::string source;
  std::uint64_t source_triangles = 0;  ///< before simplification
  bool closed = false;                 ///< every edge has exactly two faces
  /// Real meshes that were tried and given up, each as "name: reason".
  std::vector<std::string> rejected;
};

/// True when generate_object needs a MeshLibrary for this triangle count.
inline bool object_needs_meshes(std::uint64_t triangles) {
  return triangles > sphere_object_limit;
}

/// The UV sphere's (slices, stacks) whose 2 * slices * (stacks - 1) triangles are closest to
/// `triangles`, preferring slices close to 2 * stacks (square-ish quads); at least (3, 2).
std::pair<std::size_t, std::size_t> uv_sphere_resolution(std::uint64_t triangles);

/// Builds the flying object. `library` is used (and required) only when
/// object_needs_meshes(options.triangles). A closed real mesh is preferred; it is loaded into
/// a CGAL::Surface_mesh (polygon soup, repaired and oriented, then turned into a mesh),
/// refined by Loop subdivision if no mesh is large enough, and simplified with edge
/// collapses down to about options.triangles; a mesh whose simplification fails or misses
/// the count by more than 5% is given up for the next candidate. Deterministic.
/// @throw InputError if options are out of range, if a library is needed and missing, or if
///        no mesh of the library could be simplified (the message lists why each failed).
GeneratedObject generate_object(const ObjectOptions& options, const MeshLibrary* library = nullptr);

}  // namespace tetrapage
