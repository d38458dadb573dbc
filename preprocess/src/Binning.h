#pragma once
/// @file Binning.h (private)
/// Stage 5 of the preprocess (docs/ARCHITECTURE.md): every triangle binned into every tet it
/// meets, its copies appended to their tets' buckets. The exact test of one triangle,
/// bin_triangle, is public: tetrapage/preprocess/TriangleBinning.h.

#include <cstdint>
#include <span>

#include "Buckets.h"
#include "Ingest.h"
#include "tetrapage/formats/index/TetMesh.h"
#include "tetrapage/preprocess/PreprocessOptions.h"
#include "tetrapage/preprocess/PreprocessSummary.h"

namespace tetrapage {

/// Bins the model's triangles into `buckets` (bucket_of: each tet's bucket): (id, tet) pairs
/// while the soups are in memory, records while they are spilled; the spilled soups are then
/// cleared (in memory, the shard stage still gathers its triangles from them).
/// @throw InputError when a triangle's first vertex lies outside the mesh.
void bin_triangles(IngestedModel& model, const TetMesh& mesh,
                   std::span<const std::uint32_t> bucket_of, std::span<CopyBucket> buckets,
                   const PreprocessOptions& options, PreprocessSummary& summary);

}  // namespace tetrapage
