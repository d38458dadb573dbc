#pragma once
/// @file PreprocessSummary.h
/// What a preprocess run reports (the --report file and the lines on stdout), filled in by
/// its stages.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "tetrapage/preprocess/PreprocessOptions.h"

namespace tetrapage {

/// Time and peak resident memory of one stage.
struct StageFigures {
  std::string name;
  double seconds = 0;
  std::uint64_t peak_resident_bytes = 0;
};

struct PreprocessSummary {
  std::filesystem::path output;
  std::uint64_t files_read = 0;
  /// Files too large to read whole within the budget, read a chunk at a time.
  std::uint64_t files_read_in_chunks = 0;
  std::uint64_t parts = 0;
  std::string length_unit;                 ///< the model's, "" when no input said
  double tessellation_deflection = 0;      ///< of STEP/IGES inputs, in the model's unit
  std::vector<std::string> skipped_parts;  ///< STEP/IGES shapes left out (--skip-bad-parts)
  std::uint64_t triangles_read = 0;        ///< kept triangles, as read and placed
  std::uint64_t degenerate_dropped = 0;    ///< by the readers and the placement
  std::uint64_t region_triangles = 0;      ///< the target used (the option, or the automatic one)
  std::uint64_t sites = 0;
  std::uint64_t regions = 0;        ///< tets of the coarse mesh
  std::uint64_t empty_regions = 0;  ///< tets without triangles (no shard)
  std::uint64_t grid_shards = 0;
  std::uint64_t rtree_shards = 0;
  std::uint64_t stored_triangles = 0;  ///< triangle references over all shards
  double duplication_factor = 0;       ///< stored_triangles / triangles_read
  std::uint64_t exact_tet_tests = 0;
  std::uint64_t shard_payload_bytes = 0;  ///< decoded, the bytes a resident cache holds
  std::uint64_t bytes_written = 0;        ///< the index file
  double max_rounding_distance = 0;
  std::string precision;           ///< "exact", "double" or "float"
  std::uint64_t float_shards = 0;  ///< shards stored in 4-byte floats (lossless under "exact")
  std::string compression;         ///< of the shard chunks: "lz4" or "none"
  double query_extent = 0;
  std::uint64_t memory_budget_bytes = 0;
  /// Connected components of the parts' surfaces (SurfaceComponents.h), and those closed:
  /// every edge used an even number of times.
  std::uint64_t components = 0;
  std::uint64_t closed_components = 0;
  /// "stored", "off" (no classifier), "none closed", or "skipped: <why>".
  std::string interiors = "off";
  std::uint64_t interior_tets = 0;  ///< tets whose reference point is inside a closed component
  std::uint64_t interior_undecided = 0;  ///< tets whose reference point could not be classified
  std::uint64_t buckets = 0;             ///< tet buckets processed one at a time
  bool spilled = false;                  ///< whether the stages used spill files
  /// OUTPUT.tmp-PID files of processes that no longer exist (killed runs), removed at the start.
  std::uint64_t stale_temporaries_removed = 0;
  std::uint64_t peak_resident_bytes = 0;  ///< the whole run (VmHWM, kept across stages)
  /// The process's resident bytes when the run started (libraries, the caller's data): the
  /// budget bounds what the stages hold on top of this and of the input file being read.
  std::uint64_t resident_at_start_bytes = 0;
  double seconds = 0;
  std::vector<StageFigures> stages;

  /// The peak the run promises: --memory + resident_at_start_bytes + kPreprocessInputAllowance.
  std::uint64_t promised_peak_bytes() const {
    return memory_budget_bytes + resident_at_start_bytes + kPreprocessInputAllowance;
  }

  /// The summary as JSON text (the --report file).
  std::string to_json() const;
  /// A few human lines (stdout).
  std::string to_text() const;
};

}  // namespace tetrapage
