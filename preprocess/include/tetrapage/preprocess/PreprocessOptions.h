#pragma once
/// @file PreprocessOptions.h
/// What the preprocess pipeline (Preprocess.h) is asked: its options, the shard choice, the
/// automatic region size and the memory it works in. Below the stages: each stage reads them.

#include <cstdint>
#include <filesystem>
#include <string>

#include "tetrapage/formats/base/ByteSize.h"
#include "tetrapage/formats/base/Progress.h"
#include "tetrapage/formats/index/IndexWriter.h"
#include "tetrapage/formats/mesh/CadReader.h"
#include "tetrapage/runtime/paging/ShardKind.h"

namespace tetrapage {

enum class ShardChoice : std::uint8_t { automatic, grid, rtree };

/// @throw InputError for anything but "auto", "grid", "rtree".
ShardChoice parse_shard_choice(const std::string& text);

/// The automatic region size: 4096 triangles (measured best on the 1M scene; at 100M it meets
/// the index's 30 B and the resident shards' 40 B per triangle, which 2048 did not), or more
/// for models beyond 49M triangles, so that the coarse mesh stays near 100k tets: its tables are
/// read whole at open, and open to first answer must stay in milliseconds whatever the model
/// (docs/BENCHMARKS.md, "Region size").
std::size_t auto_region_triangles(std::uint64_t triangles);
/// The sites the automatic region size aims at, at most, for a large model: about 100k tets.
inline constexpr std::size_t kAutoRegionSites = 12'000;

/// The least working memory the pipeline works in (PreprocessOptions::memory_bytes).
inline constexpr std::uint64_t kLeastPreprocessMemory = std::uint64_t(16) << 20;

/// What the preprocess's peak resident memory may exceed --memory and the process's own
/// resident memory before any work by: the files being read (a file is held once, its placed
/// copies in batches within the budget) and the allocator's slack. Measured: a 1M-triangle PLY
/// at --memory 16M peaked 60 MiB above the two (docs/USAGE.md, "Memory").
inline constexpr std::uint64_t kPreprocessInputAllowance = std::uint64_t(64) << 20;

struct PreprocessOptions {
  /// Target triangles per region (the leaf size of the adaptive split of centroids); 0: auto,
  /// auto_region_triangles(triangles read).
  std::size_t region_triangles = 0;
  /// Working-memory budget in bytes (the ingest's largest part file comes on top;
  /// kDefaultMemoryBudget, ByteSize.h).
  std::uint64_t memory_bytes = kDefaultMemoryBudget;
  /// Worker threads; 0: all cores.
  unsigned threads = 0;
  ShardChoice shard = ShardChoice::automatic;
  /// exact: every shard decodes to the input's coordinates (float32 where lossless, else
  /// float64); float: rounded compact floats (answers exact for the rounded model); double.
  StoredPrecision precision = StoredPrecision::exact;
  /// How shard chunks are stored: LZ4 (the smaller file) or as they are (the faster page-in).
  ChunkCompression compression = ChunkCompression::lz4;
  /// The side of the query boxes the cost model plans for; 0: 5 % of the model's largest side
  /// (the study's flying objects fit a cube of 0.05 in a unit-cube scene).
  double query_extent = 0;
  /// Progress bars (or lines) on stderr.
  bool progress = false;
  /// Told of each stage's progress (Progress.h), whether or not `progress` draws it: from the
  /// preprocess's threads, at most 10 times a second per stage. What it throws stops the run,
  /// which then leaves nothing at the output.
  ProgressCallback on_progress;
  /// The length unit of inputs that state none (plain meshes): "m", "mm", "in", ...; STEP and
  /// IGES files are read in millimetres, and a manifest states its units.
  std::string length_unit;
  /// How STEP and IGES inputs are tessellated.
  TessellationOptions tessellation;
  /// Where spill files go; empty: next to the output.
  std::filesystem::path spill_folder;
  /// The free bytes assumed of the spill's and the output's folders; 0: what the filesystem says.
  /// Tests set it to see a model too big for the disk refused (a full disk cannot be made there).
  std::uint64_t assumed_free_disk_bytes = 0;
  /// Spill the ingested triangles and the binned copies to disk, and read in chunks every file
  /// that can be, its vertex table on disk, whatever the budget (tests compare such a run with
  /// one that holds them in memory).
  bool force_spill = false;
  /// Store the interiors: each tet's reference point classified, exactly, against every
  /// closed component (RayParity.h); false: not stored, and the runtime then reports only touching
  /// surfaces.
  bool interiors = false;
  /// A tet whose reference points all lie on a closed surface (or that has no point strictly
  /// inside) is stored as undecided, where the runtime's containment answer is unknown, instead
  /// of failing the preprocess with an InputError naming it.
  bool accept_undecided = false;
  /// (point, component) pairs classified per pass over the triangles; 0: as many as a quarter of
  /// memory_bytes holds. Tests set it small to exercise several passes.
  std::uint64_t interior_pairs_per_pass = 0;
};

}  // namespace tetrapage
