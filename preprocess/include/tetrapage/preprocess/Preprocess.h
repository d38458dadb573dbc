#pragma once
/// @file Preprocess.h
/// The preprocess pipeline (DESIGN.md): ingest the parts, sample sites where the triangles
/// are, build the coarse Delaunay mesh, bin every triangle into the tets it meets (exactly),
/// build a grid or R-tree shard per non-empty tet, and write one HDF5 index under a temporary
/// name, renamed only when complete.
///
/// Memory: the ingest holds a few part files at a time plus a bounded sample of centroids; the
/// stages after sampling stream over spill files in blocks and process the tets in buckets
/// sized from --memory, so the working memory follows the budget, not the model.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "tetrapage/formats/ByteSize.h"
#include "tetrapage/formats/CadReader.h"
#include "tetrapage/formats/IndexWriter.h"
#include "tetrapage/formats/Progress.h"
#include "tetrapage/runtime/ShardKind.h"

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
  std::uint64_t regions = 0;               ///< tets of the coarse mesh
  std::uint64_t empty_regions = 0;         ///< tets without triangles (no shard)
  std::uint64_t grid_shards = 0;
  std::uint64_t rtree_shards = 0;
  std::uint64_t stored_triangles = 0;      ///< triangle references over all shards
  double duplication_factor = 0;           ///< stored_triangles / triangles_read
  std::uint64_t exact_tet_tests = 0;
  std::uint64_t shard_payload_bytes = 0;   ///< decoded, the bytes a resident cache holds
  std::uint64_t bytes_written = 0;         ///< the index file
  double max_rounding_distance = 0;
  std::string precision;                   ///< "exact", "double" or "float"
  std::uint64_t float_shards = 0;          ///< shards stored in 4-byte floats (lossless under "exact")
  std::string compression;                 ///< of the shard chunks: "lz4" or "none"
  double query_extent = 0;
  std::uint64_t memory_budget_bytes = 0;
  /// Connected components of the parts' surfaces (SurfaceComponents.h), and those closed:
  /// every edge used an even number of times.
  std::uint64_t components = 0;
  std::uint64_t closed_components = 0;
  /// "stored", "off" (no classifier), "none closed", or "skipped: <why>".
  std::string interiors = "off";
  std::uint64_t interior_tets = 0;         ///< tets whose reference point is inside a closed component
  std::uint64_t interior_undecided = 0;    ///< tets whose reference point could not be classified
  std::uint64_t buckets = 0;               ///< tet buckets processed one at a time
  bool spilled = false;                    ///< whether the stages used spill files
  /// OUTPUT.tmp-PID files of processes that no longer exist (killed runs), removed at the start.
  std::uint64_t stale_temporaries_removed = 0;
  std::uint64_t peak_resident_bytes = 0;   ///< the whole run (VmHWM, kept across stages)
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

/// The line of the index's `source` attribute that records `input` of an index written to
/// `index`: its path from the index's folder, a tab, its absolute path (so that the index finds
/// its model when both move together, and from any working directory).
std::string source_line(const std::filesystem::path& input, const std::filesystem::path& index);

/// Runs the pipeline over mesh files and manifests (.json) into `output`.
/// @throw IoError, FormatError, InputError (from the readers, naming the file), InputError for
///        an empty model or bad options; nothing is left at `output` on failure.
PreprocessSummary preprocess(const std::vector<std::filesystem::path>& inputs,
                             const std::filesystem::path& output,
                             const PreprocessOptions& options);

}  // namespace tetrapage
