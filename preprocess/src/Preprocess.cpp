#include "tetrapage/preprocess/Preprocess.h"

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <nlohmann/json.hpp>
#include <sstream>
#include <type_traits>

#include "Binning.h"
#include "Buckets.h"
#include "CoarseMeshStage.h"
#include "Ingest.h"
#include "Interiors.h"
#include "MortonGrid.h"
#include "Shards.h"
#include "WriteIndex.h"
#include "tetrapage/formats/base/ByteSize.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/MemoryUsage.h"
#include "tetrapage/formats/base/TemporaryFiles.h"
#include "tetrapage/formats/index/IndexHeader.h"
#include "tetrapage/formats/index/IndexWriter.h"
#include "tetrapage/formats/mesh/FileChecks.h"
#include "tetrapage/formats/mesh/MeshReader.h"

namespace tetrapage {
namespace {

using Clock = std::chrono::steady_clock;

// Runs one stage, recording its time and peak resident memory.
class StageClock {
 public:
  StageClock(PreprocessSummary& summary, std::string name)
      : summary_(summary), name_(std::move(name)) {
    // The peak so far is kept before the reset: the whole run's peak spans the stages.
    summary_.peak_resident_bytes = std::max(summary_.peak_resident_bytes, peak_resident_bytes());
    reset_peak_resident();
    start_ = Clock::now();
  }
  void stop() {
    const double seconds = std::chrono::duration<double>(Clock::now() - start_).count();
    summary_.stages.push_back({name_, seconds, peak_resident_bytes()});
  }

 private:
  PreprocessSummary& summary_;
  std::string name_;
  Clock::time_point start_;
};

// Runs one stage under a StageClock and returns what it returns (a stage that throws
// records nothing).
template <class Stage>
auto run_stage(PreprocessSummary& summary, std::string name, Stage&& stage) {
  StageClock clock(summary, std::move(name));
  if constexpr (std::is_void_v<std::invoke_result_t<Stage&>>) {
    stage();
    clock.stop();
  } else {
    auto result = stage();
    clock.stop();
    return result;
  }
}

// The header's source: a line per input (source_line).
std::string index_source(const std::vector<std::filesystem::path>& inputs,
                         const std::filesystem::path& output) {
  std::string source;
  for (const auto& input : inputs) {
    if (!source.empty()) source += '\n';
    source += source_line(input, output);
  }
  return source;
}

}  // namespace

std::string source_line(const std::filesystem::path& input, const std::filesystem::path& index) {
  std::error_code error;
  const std::filesystem::path absolute = std::filesystem::absolute(input, error);
  std::filesystem::path from_index = std::filesystem::relative(
      absolute, std::filesystem::absolute(index, error).parent_path(), error);
  if (error || from_index.empty()) from_index = absolute;
  return from_index.string() + "\t" + absolute.string();
}

ShardChoice parse_shard_choice(const std::string& text) {
  if (text == "auto") return ShardChoice::automatic;
  if (text == "grid") return ShardChoice::grid;
  if (text == "rtree") return ShardChoice::rtree;
  throw InputError("unknown shard kind '" + text + "' (use auto, grid or rtree)");
}

std::size_t auto_region_triangles(std::uint64_t triangles) {
  constexpr std::uint64_t kMinimum = 4096, kLeaves = kAutoRegionSites;
  return std::size_t(std::max(kMinimum, (triangles + kLeaves - 1) / kLeaves));
}

PreprocessSummary preprocess(const std::vector<std::filesystem::path>& inputs,
                             const std::filesystem::path& output,
                             const PreprocessOptions& options) {
  if (inputs.empty()) throw InputError("no input given");
  check_outputs(std::span<const std::filesystem::path>(&output, 1), inputs);
  const std::size_t stale = remove_stale_temporaries(output).size();
  if (options.memory_bytes < kLeastPreprocessMemory)
    throw InputError("--memory " + format_byte_size(options.memory_bytes) +
                     " is below the 16 MiB the pipeline needs to work");
  const auto start = Clock::now();
  const unsigned threads =
      options.threads == 0 ? unsigned(tbb::info::default_concurrency()) : options.threads;
  tbb::global_control thread_limit(tbb::global_control::max_allowed_parallelism, threads);

  PreprocessSummary summary;
  summary.output = output;
  summary.memory_budget_bytes = options.memory_bytes;
  summary.stale_temporaries_removed = stale;
  // The readers' libraries (the CAD module) are the process's own, as the others are.
  load_readers_for(inputs);
  summary.resident_at_start_bytes = resident_bytes();
  reset_peak_resident();  // the run's peak, not the caller's before it
  summary.precision = std::string(to_string(options.precision));
  summary.compression = std::string(to_string(options.compression));
  const std::filesystem::path spill_folder = !options.spill_folder.empty()
                                                 ? options.spill_folder
                                                 : std::filesystem::absolute(output).parent_path();

  // The writer's temporary file is removed if anything below throws.
  IndexWriter writer(output, {.compression = options.compression});

  // The stages of docs/ARCHITECTURE.md, in order.
  const DiskRoom room = measure_disk_room(spill_folder, output, options);
  IngestedModel model = run_stage(
      summary, "ingest", [&] { return ingest(inputs, options, spill_folder, room, summary); });
  const ModelCoarseMesh coarse = run_stage(
      summary, "coarse mesh", [&] { return build_model_coarse_mesh(model, options, summary); });
  const TetMesh& mesh = coarse.mesh;
  const MortonGrid mesh_grid(coarse.covered);
  const Interiors interiors = run_stage(
      summary, "interiors", [&] { return classify_interiors(model, mesh, options, summary); });
  const TetOrder tets = order_tets(mesh, mesh_grid);
  const BucketPlan plan = run_stage(summary, "buckets", [&] {
    return plan_buckets(model, mesh, mesh_grid, tets.order, options);
  });
  summary.buckets = plan.bucket_count;
  std::vector<Vec3>().swap(model.sample);

  // While the ingested soups are in memory (within a quarter of the budget, at about 30 bytes a
  // triangle), the copies are (id, tet) pairs in memory too, 12 bytes a copy: about half of
  // what the soups take at the usual 1.2-1.4 copies a triangle.
  std::vector<CopyBucket> buckets = make_buckets(plan.bucket_count, spill_folder, model.soups);
  summary.spilled = model.soups.spilled();
  run_stage(summary, "binning",
            [&] { bin_triangles(model, mesh, plan.bucket_of, buckets, options, summary); });
  const ShardTables shards = run_stage(summary, "shards", [&] {
    return build_shards(buckets, tets.rank, mesh.tet_count(), model, writer, options, summary);
  });
  run_stage(summary, "write index", [&] {
    write_index(writer, mesh, shards, model, interiors, index_source(inputs, output), start,
                summary);
  });

  summary.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  summary.peak_resident_bytes = std::max(summary.peak_resident_bytes, peak_resident_bytes());
  for (const auto& stage : summary.stages)
    summary.peak_resident_bytes = std::max(summary.peak_resident_bytes, stage.peak_resident_bytes);
  return summary;
}

std::string PreprocessSummary::to_json() const {
  nlohmann::ordered_json j;
  j["output"] = output.string();
  j["files_read"] = files_read;
  if (files_read_in_chunks > 0) j["files_read_in_chunks"] = files_read_in_chunks;
  j["parts"] = parts;
  j["length_unit"] = length_unit;
  // Keys about a feature the run did not use are left out, not written as zeros: tessellation
  // (STEP or IGES input), rounding (float storage), shards in floats (not under double), and
  // the interiors' figures (stored).
  if (tessellation_deflection > 0 || !skipped_parts.empty()) {
    j["tessellation_deflection"] = tessellation_deflection;
    j["skipped_parts"] = skipped_parts;
  }
  j["triangles_read"] = triangles_read;
  j["degenerate_dropped"] = degenerate_dropped;
  j["region_triangles"] = region_triangles;
  j["sites"] = sites;
  j["regions"] = regions;
  j["empty_regions"] = empty_regions;
  j["grid_shards"] = grid_shards;
  j["rtree_shards"] = rtree_shards;
  j["stored_triangles"] = stored_triangles;
  j["duplication_factor"] = duplication_factor;
  j["exact_tet_tests"] = exact_tet_tests;
  j["shard_payload_bytes"] = shard_payload_bytes;
  j["bytes_written"] = bytes_written;
  j["bytes_per_triangle"] = triangles_read ? double(bytes_written) / double(triangles_read) : 0.0;
  j["precision"] = precision;
  j["compression"] = compression;
  if (precision == "float") j["max_rounding_distance"] = max_rounding_distance;
  if (precision != "double") j["float_shards"] = float_shards;
  j["query_extent"] = query_extent;
  j["memory_budget_bytes"] = memory_budget_bytes;
  j["components"] = components;
  j["closed_components"] = closed_components;
  j["interiors"] = interiors;
  if (interiors.starts_with("stored")) {
    j["interior_tets"] = interior_tets;
    j["interior_undecided"] = interior_undecided;
  }
  j["buckets"] = buckets;
  j["spilled"] = spilled;
  j["stale_temporaries_removed"] = stale_temporaries_removed;
  j["seconds"] = seconds;
  j["triangles_per_second"] = seconds > 0 ? double(triangles_read) / seconds : 0.0;
  j["peak_rss_bytes"] = peak_resident_bytes;
  j["resident_at_start_bytes"] = resident_at_start_bytes;
  j["budget_exceeded_bytes"] =
      peak_resident_bytes > memory_budget_bytes ? peak_resident_bytes - memory_budget_bytes : 0;
  j["input_allowance_bytes"] = kPreprocessInputAllowance;
  j["promised_peak_bytes"] = promised_peak_bytes();
  j["promise_exceeded_bytes"] =
      peak_resident_bytes > promised_peak_bytes() ? peak_resident_bytes - promised_peak_bytes() : 0;
  auto& stage_list = j["stages"] = nlohmann::ordered_json::array();
  for (const auto& stage : stages)
    stage_list.push_back({{"name", stage.name},
                          {"seconds", stage.seconds},
                          {"peak_rss_bytes", stage.peak_resident_bytes}});
  return j.dump(2);
}

std::string PreprocessSummary::to_text() const {
  std::ostringstream text;
  char line[256];
  std::snprintf(line, sizeof line,
                "triangles read %llu (degenerate dropped %llu) from %llu files, %llu parts\n",
                (unsigned long long)triangles_read, (unsigned long long)degenerate_dropped,
                (unsigned long long)files_read, (unsigned long long)parts);
  text << line;
  if (files_read_in_chunks > 0)
    text << files_read_in_chunks << (files_read_in_chunks == 1 ? " file" : " files")
         << " read in chunks (too large to read whole within --memory)\n";
  if (!length_unit.empty()) text << "model unit " << length_unit << "\n";
  if (tessellation_deflection > 0)
    text << "STEP/IGES tessellated within a deflection of " << tessellation_deflection << " "
         << (length_unit.empty() ? "model units" : length_unit) << "\n";
  for (const std::string& skipped : skipped_parts) text << "skipped part " << skipped << "\n";
  std::snprintf(
      line, sizeof line,
      "regions %llu (empty %llu; %llu triangles per region asked), shards: grid %llu, rtree %llu; "
      "duplication factor %.3f\n",
      (unsigned long long)regions, (unsigned long long)empty_regions,
      (unsigned long long)region_triangles, (unsigned long long)grid_shards,
      (unsigned long long)rtree_shards, duplication_factor);
  text << line;
  std::snprintf(line, sizeof line, "index %s: %s (%.1f B/triangle, chunks %s), shards decoded %s\n",
                output.string().c_str(), format_byte_size(bytes_written).c_str(),
                triangles_read ? double(bytes_written) / double(triangles_read) : 0.0,
                compression.c_str(), format_byte_size(shard_payload_bytes).c_str());
  text << line << storage_statement(precision, max_rounding_distance) << "; " << float_shards
       << " of " << (grid_shards + rtree_shards) << " shards in 4-byte floats\n";
  std::snprintf(
      line, sizeof line,
      "components %llu (closed %llu, open %llu); interiors %s (%llu tets inside, %llu undecided)\n",
      (unsigned long long)components, (unsigned long long)closed_components,
      (unsigned long long)(components - closed_components), interiors.c_str(),
      (unsigned long long)interior_tets, (unsigned long long)interior_undecided);
  text << line;
  if (stale_temporaries_removed > 0)
    text << "removed " << stale_temporaries_removed
         << " temporary index file(s) left beside the output by killed runs\n";
  for (const auto& stage : stages) {
    std::snprintf(line, sizeof line, "  %-12s %8.2f s  peak RSS %s\n", stage.name.c_str(),
                  stage.seconds, format_byte_size(stage.peak_resident_bytes).c_str());
    text << line;
  }
  std::snprintf(line, sizeof line,
                "total %.2f s (%.2f M triangles/s), peak RSS %s against --memory %s%s\n", seconds,
                seconds > 0 ? double(triangles_read) / seconds / 1e6 : 0.0,
                format_byte_size(peak_resident_bytes).c_str(),
                format_byte_size(memory_budget_bytes).c_str(), spilled ? " (spilled to disk)" : "");
  text << line;
  // --memory bounds the stages' data; the process itself and the files being read come on top.
  const bool kept = peak_resident_bytes <= promised_peak_bytes();
  if (peak_resident_bytes > memory_budget_bytes)
    text << "budget exceeded by " << format_byte_size(peak_resident_bytes - memory_budget_bytes)
         << ": ";
  std::snprintf(line, sizeof line,
                "the process held %s before any work (libraries, threads); --memory + that + %s "
                "for the files being read = %s: %s",
                format_byte_size(resident_at_start_bytes).c_str(),
                format_byte_size(kPreprocessInputAllowance).c_str(),
                format_byte_size(promised_peak_bytes()).c_str(), kept ? "kept" : "exceeded by ");
  text << line;
  if (!kept)
    text << format_byte_size(peak_resident_bytes - promised_peak_bytes())
         << " (a file whose own soup is larger is held whole while it is read)";
  text << "\n";
  return text.str();
}

}  // namespace tetrapage
