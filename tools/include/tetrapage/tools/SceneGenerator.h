#pragma once
/// @file SceneGenerator.h
/// The study's "scenes" (section 4.1): a random BSP partition of the unit cube, a random
/// subset of whose leaves each hold one scaled, randomly rotated copy of a real mesh. The
/// meshes are chosen so that the total reaches about the requested number of triangles; each
/// copy is streamed to the writer as its own part, so memory stays at the size of the mesh
/// library plus a few numbers per copy, whatever the size of the scene.

#include <cstdint>
#include <string>
#include <vector>

#include "tetrapage/formats/MeshWriter.h"
#include "tetrapage/formats/Progress.h"
#include "tetrapage/tools/MeshLibrary.h"
#include "tetrapage/tools/Random.h"

namespace tetrapage {

struct SceneOptions {
  std::uint64_t triangles = 22400;  ///< target total (a study-sized scene by default)
  std::uint64_t seed = 1;
  double leaves_per_copy = 2.0;  ///< BSP leaves per copy: half the leaves stay empty
  double fill = 0.9;             ///< a copy spans this fraction of its leaf along its
                                 ///< tightest axis, so copies in adjacent leaves never touch
};

/// Largest accepted SceneOptions::triangles.
inline constexpr std::uint64_t max_scene_triangles = 10'000'000'000ULL;

struct SceneCopy {
  std::size_t mesh = 0;  ///< index into the library
  BoundingBox leaf;      ///< the BSP leaf it was placed in
  BoundingBox placed;    ///< bounds of its placed vertices (inside `leaf`)
  std::uint64_t triangles = 0;
};

struct SceneSummary {
  std::uint64_t triangles = 0;
  std::uint64_t vertices = 0;
  std::size_t leaves = 0;         ///< BSP leaves (copies fill a random subset)
  double alpha = 0.0;             ///< the BSP's split margin
  std::vector<SceneCopy> copies;  ///< in the order they were written (part k = copies[k])
  BoundingBox bounds;
};

/// Which library meshes make up a scene of about `triangles` triangles, in placement order:
/// while the remaining budget is positive, a mesh is drawn uniformly among those that fit in
/// it; when none fits, the smallest mesh is added if that brings the total closer to the
/// target. The total is then within half the smallest mesh of the target (or the smallest
/// mesh itself for a tiny target).
/// @throw InputError if triangles is 0 or above max_scene_triangles.
std::vector<std::size_t> plan_scene_copies(const MeshLibrary& library, std::uint64_t triangles,
                                           Random& random);

/// Generates a scene and appends its copies to `writer` (one part per copy, in the order of
/// SceneSummary::copies); the caller commits. Deterministic: the same library, options and
/// seed give the same parts.
/// @throw InputError for options out of range (names the option and the value).
/// @throw IoError if the writer fails.
SceneSummary generate_scene(const MeshLibrary& library, const SceneOptions& options,
                            MeshWriter& writer, Progress& progress = Progress::silent());

}  // namespace tetrapage
