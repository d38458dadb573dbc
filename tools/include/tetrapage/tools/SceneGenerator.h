#pragma once
/// @file SceneGenerator.h
/// The study's "scenes" (section 4.1): a random BSP partition of the unit cube, a random
/// subset of whose leaves each hold one scaled, randomly rotated copy of a real mesh. The
/// meshes are chosen so that the total reaches about the requested number of triangles; each
/// copy is streamed to the writer as its own part, so memory stays at the size of the mesh
/// library plus a few numbers per copy, whatever the size of the scene.
///
/// Real CAD exports mix closed solids with open sheets and scanned shells in one file, so a
/// fraction of the copies can be opened: the triangles above a random plane through the copy
/// are dropped, leaving a shell with a hole, still in one piece.

#include <cstdint>
#include <string>
#include <vector>

#include "tetrapage/formats/base/Progress.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/tools/MeshLibrary.h"
#include "tetrapage/tools/Random.h"

namespace tetrapage {

struct SceneOptions {
  std::uint64_t triangles = 22400;  ///< target total (a study-sized scene by default)
  std::uint64_t seed = 1;
  double leaves_per_copy = 2.0;  ///< BSP leaves per copy: half the leaves stay empty
  double fill = 0.9;             ///< a copy spans this fraction of its leaf along its
                                 ///< tightest axis, so copies in adjacent leaves never touch
  /// Fraction of the copies opened, in [0, 1]. 0 (all closed, as the study's scenes) here so
  /// that library callers keep closed obstacles; `generate scene` defaults to
  /// default_scene_open_fraction.
  double open_fraction = 0.0;
};

/// The `generate scene` command's --open-fraction default.
inline constexpr double default_scene_open_fraction = 0.25;

/// Largest accepted SceneOptions::triangles.
inline constexpr std::uint64_t max_scene_triangles = 10'000'000'000ULL;

/// How a copy is opened, in its mesh's own frame (the copy is rotated at random afterwards,
/// so the plane's direction is random in the scene too): the plane is perpendicular to
/// `direction` at `height` of the mesh's extent along it.
struct SceneCut {
  Vec3 direction{0.0, 0.0, 1.0};  ///< unit vector
  double height = 1.0;            ///< in [0.6, 0.9] when drawn
};

/// One copy of the plan: which mesh, whether it is opened, and how many triangles it writes.
struct PlannedCopy {
  std::size_t mesh = 0;  ///< index into the library
  bool open = false;     ///< the cut dropped triangles (a cut that drops none leaves it closed)
  SceneCut cut;          ///< meaningful when `open`
  std::uint64_t triangles = 0;  ///< the mesh's count, less what the cut drops
};

struct SceneCopy {
  std::size_t mesh = 0;         ///< index into the library
  BoundingBox leaf;             ///< the BSP leaf it was placed in
  BoundingBox placed;           ///< bounds of its placed vertices (inside `leaf`)
  std::uint64_t triangles = 0;  ///< as written (fewer than the mesh's when open)
  bool open = false;  ///< an open shell (some of the mesh's triangles dropped), else closed
};

struct SceneSummary {
  std::uint64_t triangles = 0;
  std::uint64_t vertices = 0;
  std::size_t open_copies = 0;    ///< copies written as open shells
  std::size_t closed_copies = 0;  ///< copies written whole (closed: the curated meshes are)
  std::size_t leaves = 0;         ///< BSP leaves (copies fill a random subset)
  double alpha = 0.0;             ///< the BSP's split margin
  std::vector<SceneCopy> copies;  ///< in the order they were written (part k = copies[k])
  BoundingBox bounds;
};

/// Which library meshes make up a scene of about `triangles` triangles, in placement order:
/// while the remaining budget is positive, a mesh is drawn uniformly among those that fit in
/// it; when none fits, the smallest mesh is added if that brings the total closer to the
/// target. Copy k is opened when floor((k + 1) f + phase) > floor(k f + phase) (f the open
/// fraction, phase uniform), so the fraction holds even in a scene of a few copies. An opened
/// copy draws a cut and keeps the triangles with a corner on or below its plane, and of those
/// only the largest connected piece (a cut can sever a leg or a knot's arc). The budget counts
/// the kept triangles, so the total is still within half the smallest mesh of the target (or
/// the smallest mesh itself for a tiny target). With f = 0 nothing more is drawn from the
/// random stream, so the all-closed plan is the same as without the option.
/// @throw InputError if triangles is 0 or above max_scene_triangles, or f is not in [0, 1].
std::vector<PlannedCopy> plan_scene_copies(const MeshLibrary& library, std::uint64_t triangles,
                                           double open_fraction, Random& random);

/// @throw InputError for options out of range (names the option and the value).
void check_scene_options(const SceneOptions& options);

/// Generates a scene and appends its copies to `writer` (one part per copy, in the order of
/// SceneSummary::copies, named "<mesh>#<n>" for the n-th copy of a mesh, from 0); the caller
/// commits. Deterministic: the same library, options and
/// seed give the same parts.
/// @throw InputError for options out of range (names the option and the value).
/// @throw IoError if the writer fails.
SceneSummary generate_scene(const MeshLibrary& library, const SceneOptions& options,
                            MeshWriter& writer, Progress& progress = Progress::silent());

}  // namespace tetrapage
