#pragma once
// Convex-hull helpers shared by ObjectModel (the hull graph and planes) and FlyingObject (the
// hull and swept solids): CGAL's hull of points, as vertices and triangles, and its planes.
// Internal to the runtime's sources.

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/runtime/geometry/Shapes.h"

namespace tetrapage::hull {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;

inline geometry::Point to_point(const Kernel::Point_3& p) {
  return {p.x(), p.y(), p.z()};
}

/// The convex hull of the points as vertices and triangles (outward, coplanar facets
/// triangulated; nothing for fewer than three non-collinear points).
void hull_of(const std::vector<Kernel::Point_3>& points, std::vector<Kernel::Point_3>& vertices,
             std::vector<std::array<std::size_t, 3>>& faces);

/// The object's distinct vertex positions that some triangle uses, as CGAL points, and the
/// first vertex id of each position.
void distinct_triangle_vertices(const TriangleSoup& object, std::vector<Kernel::Point_3>& points,
                                std::map<std::array<double, 3>, std::uint32_t>& id_of);

/// The facets' planes of a hull (outward unit normal n and offset: n.x <= offset inside, up to
/// rounding), skipping facets without area.
std::vector<std::pair<Vec3, double>> facet_planes(
    const std::vector<Kernel::Point_3>& hull_points,
    const std::vector<std::array<std::size_t, 3>>& faces);

}  // namespace tetrapage::hull
