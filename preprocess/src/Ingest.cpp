#include "Ingest.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <random>

#include "Interiors.h"
#include "OrderedPipeline.h"
#include "SpillPath.h"
#include "tetrapage/formats/Error.h"
#include "tetrapage/formats/Manifest.h"
#include "tetrapage/formats/MeshReader.h"
#include "tetrapage/formats/Pose.h"
#include "tetrapage/formats/Progress.h"

namespace tetrapage {
namespace {

// One input soup (a manifest's part, or a mesh file) with what can be computed off the
// ingest's serial path: centroids, and its surfaces' connected components (its part_of then
// holds each triangle's component, numbered within the soup).
struct LoadedSoup {
  std::uint64_t degenerate_dropped = 0;
  std::uint64_t files_read = 0;
  std::string length_unit;  // of its coordinates: the manifest's, or what the reader said
  std::string file;         // what the unit came from, for messages
  std::vector<std::string> skipped_parts;
  double tessellation_deflection = 0;
  TriangleSoup soup;
  std::vector<std::uint64_t> part_triangles;
  std::vector<Vec3> centroids;  // per triangle
  std::vector<SurfaceComponent> components;
};

// Coordinates beyond kMaxCoordinateMagnitude overflow the distances to the model and the
// exact predicates' products: refused, naming the file and the value.
void check_coordinate_magnitudes(const TriangleSoup& soup, const InputPiece& piece) {
  const CoordinateBeyondLimit beyond = find_coordinate_beyond_limit(soup);
  if (!beyond.found) return;
  char value[64], limit[64];
  std::snprintf(value, sizeof value, "%g", beyond.value);
  std::snprintf(limit, sizeof limit, "%g", kMaxCoordinateMagnitude);
  throw InputError(piece.file().string() + ": a vertex coordinate of " + value + " is beyond " +
                   limit + " in magnitude: distances would overflow; scale the model");
}

LoadedSoup load_soup(const InputPiece& piece, const TessellationOptions& tessellation) {
  LoadedSoup loaded;
  std::vector<ReadReport> reports;
  loaded.soup = load_input_piece(piece, &reports, tessellation);
  for (const auto& report : reports) {
    loaded.degenerate_dropped += report.degenerate_dropped;
    ++loaded.files_read;
    loaded.tessellation_deflection =
        std::max(loaded.tessellation_deflection, report.tessellation_deflection);
    for (const std::string& skipped : report.skipped_parts)
      loaded.skipped_parts.push_back(report.path + ": " + skipped);
  }
  loaded.file = piece.input.string();
  if (piece.manifest) {
    loaded.length_unit = piece.manifest->units;
  } else if (!reports.empty()) {
    loaded.length_unit = reports.front().length_unit;
  }
  TriangleSoup& soup = loaded.soup;
  loaded.part_triangles.assign(std::max<std::size_t>(soup.part_count(), 1), 0);
  for (const std::uint32_t part : soup.part_of) ++loaded.part_triangles[part];
  check_coordinate_magnitudes(soup, piece);
  SurfaceComponents found = find_surface_components(soup);
  soup.part_of = std::move(found.component_of);
  loaded.components = std::move(found.components);
  loaded.centroids.resize(soup.triangle_count());
  for (std::size_t t = 0; t < soup.triangle_count(); ++t)
    loaded.centroids[t] = centroid(soup.corners(t));
  return loaded;
}

// How many soups the ingest's pipeline may hold at once. One more than the threads left both
// threads idle whenever the in-order append waited for a slow file; four times the threads
// took the 10M ingest from 0.91 to 0.72 s. Bounded so that the soups in flight, taken at 4
// times their files' bytes, stay within an eighth of the budget. (A loaded soup holds double
// vertices, indices and a double centroid a triangle: by arithmetic about 2.6 times a binary
// PLY of float vertices, less for double ones; not measured for every reader.)
std::size_t ingest_depth(const std::vector<InputPiece>& jobs, std::uint64_t memory_bytes,
                         std::size_t threads) {
  std::uint64_t largest = 0;
  for (const InputPiece& job : jobs) {
    std::error_code error;
    const std::uint64_t bytes = std::filesystem::file_size(job.file(), error);
    if (!error) largest = std::max<std::uint64_t>(largest, bytes * job.copies());
  }
  const std::size_t fewest = threads + 1, most = 4 * threads;
  if (largest == 0) return fewest;
  return std::clamp<std::size_t>(std::size_t(memory_bytes / 8 / (4 * largest)), fewest,
                                 std::max(fewest, most));
}

// The model's unit is the one its inputs state; inputs that state different units cannot be
// one model without a manifest to convert them.
void note_length_unit(IngestedModel& model, const LoadedSoup& loaded) {
  if (loaded.length_unit.empty()) return;
  if (model.length_unit.empty()) {
    model.length_unit = loaded.length_unit;
    model.length_unit_source = loaded.file;
  } else if (model.length_unit != loaded.length_unit) {
    throw InputError(loaded.file + " is in " + loaded.length_unit + " but " +
                     model.length_unit_source + " in " + model.length_unit +
                     ": place both in one manifest, which converts each file to its units");
  }
}

// --unit names the unit of inputs that state none; it may not contradict one that does.
void settle_length_unit(IngestedModel& model, const std::string& option) {
  if (option.empty()) return;
  metres_per_unit(option);  // an unknown unit is an InputError naming it
  if (model.length_unit.empty()) {
    model.length_unit = option;
  } else if (model.length_unit != option) {
    throw InputError("--unit " + option + ", but " + model.length_unit_source + " is in " +
                     model.length_unit);
  }
}

// Appends a loaded soup's parts, components and triangles to the model; the soups are
// spilled once they hold more than a quarter of the budget.
void append_soup(IngestedModel& model, LoadedSoup& loaded, const PreprocessOptions& options,
                 const std::filesystem::path& spill_folder, PreprocessSummary& summary) {
  summary.degenerate_dropped += loaded.degenerate_dropped;
  summary.skipped_parts.insert(summary.skipped_parts.end(), loaded.skipped_parts.begin(),
                               loaded.skipped_parts.end());
  summary.files_read += loaded.files_read;
  const auto part_offset = std::uint32_t(model.part_names.size());
  for (std::size_t p = 0; p < loaded.soup.part_count(); ++p) {
    model.part_names.push_back(loaded.soup.part_names[p]);
    model.part_paths.push_back(loaded.soup.part_path(p));
  }
  if (loaded.soup.part_names.empty()) {
    model.part_names.push_back("part" + std::to_string(part_offset));
    model.part_paths.push_back(model.part_names.back());
  }
  model.part_triangles.insert(model.part_triangles.end(), loaded.part_triangles.begin(),
                              loaded.part_triangles.end());
  model.tessellation_deflection =
      std::max(model.tessellation_deflection, loaded.tessellation_deflection);
  note_length_unit(model, loaded);
  if (model.components.size() + loaded.components.size() >= kInteriorUndecided)
    throw InputError("the inputs hold more than 2^32 - 2 connected components");
  const auto component_offset = std::uint32_t(model.components.size());
  for (SurfaceComponent& c : loaded.components) {
    c.part += part_offset;
    model.bounds.extend(c.bounds);
    model.components.push_back(c);
  }
  model.soups.append(loaded.soup, component_offset);
  const std::uint64_t held_limit = options.memory_bytes / 4;
  if (!model.soups.spilled() && (model.soups.held_bytes() > held_limit || options.force_spill))
    model.soups.spill_to(spill_path(spill_folder, "triangles"));
}

// Counts a soup's triangles into the model and keeps its centroids in the reservoir sample
// (of at most sample_capacity).
void sample_centroids(IngestedModel& model, const std::vector<Vec3>& centroids,
                      std::size_t sample_capacity, std::mt19937_64& random) {
  for (std::size_t t = 0; t < centroids.size(); ++t, ++model.triangle_count) {
    if (model.sample.size() < sample_capacity) {
      model.sample.push_back(centroids[t]);
    } else {
      const std::uint64_t slot =
          std::uniform_int_distribution<std::uint64_t>(0, model.triangle_count)(random);
      if (slot < sample_capacity) model.sample[slot] = centroids[t];
    }
  }
}

}  // namespace

IngestedModel ingest(const std::vector<std::filesystem::path>& inputs,
                     const PreprocessOptions& options, const std::filesystem::path& spill_folder,
                     PreprocessSummary& summary) {
  IngestedModel model;
  // At most 2M centroids, at least 2^16: a site stands for the mean of hundreds of sampled
  // centroids at the default region size. A cap of 4M gave the 10M scene the same regions
  // (26,081 against 26,071), duplication (1.2623 against 1.2630) and flights in memory (six
  // objects, four runs each, within their noise) at twice the coarse mesh's time; 1M began to
  // show in the flights (the tetrahedron's 7 % slower; docs/BENCHMARKS.md).
  const std::size_t sample_capacity = std::size_t(
      std::clamp<std::uint64_t>(options.memory_bytes / (8 * sizeof(Vec3)), 1 << 16, 1 << 21));
  model.sample.reserve(std::min<std::size_t>(sample_capacity, 1 << 16));
  std::mt19937_64 random(0x7e7a9a9e);

  // One part file at a time per thread: the ingest never holds the assembly.
  const std::vector<InputPiece> jobs = input_pieces(inputs);
  // Parsing, edge parity, bounds and centroids run on all threads, a few soups at once; the
  // soups are appended in input order on one.
  Progress progress("reading parts", jobs.size(), options.progress, options.on_progress);
  const std::size_t in_flight = ingest_depth(jobs, options.memory_bytes,
                                             std::size_t(tbb::this_task_arena::max_concurrency()));
  produce_in_parallel_consume_in_order(
      jobs.size(), in_flight,
      [&](std::size_t j) {
        return std::make_shared<LoadedSoup>(load_soup(jobs[j], options.tessellation));
      },
      [&](const std::shared_ptr<LoadedSoup>& loaded) {
        // In input order (ids, part numbers and the sample do not depend on the threads).
        append_soup(model, *loaded, options, spill_folder, summary);
        sample_centroids(model, loaded->centroids, sample_capacity, random);
        progress.advance();
      });
  progress.finish();
  summary.triangles_read = model.triangle_count;
  summary.parts = model.part_names.size();
  settle_length_unit(model, options.length_unit);
  summary.length_unit = model.length_unit;
  summary.tessellation_deflection = model.tessellation_deflection;
  summary.components = model.components.size();
  if (model.triangle_count == 0)
    throw InputError("the inputs hold no triangle (after dropping degenerate ones)");
  return model;
}

}  // namespace tetrapage
