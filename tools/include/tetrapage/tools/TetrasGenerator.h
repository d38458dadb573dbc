#pragma once
/// @file TetrasGenerator.h
/// The study's "tetras" (section 4.1, Table 1: 100 to 16,000 triangles): a random BSP
/// partition of the unit cube, a random subset of whose leaves each hold one random
/// tetrahedron. Each tetrahedron is a closed, outward-oriented 4-triangle part, streamed to
/// the writer as it is made.

#include <cstdint>

#include "tetrapage/formats/base/Progress.h"
#include "tetrapage/formats/mesh/MeshWriter.h"

namespace tetrapage {

struct TetrasOptions {
  std::uint64_t triangles = 4000;  ///< 4 per tetrahedron: triangles/4 tetrahedra (rounded)
  std::uint64_t seed = 1;
  double leaves_per_tetra = 2.0;  ///< BSP leaves per tetrahedron: half the leaves stay empty
  /// A tetrahedron is redrawn while its volume is below this fraction of its box's volume
  /// (a random tetrahedron in a box has 1.4% of its volume on average), so that no sliver
  /// is left in the scene.
  double min_volume_fraction = 0.005;
  /// Corners are drawn in the leaf shrunk by this fraction of its size on every side, so
  /// tetrahedra in adjacent leaves never touch.
  double margin = 0.05;
};

/// Largest accepted TetrasOptions::triangles (the BSP holds ~100 bytes per tetrahedron).
inline constexpr std::uint64_t max_tetras_triangles = 1'000'000'000ULL;

struct TetrasSummary {
  std::uint64_t tetras = 0;
  std::uint64_t triangles = 0;
  std::uint64_t vertices = 0;
  std::size_t leaves = 0;
  double alpha = 0.0;
  std::uint64_t redraws = 0;  ///< tetrahedra rejected for a too small volume
  BoundingBox bounds;
};

/// Generates the tetras and appends them to `writer`, one part (4 vertices, 4 triangles,
/// named "tetra#<k>", k from 0) per tetrahedron; the caller commits. Each part's corners v0..v3
/// satisfy orient3d(v0, v1, v2, v3) > 0 and its faces face outward. Deterministic.
/// @throw InputError for options out of range (names the option and the value).
/// @throw IoError if the writer fails.
TetrasSummary generate_tetras(const TetrasOptions& options, MeshWriter& writer,
                              Progress& progress = Progress::silent());

}  // namespace tetrapage
