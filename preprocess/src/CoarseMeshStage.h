#pragma once
/// @file CoarseMeshStage.h (private)
/// Stage 2 of the preprocess (docs/ARCHITECTURE.md): sites sampled from the ingested
/// centroids and their Delaunay mesh. The sampling and the mesh of given sites are public:
/// tetrapage/preprocess/CoarseMesh.h.

#include "Ingest.h"
#include "tetrapage/formats/index/TetMesh.h"
#include "tetrapage/preprocess/PreprocessOptions.h"
#include "tetrapage/preprocess/PreprocessSummary.h"

namespace tetrapage {

/// The coarse mesh of the model, and the box it covers (the model's, enlarged): Morton codes
/// of tets and sample points are taken in that box.
struct ModelCoarseMesh {
  TetMesh mesh;
  BoundingBox covered;
};

/// Reorders model.sample (the buckets' estimate takes any every-stride-th of it).
/// @throw InputError if the sites span no volume.
ModelCoarseMesh build_model_coarse_mesh(IngestedModel& model, const PreprocessOptions& options,
                                        PreprocessSummary& summary);

}  // namespace tetrapage
