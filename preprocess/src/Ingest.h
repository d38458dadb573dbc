#pragma once
/// @file Ingest.h
/// Stage 1 of the preprocess (docs/ARCHITECTURE.md): the input files read into soups, a
/// sample of centroids, and the surfaces' connected components.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "TriangleRecord.h"
#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/formats/mesh/SurfaceComponents.h"
#include "tetrapage/preprocess/PreprocessOptions.h"
#include "tetrapage/preprocess/PreprocessSummary.h"
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
  std::vector<std::string> part_paths;        // one per part (the name when a file has none)
  std::vector<std::uint64_t> part_triangles;  // triangles kept, per part
  std::string length_unit;                    // the model's unit, "" when no input says
  std::string length_unit_source;             // the input that said it
  double tessellation_deflection = 0;         // the largest of the CAD inputs', model units
  // The surfaces' connected components, model-wide (the ids the records and shards carry).
  std::vector<SurfaceComponent> components;
};

/// The free disk where the spill and the index go (unknown: the largest figure), to refuse up
/// front a model they cannot hold.
struct DiskRoom {
  std::filesystem::path spill_folder, output_folder;
  std::uint64_t spill_free = ~std::uint64_t(0), output_free = ~std::uint64_t(0);
  bool same_device = true;  // one free figure for both
};

/// The free space of `spill_folder` and of `output`'s folder, or
/// PreprocessOptions::assumed_free_disk_bytes for both when given.
DiskRoom measure_disk_room(const std::filesystem::path& spill_folder,
                           const std::filesystem::path& output, const PreprocessOptions& options);

/// Reads every input once, in input order (ids, part numbers and the sample do not depend on
/// the threads), spilling the soups beyond a quarter of the budget (`spill_folder`). A file
/// placed many times is read once and its copies appended in batches within the budget.
/// @throw InputError when the inputs hold no triangle, more than 2^32 - 2 components, or a
/// coordinate beyond kMaxCoordinateMagnitude; when the parts' and components' tables would
/// exceed the budget (checked up front from the manifests' placements, then as the
/// files are read); when the placed triangles' spill and index would exceed `room` (checked
/// as each file is read, before its copies are placed); the readers' errors as they throw them.
IngestedModel ingest(const std::vector<std::filesystem::path>& inputs,
                     const PreprocessOptions& options, const std::filesystem::path& spill_folder,
                     const DiskRoom& room, PreprocessSummary& summary);

}  // namespace tetrapage
