#pragma once
/// @file MeshMethod.h
/// The study's mesh method (section 2): a tetrahedral mesh conforming to the obstacles, made
/// from the Delaunay triangulation of the obstacle vertices by inserting Steiner points at the
/// intersections of obstacle edges with mesh faces and of mesh edges with obstacle triangles,
/// at most one per obstacle triangle per round, until every obstacle triangle is a union of
/// mesh faces (section 2.2). A query locates a corner of BB(F) by walking from the previous
/// step's tet, enumerates the tets whose boxes overlap BB(F) by breadth-first search (phase I,
/// nO), and tests the object against the obstacle triangles on their faces (phase II).

#include <memory>
#include <span>

#include "tetrapage/study/StudyMethod.h"

namespace tetrapage::study {

struct MeshMethodOptions {
  /// Rounds of Steiner insertion before giving up on conformity (the mesh is still correct
  /// for queries: see make_mesh_method).
  unsigned max_rounds = 64;
  /// Stop inserting once the vertex count exceeds this factor times the obstacle vertices.
  double max_growth = 10.0;
  /// Extra Steiner points on a regular n x n x n grid over the workspace (the study added
  /// 10 x 10 x 10 to its terrains to lower the stabbing number for boxes); 0 = none.
  unsigned grid_points = 0;
};

/// Builds the conforming mesh over `obstacles` (world coordinates; degenerate triangles are
/// kept as their edges, duplicates and self-intersections are allowed). Every obstacle
/// triangle is attached to each tet it meets (exact triangle/tetrahedron test), so queries are
/// exact even where conformity was not reached within the limits; statistics() reports the
/// Steiner points, the growth factor, tets, tets per vertex, the triangles left non-conforming
/// and the rounds taken.
/// @throw InputError for no obstacles or non-finite coordinates.
std::unique_ptr<StudyMethod> make_mesh_method(std::span<const geometry::Triangle> obstacles,
                                              const MeshMethodOptions& options = {});

}  // namespace tetrapage::study
