#pragma once
/// @file TerrainGenerator.h
/// The study's "terrains" (section 4.1): 1201 x 1201 "1-degree DEM" elevation arrays sampled
/// to 120 x 120 and triangulated. We have no DEM files, so the elevations are a fractal
/// (diamond-square on a (2^k+1)^2 grid, cropped to 1201 x 1201, or to the sample count when
/// more samples are asked for), sampled bilinearly to s x s points with 2 (s-1)^2 close to
/// the requested triangle count. The surface is open (a heightfield, not a solid).

#include <cstdint>

#include "tetrapage/formats/base/Progress.h"
#include "tetrapage/formats/mesh/MeshWriter.h"

namespace tetrapage {

struct TerrainOptions {
  /// Target triangle count; the default is the study's 120 x 120 samples (2 * 119^2).
  /// 2,880,000 gives the full 1201 x 1201 resolution.
  std::uint64_t triangles = 28322;
  std::uint64_t seed = 1;
  /// Amplitude ratio between successive diamond-square levels is 2^-roughness: 1 is smooth,
  /// 0 is noise; real terrains are around 0.7-0.9.
  double roughness = 0.8;
  /// Heights are mapped linearly onto [low, high] (lowest sample at low, highest at high), so
  /// that objects can fly above the terrain inside the unit cube.
  double slab_low = 0.05;
  double slab_high = 0.45;
};

/// Largest accepted TerrainOptions::triangles: 8193^2 samples (the fractal grid holds 4 bytes
/// per sample, 268 MB at this size).
inline constexpr std::uint64_t max_terrain_triangles = 2ULL * 8192 * 8192;

/// The source grid's side in the study (1201 x 1201 DEM).
inline constexpr std::size_t dem_grid_side = 1201;

struct TerrainSummary {
  std::size_t samples_per_side = 0;  ///< s: the surface has s x s vertices
  std::size_t source_side = 0;       ///< side of the cropped elevation grid that was sampled
  std::size_t fractal_side = 0;      ///< 2^k + 1, the diamond-square grid
  std::uint64_t triangles = 0;       ///< 2 (s-1)^2
  std::uint64_t vertices = 0;        ///< s^2 plus the rows repeated where bands meet
  std::size_t bands = 0;             ///< bands of rows written (one for s up to 725), one part
  BoundingBox bounds;
};

/// s such that 2 (s-1)^2 is closest to `triangles` (at least 2).
std::size_t terrain_samples_per_side(std::uint64_t triangles);

/// Generates a terrain over [0,1]^2 with heights in [slab_low, slab_high] and appends it to
/// `writer`; the caller commits. Each grid cell is split into two triangles along the same
/// diagonal, every normal pointing up (+z). The surface is one part, "terrain", written in
/// bands of at most 2^20 triangles (MeshWriter::extend_part; a band repeats the last row of
/// vertices of the band below, so bands meet along identical edges without sharing vertex
/// indices), so memory stays at the fractal grid plus one band (~24 MB). Deterministic.
/// @throw InputError for options out of range (names the option and the value).
/// @throw IoError if the writer fails.
TerrainSummary generate_terrain(const TerrainOptions& options, MeshWriter& writer,
                                Progress& progress = Progress::silent());

}  // namespace tetrapage
