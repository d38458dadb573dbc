#pragma once
/// @file Ingest.h
/// Stage 1 of the preprocess (docs/ARCHITECTURE.md): the input files read into soups, a
/// sample of centroids, and the surfaces' connected components.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "TriangleRecord.h"
#include "tetrapage/formats/SurfaceComponents.h"
#include "tetrapage/formats/TriangleSoup.h"
#include "tetrapage/preprocess/Preprocess.h"
#include "tetrapage/preprocess/SoupSpill.h"

namespace tetrapage {

// Ingest: every part file read once, instances placed, soups kept compactly (SoupSpill); a
// reservoir sample of centroids (Algorithm R, fixed seed) bounded by the memory budget.
struct IngestedModel {
  SoupSpill<TriangleRecord> soups;
  std::vector<Vec3> sample;
  std::uint64_t triangle_count = 0;
  BoundingBox bounds;
  std::vector<std::string> part_names;
  std::vector<std::string> part_paths;           // one per part (the name when a file has none)
  std::vector<std::uint64_t> part_triangles;     // triangles kept, per part
  std::string length_unit;                       // the model's unit, "" when no input says
  std::string length_unit_source;                // the input that said it
  double tessellation_deflection = 0;            // the largest of the CAD inputs', model units
  // The surfaces' connected components, model-wide (the ids the records and shards carry).
  std::vector<SurfaceComponent> components;
};

/// Reads every input once, in input order (ids, part numbers and the sample do not depend on
/// the threads), spilling the soups beyond a quarter of the budget (`spill_folder`).
/// @throw InputError when the inputs hold no triangle, more than 2^32 - 2 components, or a
/// coordinate beyond kMaxCoordinateMagnitude; the readers' errors as they throw them.
IngestedModel ingest(const std::vector<std::filesystem::path>& inputs,
                     const PreprocessOptions& options, const std::filesystem::path& spill_folder,
                     PreprocessSummary& summary);

}  // namespace tetrapage
