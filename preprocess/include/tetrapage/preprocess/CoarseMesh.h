#pragma once
/// @file CoarseMesh.h
/// Sampling sites where the geometry is, and the coarse Delaunay mesh of those sites.
/// "Model only what a scene requires": dense sites where triangles crowd, none in empty
/// space, so empty space becomes a few big tetrahedra.

#include <span>
#include <vector>

#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/formats/index/TetMesh.h"

namespace tetrapage {

struct SamplingOptions {
  /// A leaf of the adaptive split holds at most this many triangle centroids.
  std::size_t leaf_triangles = 4096;
  /// The mesh covers the model's box enlarged by this fraction of its largest side.
  double margin = 0.05;
};

/// The sites of one leaf of the split: its mean centroid, or, when its centroids are flat
/// (their box's thinnest side under half its largest), two sites either side of the
/// mean along that side, twice the largest side away (clamped to `bounds`), so that the tets
/// straddle the surface rather than lie along it.
void append_leaf_sites(std::span<const Vec3> leaf, const BoundingBox& bounds,
                       std::vector<Vec3>& sites);

/// The sites sample_sites appends after the leaves': the enlarged box's corners.
inline constexpr std::size_t kBoxCornerSites = 8;

/// Sites for the coarse mesh: each leaf's sites (append_leaf_sites) of a median split of the
/// centroids (split along the longest side until a leaf holds at most leaf_triangles), plus
/// the eight corners of the enlarged bounding box. The split reorders `centroids` in place
/// (they are the preprocess's sample, up to 96 MB: a copy was a serial twentieth of a second).
/// @throw InputError if there is no centroid or the bounds are not finite.
std::vector<Vec3> sample_sites(std::span<Vec3> centroids, const BoundingBox& bounds,
                               const SamplingOptions& options);

/// The enlarged box whose corners bound the coarse mesh.
BoundingBox enlarged_bounds(const BoundingBox& bounds, double margin);

/// The Delaunay tetrahedralisation of the sites (CGAL), as a TetMesh of its finite cells.
/// @throw InputError if the sites span no volume.
TetMesh build_coarse_mesh(std::span<const Vec3> sites);

}  // namespace tetrapage
