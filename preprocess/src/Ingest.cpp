#include "Ingest.h"

#include <sys/stat.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <random>

#include "Interiors.h"
#include "OrderedPipeline.h"
#include "SpillPath.h"
#include "tetrapage/formats/base/ByteSize.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/Progress.h"
#include "tetrapage/formats/base/QuotedInput.h"
#include "tetrapage/formats/mesh/Manifest.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/formats/mesh/TessellatedFile.h"
#include "tetrapage/preprocess/ChunkedComponents.h"

namespace tetrapage {
namespace {

// The bytes a part's and a component's entries take in the model's tables, which stay in
// memory to the end (the index's part tables, the interiors' components).
constexpr std::uint64_t kPartEntryBytes = 2 * sizeof(std::string) + sizeof(std::uint64_t);
constexpr std::uint64_t kComponentEntryBytes = sizeof(SurfaceComponent);

// A file too large to read whole within the budget, read in chunks by its producer: the chunks
// in a spill of their own, their triangles labelled with their pieces of components, and the
// components those labels unite into (ChunkedComponents).
struct StreamedFile {
  StreamedFile(const std::filesystem::path& spill_folder, const std::string& name) {
    chunks.spill_to(spill_path(spill_folder, name + "-chunks"));
  }
  SoupSpill<TriangleRecord> chunks;
  ChunkedComponents::United united;
  TriangleSoup parts;  // the file's part names and paths
  std::vector<std::uint64_t> part_triangles;
  std::uint64_t triangles = 0, soup_bytes = 0;
};

// One input piece as its producer left it: its file read, and either placed whole with its
// surfaces' connected components (its part_of then holds each triangle's component, numbered
// within the soup), or, when its copies do not fit a batch, the loader the in-order consumer
// places them from, a batch at a time, or read in chunks (streamed).
struct LoadedSoup {
  std::unique_ptr<PieceLoader> loader;  // placed in batches; null when `soup` holds the piece
  std::unique_ptr<StreamedFile> streamed;  // read in chunks; null unless the file is
  ReadReport report;                    // the file's (placed whole)
  std::string length_unit;  // of its coordinates: the manifest's, or what the reader said
  std::string file;         // what the unit came from, for messages
  TriangleSoup soup;
  std::vector<std::uint64_t> part_triangles;
  std::vector<SurfaceComponent> components;
};

// Coordinates beyond kMaxCoordinateMagnitude overflow the distances to the model and the
// exact predicates' products: refused, naming the file and the value.
[[noreturn]] void refuse_coordinate(double coordinate, const InputPiece& piece) {
  char value[64], limit[64];
  std::snprintf(value, sizeof value, "%g", coordinate);
  std::snprintf(limit, sizeof limit, "%g", kMaxCoordinateMagnitude);
  throw InputError(piece.file().string() + ": a vertex coordinate of " + value + " is beyond " +
                   limit + " in magnitude: distances would overflow; scale the model");
}

void check_coordinate_magnitudes(const TriangleSoup& soup, const InputPiece& piece) {
  const CoordinateBeyondLimit beyond = find_coordinate_beyond_limit(soup);
  if (beyond.found) refuse_coordinate(beyond.value, piece);
}

void check_coordinate_magnitude(const Vec3& vertex, const InputPiece& piece) {
  for (const double coordinate : vertex)
    if (std::fabs(coordinate) > kMaxCoordinateMagnitude) refuse_coordinate(coordinate, piece);
}

// Per triangle: its parts counted, then part_of replaced by its component's number.
void find_components(LoadedSoup& loaded, const InputPiece& piece) {
  TriangleSoup& soup = loaded.soup;
  loaded.part_triangles.assign(std::max<std::size_t>(soup.part_count(), 1), 0);
  for (const std::uint32_t part : soup.part_of) ++loaded.part_triangles[part];
  check_coordinate_magnitudes(soup, piece);
  SurfaceComponents found = find_surface_components(soup);
  soup.part_of = std::move(found.component_of);
  loaded.components = std::move(found.components);
}

// What reading one piece holds at its peak, beyond the budget's shares (docs/USAGE.md, "Memory"):
// the reader's peak; its soup beside the component search's tables; its soup beside the sample
// it fills; a file placed once by a manifest beside its placed copy. Copies placed in batches
// take their batch from the budget; the file is held beside them.
struct PieceEstimate {
  MeshReadEstimate read;
  std::uint64_t bytes = 0;
  bool streamed = false;  // read in chunks (StreamedFile): bytes exceed the room it has
  std::uint64_t held_vertices = ~std::uint64_t(0);  // streamed: of its vertex table, in memory
};
// The reservoir sample holds at most this many centroids (ingest() says why).
constexpr std::uint64_t kMostSampledCentroids = std::uint64_t(1) << 21;
constexpr std::uint64_t kLargestSampleBytes = kMostSampledCentroids * sizeof(Vec3);

std::uint64_t piece_bytes(const MeshReadEstimate& read, std::size_t copies, bool manifest) {
  const std::uint64_t soup = read.soup_bytes();
  if (copies > 1) return std::max(read.reading_bytes, soup);
  const std::uint64_t components = surface_components_bytes(read.vertices, read.triangles);
  const std::uint64_t sample = std::min(sizeof(Vec3) * read.triangles, kLargestSampleBytes);
  // The heap's slack beside the largest: a 1M-triangle binary STL peaked 0.8 MiB above the rest.
  constexpr std::uint64_t kSlack = std::uint64_t(8) << 20;
  return kSlack + std::max({read.reading_bytes, soup + components, soup + sample,
                            manifest ? 2 * soup : 0});
}

// A streamed file's chunks, the buckets its positions are united in, one at a time, and the
// cache its vertex table is read back through once it goes to disk.
constexpr std::size_t kChunkTriangles = std::size_t(1) << 15;
constexpr std::uint64_t kPositionBucketBytes = std::uint64_t(8) << 20;
constexpr std::uint64_t kVertexCacheBytes = std::uint64_t(8) << 20;

// What reading a file in chunks holds: the reader's block (MeshReadEstimate::chunked_bytes); a
// chunk as the reader builds it (16 B a triangle) and hands it over (at most three vertices a
// triangle: 88 B), its component search, its positions before they are sorted out (96 B a
// triangle), or a bucket of positions while it is united (read, then sorted in place); the
// vertex cache; and as much of the vertex table as `room` leaves (the rest goes to disk). The
// labels (a component's piece per chunk, about) are tables, counted with the model's.
struct StreamPlan {
  std::uint64_t bytes = 0;
  std::uint64_t held_vertices = ~std::uint64_t(0);
};
StreamPlan plan_stream(const MeshReadEstimate& read, std::uint64_t room) {
  constexpr std::uint64_t kSlack = std::uint64_t(8) << 20;
  constexpr std::uint64_t n = kChunkTriangles;
  const std::uint64_t chunk = n * (16 + 88 + 2 * 96 + 48) + surface_components_bytes(3 * n, n);
  const std::uint64_t fixed =
      kSlack + read.chunked_bytes + std::max(chunk, 2 * kPositionBucketBytes) + kVertexCacheBytes;
  // A table grown as it is read holds up to twice its vertices' bytes. Capped whatever the
  // estimate: an OBJ's vertices are counted from its size, and may be more.
  const std::uint64_t per_vertex = read.counted ? 24 : 48;
  const std::uint64_t held = room > fixed ? (room - fixed) / per_vertex : 0;
  return {fixed + std::min(read.vertex_table_bytes, held * per_vertex), held};
}

PieceEstimate estimate_piece(const InputPiece& piece) {
  PieceEstimate estimate;
  estimate.read = estimate_mesh_read(piece.file());
  estimate.bytes = piece_bytes(estimate.read, piece.copies(), piece.manifest != nullptr);
  return estimate;
}

// How many pieces the ingest's pipeline may hold at once. One more than the threads left both
// threads idle whenever the in-order append waited for a slow file; four times the threads
// took the 10M ingest from 0.91 to 0.72 s. Bounded so that the pieces in flight, each at the
// largest piece's estimate, stay within an eighth of the budget: down to one piece at a time
// when one file alone exceeds it (then nothing else is read beside it).
std::size_t ingest_depth(std::uint64_t largest, std::uint64_t memory, std::size_t threads) {
  const std::size_t most = 4 * threads;
  if (largest == 0) return threads + 1;
  return std::clamp<std::size_t>(std::size_t(memory / 8 / largest), 1, most);
}

std::uint64_t largest_estimate(const std::vector<PieceEstimate>& estimates) {
  std::uint64_t largest = 0;
  for (const PieceEstimate& estimate : estimates) largest = std::max(largest, estimate.bytes);
  return largest;
}

// What the pieces before one place, by their estimates.
struct PiecesBefore {
  std::uint64_t soups = 0, triangles = 0, parts = 0;
};

// What the ingest may hold beside a piece while it is read, at --memory `memory`: the soups
// before it (held up to a quarter of the budget, then spilled), their sample of centroids,
// their parts' tables, and the pieces in flight with it.
std::uint64_t held_beside(const PiecesBefore& before, std::uint64_t largest, std::uint64_t memory,
                          std::size_t threads) {
  const std::uint64_t sample = std::min({sizeof(Vec3) * before.triangles, memory / 8, kLargestSampleBytes});
  const std::uint64_t in_flight = ingest_depth(largest, memory, threads) > 1 ? memory / 8 : 0;
  return std::min(before.soups, memory / 4) + sample + before.parts * kPartEntryBytes + in_flight;
}

// "1,234,567": counts in messages.
std::string thousands(std::uint64_t value) {
  std::string digits = std::to_string(value), out;
  for (std::size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out.push_back(',');
    out.push_back(digits[i]);
  }
  return out;
}

// Refuses, before it is read, a file whose reading needs more than the budget leaves: the
// budget + the allowance, less what the ingest holds beside it.
[[noreturn]] void refuse_reading(const std::filesystem::path& file, const MeshReadEstimate& read,
                                 std::uint64_t bytes, std::uint64_t beside,
                                 std::uint64_t raise_to, std::uint64_t memory) {
  // The whole path (PATH_MAX): cut, it would lose the file's name.
  std::string message = quoted_input(file.string(), 4096);
  message.append(read.cad ? " makes " : " holds ")
      .append(read.counted ? "" : "about ")
      .append(thousands(read.triangles))
      .append(" triangles");
  if (read.cad) message.append(" once tessellated");
  if (!read.counted && !read.cad) {
    std::error_code error;
    message.append(" by its size (")
        .append(format_byte_size(std::filesystem::file_size(file, error)))
        .append(")");
  }
  message.append(": reading it needs about ")
      .append(format_byte_size(bytes))
      .append(", above --memory ")
      .append(format_byte_size(memory))
      .append(" + ")
      .append(format_byte_size(kPreprocessInputAllowance));
  if (beside > 0) message.append(" less ").append(format_byte_size(beside)).append(" held beside it");
  message.append("; raise --memory to ")
      .append(format_byte_size(raise_to))
      .append(" or more, or split the file");
  throw InputError(message);
}

// The least --memory, rounded up to 8 MiB, at which `bytes` fit beside what `beside` says the
// ingest holds at that budget (which grows with it: iterated to its fixed point).
template <class Beside>
std::uint64_t memory_admitting(std::uint64_t bytes, std::uint64_t memory, Beside&& beside) {
  constexpr std::uint64_t kStep = std::uint64_t(8) << 20;
  for (int round = 0; round < 16; ++round) {
    const std::uint64_t need = bytes + beside(memory);
    const std::uint64_t next = need > kPreprocessInputAllowance ? need - kPreprocessInputAllowance : 0;
    if (next <= memory) break;
    memory = next;
  }
  return std::max((memory + kStep - 1) / kStep * kStep, kLeastPreprocessMemory);
}

// Up front, before any file is read: every piece whose estimate exceeds the room the budget
// leaves it is read in chunks where it can be and fits so, else refused with the figure (STEP
// and IGES once tessellated: load_tessellated). Returns each piece's room.
std::vector<std::uint64_t> check_read_room(const std::vector<InputPiece>& jobs,
                                           std::vector<PieceEstimate>& estimates,
                                           const PreprocessOptions& options, std::size_t threads) {
  const std::uint64_t memory = options.memory_bytes;
  const std::uint64_t largest = largest_estimate(estimates);
  std::vector<std::uint64_t> rooms(jobs.size());
  PiecesBefore before;
  for (std::size_t j = 0; j < jobs.size(); ++j) {
    if (j > 0) {
      before.soups += estimates[j - 1].read.soup_bytes() * jobs[j - 1].copies();
      before.triangles += estimates[j - 1].read.triangles * jobs[j - 1].copies();
      before.parts += jobs[j - 1].copies();
    }
    const auto beside = [&](std::uint64_t at) { return held_beside(before, largest, at, threads); };
    const std::uint64_t held = beside(memory);
    const std::uint64_t total = memory + kPreprocessInputAllowance;
    rooms[j] = total > held ? total - held : 0;
    // A file in a format read in chunks, however many times it is placed (read once per copy;
    // a file that fits is read once and its copies placed in batches).
    const bool streams = estimates[j].read.chunked;
    if (estimates[j].bytes <= rooms[j] && !(options.force_spill && streams)) continue;
    const StreamPlan plan = streams ? plan_stream(estimates[j].read, rooms[j]) : StreamPlan{};
    const std::uint64_t bytes = streams ? plan.bytes : estimates[j].bytes;
    if (bytes <= rooms[j]) {
      estimates[j].streamed = streams;
      // Forced spills send the vertex table to disk too, past a few blocks.
      constexpr std::uint64_t kForcedHeldVertices = 4096;
      estimates[j].held_vertices = options.force_spill
                                       ? std::min(plan.held_vertices, kForcedHeldVertices)
                                       : plan.held_vertices;
      continue;
    }
    refuse_reading(jobs[j].file(), estimates[j].read, bytes, held,
                   memory_admitting(bytes, memory, beside), memory);
  }
  return rooms;
}

// What one placed copy of `source` takes while its components are found: the soup (24 B a
// vertex, 16 a triangle) and the component search's tables (about 40 B a vertex, 8 a
// triangle; SurfaceComponents.cpp).
std::uint64_t copy_working_bytes(const TriangleSoup& source) {
  return 64 * std::uint64_t(source.vertices.size()) + 24 * std::uint64_t(source.triangles.size());
}

// The memory the ingest's pieces in flight share (an eighth of the budget), and each batch of
// placed copies: a sixteenth, split between the batches placed at once.
std::uint64_t batch_bytes(const PreprocessOptions& options, std::size_t threads) {
  return std::max<std::uint64_t>(options.memory_bytes / 16 / (threads + 1), 1);
}

// The tables cannot spill: a model whose tables alone exceed the budget is refused (a tetras
// file of 50,000 parts, 9.4 MiB of tables, is a model the 16 MiB budget works with).
void check_table_bytes(std::uint64_t parts, std::uint64_t bytes, const PreprocessOptions& options) {
  if (bytes <= options.memory_bytes) return;
  std::string message = std::to_string(parts);
  message.append(" parts need about ")
      .append(format_byte_size(bytes))
      .append(" of part and component tables, above --memory ")
      .append(format_byte_size(options.memory_bytes))
      .append(": raise --memory to ")
      .append(format_byte_size(2 * bytes))
      .append(" or more");
  throw InputError(message);
}

// The disk the spill and the index need for `triangles` triangles whose soups take
// `soup_bytes`: the index's 32 B a triangle measured (24 counted), and, once the soups exceed
// their share of the budget, the soups and at least one binned 88-byte record a triangle.
struct DiskNeed {
  std::uint64_t spill = 0, index = 0;
};
DiskNeed disk_need(double triangles, double soup_bytes, const PreprocessOptions& options) {
  constexpr double kIndexBytes = 24, kRecordBytes = sizeof(TriangleRecord);
  const bool spills = options.force_spill || soup_bytes > double(options.memory_bytes / 4);
  const double spill = spills ? soup_bytes + kRecordBytes * triangles : 0;
  const double cap = 1.8e19;  // within std::uint64_t
  return {std::uint64_t(std::min(spill, cap)),
          std::uint64_t(std::min(kIndexBytes * triangles, cap))};
}

// Refuses a model that the free disk cannot hold, as soon as what it places is known.
void check_disk_room(const DiskRoom& room, double triangles, double soup_bytes,
                     const PreprocessOptions& options) {
  const DiskNeed need = disk_need(triangles, soup_bytes, options);
  const auto refuse = [&](std::uint64_t bytes, const std::filesystem::path& folder,
                          std::uint64_t free) {
    char count[32];
    std::snprintf(count, sizeof count, "%.2g", triangles);
    std::string message = "the model places ";
    message.append(count)
        .append(" triangles, about ")
        .append(format_byte_size(bytes))
        .append(" of spill and index, but ")
        .append(folder.string())
        .append(" has ")
        .append(format_byte_size(free))
        .append(" free");
    throw InputError(message);
  };
  if (room.same_device) {
    if (need.spill + need.index > room.spill_free)
      refuse(need.spill + need.index, room.spill_folder, room.spill_free);
    return;
  }
  if (need.spill > room.spill_free) refuse(need.spill, room.spill_folder, room.spill_free);
  if (need.index > room.output_free) refuse(need.index, room.output_folder, room.output_free);
}

// Reads a file in chunks into a StreamedFile, once per copy a manifest places (each copy's
// triangles follow the one before, as the copies placed whole do): each chunk placed, its
// coordinates checked, its parts counted, its components labelled, and the chunk spilled; the
// labels united at the end. Copies are parts of their own: no component spans two.
class StreamedReading {
 public:
  // `tessellated`: the piece's STEP or IGES file, read already (its report `tessellated_report`),
  // whose instances are placed in chunks; null for a mesh file, read in chunks once per copy.
  StreamedReading(const InputPiece& piece, const PieceEstimate& estimate,
                  const PreprocessOptions& options, const std::filesystem::path& spill_folder,
                  const TessellatedFile* tessellated = nullptr,
                  const ReadReport& tessellated_report = {})
      : piece_(piece),
        options_(options),
        tessellated_(tessellated),
        tessellated_report_(tessellated_report),
        copies_(piece.manifest ? piece.copies() : 1),
        name_("streamed-" + std::to_string(next_name_++)),
        file_(std::make_unique<StreamedFile>(spill_folder, name_)),
        components_(spill_folder, name_, copies_ * distinct_positions(estimate.read),
                    kPositionBucketBytes),
        progress_("reading " + piece.file().filename().string() + " in chunks (triangles)",
                  estimate.read.counted ? copies_ * estimate.read.triangles : 0, options.progress,
                  options.on_progress),
        expected_triangles_(copies_ * estimate.read.triangles) {
    chunks_.triangles = kChunkTriangles;
    chunks_.held_vertices = estimate.held_vertices;
    chunks_.vertex_folder = spill_folder;
    chunks_.vertex_cache_bytes = kVertexCacheBytes;
    chunks_.take = [this](TriangleSoup&& chunk) { take(std::move(chunk)); };
    // Every vertex, used or not, is checked as the whole read checks it.
    chunks_.on_vertex = [this](const Vec3& vertex) {
      if (placement_) {
        placement_->note_vertex(vertex);
      } else {
        check_coordinate_magnitude(vertex, piece_);
      }
    };
    chunks_.keep_dropped_positions = false;
  }

  std::unique_ptr<StreamedFile> read(ReadReport& report) {
    for (std::size_t copy = 0; copy < copies_; ++copy) read_copy(copy, report);
    report.tessellation_deflection = largest_deflection_;
    progress_.finish();
    file_->part_triangles.resize(std::max<std::size_t>(file_->parts.part_count(), 1), 0);
    // The components' table cannot spill: past the budget, refused as the model's would be.
    const std::uint64_t most = std::max<std::uint64_t>(options_.memory_bytes / kComponentEntryBytes, 1);
    std::string refusal = quoted_input(piece_.file().string(), 4096);
    refusal.append(": more than ")
        .append(thousands(most))
        .append(" connected components, whose table exceeds --memory ")
        .append(format_byte_size(options_.memory_bytes))
        .append("; raise --memory");
    file_->united = components_.unite(most, refusal);
    return std::move(file_);
  }

 private:
  // Distinct positions: about the vertices of an indexed file, a sixth of an STL's corners.
  static std::uint64_t distinct_positions(const MeshReadEstimate& read) {
    return read.vertices <= 2 * read.triangles ? read.vertices : read.vertices / 6;
  }

  // The file's report once (its first reading), every copy's flattened triangles, and the
  // tessellation's deflection over every copy (in the top manifest's unit).
  void read_copy(std::size_t copy, ReadReport& report) {
    if (piece_.manifest)
      placement_.emplace(piece_, copy, tessellated_ ? tessellated_report_.length_unit : std::string());
    part_base_ = std::uint32_t(file_->parts.part_count());
    ReadReport reading = tessellated_report_;
    const TriangleSoup file_parts =
        tessellated_ ? tessellated_->place_in_chunks(chunks_, reading)
                     : read_mesh_in_chunks(piece_.file(), &reading, chunks_, options_.tessellation);
    if (copy == 0) report = reading;
    largest_deflection_ = std::max(largest_deflection_, reading.tessellation_deflection *
                                                            (placement_ ? placement_->largest_scale() : 1.0));
    const TriangleSoup parts = placement_ ? placement_->finish(file_parts) : file_parts;
    if (placement_) report.degenerate_dropped += placement_->dropped();
    for (std::size_t p = 0; p < parts.part_count(); ++p)
      file_->parts.add_part(parts.part_names[p], parts.part_paths.empty() ? "" : parts.part_paths[p]);
    placement_.reset();
  }

  void take(TriangleSoup&& chunk) {
    if (placement_) placement_->place(chunk);
    if (chunk.triangle_count() == 0) return;  // its vertices were checked as they were read
    for (std::uint32_t& part : chunk.part_of) {
      part += part_base_;
      if (part >= file_->part_triangles.size()) file_->part_triangles.resize(part + 1, 0);
      ++file_->part_triangles[part];
    }
    components_.add_chunk(chunk, file_->triangles);
    check_label_bytes();
    file_->triangles += chunk.triangle_count();
    file_->soup_bytes += SoupSpill<TriangleRecord>::soup_bytes(chunk);
    progress_.advance(chunk.triangle_count());
    file_->chunks.append(std::move(chunk), 0);
  }

  // The labels (8 B each) stay in memory until they are united: a file whose triangles follow
  // no spatial order makes about one a triangle. Refused past a quarter of the budget.
  void check_label_bytes() const {
    const std::uint64_t bytes = components_.label_bytes(), limit = options_.memory_bytes / 4;
    if (bytes <= limit) return;
    // The labels grow with the triangles: the whole file's, at the rate so far.
    const double whole = double(bytes) * double(std::max(expected_triangles_, file_->triangles)) /
                         double(std::max<std::uint64_t>(file_->triangles, 1));
    constexpr double kStep = double(std::uint64_t(8) << 20);
    const auto raise_to = std::uint64_t(std::ceil(4 * whole / kStep) * kStep);
    std::string message = quoted_input(piece_.file().string(), 4096);
    message.append(": read in chunks, its first ")
        .append(thousands(file_->triangles))
        .append(" triangles make ")
        .append(thousands(components_.label_count()))
        .append(" pieces of connected components (its triangles follow no spatial order), ")
        .append(format_byte_size(bytes))
        .append(" of labels, above a quarter of --memory ")
        .append(format_byte_size(options_.memory_bytes))
        .append("; raise --memory to ")
        .append(format_byte_size(raise_to))
        .append(" or more, or write the file with its triangles in order");
    throw InputError(message);
  }

  static inline std::atomic<unsigned> next_name_{0};  // streamed files read at once differ

  const InputPiece& piece_;
  const PreprocessOptions& options_;
  const TessellatedFile* tessellated_;
  ReadReport tessellated_report_;
  double largest_deflection_ = 0;
  std::size_t copies_;
  std::string name_;  // of its spill files
  std::unique_ptr<StreamedFile> file_;
  ChunkedComponents components_;
  Progress progress_;  // a file read in chunks is long work of its own
  SoupChunks chunks_;
  std::uint64_t expected_triangles_;       // by the estimate, every copy
  std::optional<PlacedChunks> placement_;  // of the copy being read
  std::uint32_t part_base_ = 0;            // its first part
};

// Reads a piece in chunks (estimate.streamed): a mesh file once per copy, or the instances of a
// STEP or IGES file read already (`tessellated`, with its report) placed a chunk at a time.
LoadedSoup load_streamed(const InputPiece& piece, const PieceEstimate& estimate,
                         const PreprocessOptions& options, const std::filesystem::path& spill_folder,
                         const DiskRoom& disk, const TessellatedFile* tessellated = nullptr,
                         const ReadReport& tessellated_report = {}) {
  // Before it is read, by its estimate alone: its chunks spill twice (its own spill, then the
  // model's), and the whole model is weighed again once it is read (append_piece).
  const double copies = double(piece.copies());
  check_disk_room(disk, copies * double(estimate.read.triangles),
                  2.0 * copies * double(estimate.read.soup_bytes()), options);
  LoadedSoup loaded;
  loaded.file = piece.input.string();
  loaded.streamed = StreamedReading(piece, estimate, options, spill_folder, tessellated,
                                    tessellated_report)
                        .read(loaded.report);
  loaded.length_unit = piece.manifest ? piece.manifest->units : loaded.report.length_unit;
  return loaded;
}

// A piece whose file `loader` read: its copies left to be placed in batches when together they
// exceed a batch, else placed whole with their components found.
LoadedSoup load_placed(const InputPiece& piece, std::unique_ptr<PieceLoader> loader,
                       const PreprocessOptions& options, std::size_t threads) {
  LoadedSoup loaded;
  loaded.file = piece.input.string();
  loaded.length_unit = piece.manifest ? piece.manifest->units : loader->report().length_unit;
  const std::uint64_t whole = copy_working_bytes(loader->source()) * loader->copies();
  if (loader->copies() > 1 && whole > batch_bytes(options, threads)) {
    loaded.loader = std::move(loader);
    return loaded;
  }
  if (loader->placed_as_read()) {
    loaded.soup = loader->take_source();
  } else {
    loader->place(0, loader->copies(), loaded.soup);
  }
  loaded.report = loader->report();
  loader.reset();  // the file's soup is not held beside its placed copy
  find_components(loaded, piece);
  return loaded;
}

// A STEP or IGES file's triangles are known once it is tessellated: its distinct shapes held,
// its instances are placed whole when that fits `room` (the file's placed soup beside the
// shapes, then its components), else a chunk at a time when the shapes fit, else refused with
// the figure.
LoadedSoup load_tessellated(const InputPiece& piece, PieceEstimate estimate,
                            const PreprocessOptions& options,
                            const std::filesystem::path& spill_folder, const DiskRoom& disk,
                            std::size_t threads, std::uint64_t room) {
  ReadReport report;
  auto tessellated = std::make_unique<TessellatedFile>(piece.file(), options.tessellation, report);
  MeshReadEstimate& read = estimate.read;
  read.counted = true;
  read.vertices = tessellated->placed_vertices();
  read.triangles = tessellated->placed_triangles();
  // Placing holds the shapes and one instance's placed vertices (24 B each) beside the soup,
  // or, in chunks, beside a chunk with 12 B more a vertex to number the chunk's.
  const std::uint64_t shapes = tessellated->held_bytes();
  const std::uint64_t instance = 24 * tessellated->largest_shape_vertices();
  read.reading_bytes = read.soup_bytes() + shapes + instance;
  estimate.bytes = piece_bytes(read, piece.copies(), piece.manifest != nullptr);
  if (estimate.bytes <= room && !options.force_spill) {
    TriangleSoup soup = tessellated->place(report);
    tessellated.reset();  // its shapes are not held beside the placed soup's components
    return load_placed(piece, std::make_unique<PieceLoader>(piece, std::move(soup), report),
                       options, threads);
  }
  read.chunked_bytes = shapes + instance + 12 * tessellated->largest_shape_vertices();
  read.vertex_table_bytes = 0;
  const std::uint64_t bytes = plan_stream(read, room).bytes;
  if (bytes > room) {
    const std::uint64_t memory = options.memory_bytes, total = memory + kPreprocessInputAllowance;
    const std::uint64_t held = total - std::min(room, total);
    refuse_reading(piece.file(), read, bytes, held,
                   memory_admitting(bytes, memory, [held](std::uint64_t) { return held; }), memory);
  }
  estimate.streamed = true;
  return load_streamed(piece, estimate, options, spill_folder, disk, tessellated.get(), report);
}

LoadedSoup load_soup(const InputPiece& piece, const PieceEstimate& estimate,
                     const PreprocessOptions& options, const std::filesystem::path& spill_folder,
                     const DiskRoom& disk, std::size_t threads, std::uint64_t room) {
  if (estimate.read.cad)
    return load_tessellated(piece, estimate, options, spill_folder, disk, threads, room);
  if (estimate.streamed) return load_streamed(piece, estimate, options, spill_folder, disk);
  return load_placed(piece, std::make_unique<PieceLoader>(piece, options.tessellation), options,
                     threads);
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


// Up front, before any file is read: each placed copy is at least one part.
void check_part_count(const std::vector<InputPiece>& jobs, const PreprocessOptions& options) {
  std::uint64_t parts = 0;
  for (const InputPiece& job : jobs) parts += job.copies();
  check_table_bytes(parts, parts * kPartEntryBytes, options);
}

// What the ingest accumulates besides the model: the sample's generator and the figures the
// checks need.
struct IngestState {
  std::size_t sample_capacity = 0;
  std::mt19937_64 random{0x7e7a9a9e};
  std::uint64_t soup_bytes = 0;   // of every soup appended (held or spilled)
  std::uint64_t table_bytes = 0;  // of the parts' and components' tables
};

// A file's report into the summary, and its unit into the model.
void note_file(IngestedModel& model, const LoadedSoup& loaded, const ReadReport& report,
               PreprocessSummary& summary) {
  summary.degenerate_dropped += report.degenerate_dropped;
  for (const std::string& skipped : report.skipped_parts)
    summary.skipped_parts.push_back(report.path + ": " + skipped);
  ++summary.files_read;
  model.tessellation_deflection =
      std::max(model.tessellation_deflection, report.tessellation_deflection);
  note_length_unit(model, loaded);
}

// Counts a soup's triangles into the model and keeps its centroids in the reservoir sample
// (of at most sample_capacity), one at a time: no array of a whole file's centroids.
void sample_centroids(IngestedModel& model, const TriangleSoup& soup, IngestState& state) {
  for (std::size_t t = 0; t < soup.triangle_count(); ++t, ++model.triangle_count) {
    if (model.sample.size() < state.sample_capacity) {
      model.sample.push_back(centroid(soup.corners(t)));
    } else {
      const std::uint64_t slot =
          std::uniform_int_distribution<std::uint64_t>(0, model.triangle_count)(state.random);
      if (slot < state.sample_capacity) model.sample[slot] = centroid(soup.corners(t));
    }
  }
}

// Appends a file's parts (`names`, and `triangles` kept in each) to the model's tables;
// returns the first one's number.
std::uint32_t append_parts(IngestedModel& model, const TriangleSoup& names,
                           const std::vector<std::uint64_t>& triangles, IngestState& state) {
  const auto part_offset = std::uint32_t(model.part_names.size());
  for (std::size_t p = 0; p < names.part_count(); ++p) {
    model.part_names.push_back(names.part_names[p]);
    model.part_paths.push_back(names.part_path(p));
  }
  if (names.part_names.empty()) {
    model.part_names.push_back("part" + std::to_string(part_offset));
    model.part_paths.push_back(model.part_names.back());
  }
  for (std::size_t p = part_offset; p < model.part_names.size(); ++p)
    state.table_bytes +=
        kPartEntryBytes + model.part_names[p].capacity() + model.part_paths[p].capacity();
  model.part_triangles.insert(model.part_triangles.end(), triangles.begin(), triangles.end());
  return part_offset;
}

// Appends a file's components (their parts numbered in the file) to the model's; returns the
// first one's number.
std::uint32_t append_components(IngestedModel& model, std::vector<SurfaceComponent>& components,
                                std::uint32_t part_offset, const PreprocessOptions& options,
                                IngestState& state) {
  if (model.components.size() + components.size() >= kInteriorUndecided)
    throw InputError("the inputs hold more than 2^32 - 2 connected components");
  const auto component_offset = std::uint32_t(model.components.size());
  for (SurfaceComponent& c : components) {
    c.part += part_offset;
    model.bounds.extend(c.bounds);
    model.components.push_back(c);
  }
  state.table_bytes += kComponentEntryBytes * components.size();
  check_table_bytes(model.part_names.size(), state.table_bytes, options);
  return component_offset;
}

// Appends a placed soup's parts, components and triangles to the model (its arrays taken);
// the soups spill once they would hold more than a quarter of the budget.
void append_soup(IngestedModel& model, LoadedSoup& loaded, const PreprocessOptions& options,
                 const std::filesystem::path& spill_folder, IngestState& state) {
  const std::uint32_t part_offset = append_parts(model, loaded.soup, loaded.part_triangles, state);
  const std::uint32_t component_offset =
      append_components(model, loaded.components, part_offset, options, state);
  sample_centroids(model, loaded.soup, state);
  const std::uint64_t bytes = SoupSpill<TriangleRecord>::soup_bytes(loaded.soup);
  state.soup_bytes += bytes;
  const std::uint64_t held_limit = options.memory_bytes / 4;
  if (!model.soups.spilled() &&
      (model.soups.held_bytes() + bytes > held_limit || options.force_spill))
    model.soups.spill_to(spill_path(spill_folder, "triangles"));
  model.soups.append(std::move(loaded.soup), component_offset);
  loaded.soup = TriangleSoup();
}

// Appends a file read in chunks: its parts and components, then its chunks one at a time, each
// triangle's label replaced by its component; the model's soups spill (the file did not fit).
void append_streamed(IngestedModel& model, StreamedFile& file, const PreprocessOptions& options,
                     const std::filesystem::path& spill_folder, IngestState& state) {
  const std::uint32_t part_offset = append_parts(model, file.parts, file.part_triangles, state);
  const std::uint32_t component_offset =
      append_components(model, file.united.components, part_offset, options, state);
  if (!model.soups.spilled()) model.soups.spill_to(spill_path(spill_folder, "triangles"));
  file.chunks.for_each_soup([&](TriangleSoup&& chunk, std::uint32_t) {
    for (std::uint32_t& label : chunk.part_of) label = file.united.component_of_label[label];
    sample_centroids(model, chunk, state);
    state.soup_bytes += SoupSpill<TriangleRecord>::soup_bytes(chunk);
    model.soups.append(std::move(chunk), component_offset);
  });
  file.chunks.clear();
}

// Places a piece's copies a batch at a time, each batch within its share of the budget, on all
// threads, appended in order: the same triangles, parts and components, in the same order, as
// placing them all at once (components never span parts, and each copy is its own parts).
void append_in_batches(IngestedModel& model, LoadedSoup& loaded, const InputPiece& piece,
                       const PreprocessOptions& options, const std::filesystem::path& spill_folder,
                       IngestState& state, std::size_t threads) {
  const PieceLoader& loader = *loaded.loader;
  const std::uint64_t per_copy = std::max<std::uint64_t>(copy_working_bytes(loader.source()), 1);
  const std::size_t batch =
      std::max<std::size_t>(std::size_t(batch_bytes(options, threads) / per_copy), 1);
  const std::size_t copies = loader.copies();
  produce_in_parallel_consume_in_order(
      (copies + batch - 1) / batch, threads + 1,
      [&](std::size_t b) {
        auto placed = std::make_shared<LoadedSoup>();
        loader.place(b * batch, std::min(batch, copies - b * batch), placed->soup);
        find_components(*placed, piece);
        return placed;
      },
      [&](const std::shared_ptr<LoadedSoup>& placed) {
        append_soup(model, *placed, options, spill_folder, state);
      });
}

// Appends one piece in input order: the disk it will take is checked first (its copies times
// its file's triangles), then it is appended whole or in batches.
void append_piece(IngestedModel& model, LoadedSoup& loaded, const InputPiece& piece,
                  const PreprocessOptions& options, const std::filesystem::path& spill_folder,
                  const DiskRoom& room, IngestState& state, PreprocessSummary& summary,
                  std::size_t threads) {
  if (loaded.streamed) {
    // Its chunks' spill is on the disk beside the model's until they are appended.
    const StreamedFile& file = *loaded.streamed;
    check_disk_room(room, double(model.triangle_count + file.triangles),
                    double(state.soup_bytes + 2 * file.soup_bytes), options);
    note_file(model, loaded, loaded.report, summary);
    ++summary.files_read_in_chunks;
    append_streamed(model, *loaded.streamed, options, spill_folder, state);
    loaded.streamed.reset();
    return;
  }
  if (loaded.loader) {
    const TriangleSoup& source = loaded.loader->source();
    const double copies = double(loaded.loader->copies());
    check_disk_room(
        room, double(model.triangle_count) + copies * double(source.triangle_count()),
        double(state.soup_bytes) + copies * double(SoupSpill<TriangleRecord>::soup_bytes(source)),
        options);
    append_in_batches(model, loaded, piece, options, spill_folder, state, threads);
    // After the batches: the report then counts the triangles every placement dropped, and the
    // tessellation's deflection over every placement.
    note_file(model, loaded, loaded.loader->report(), summary);
    return;
  }
  check_disk_room(room, double(model.triangle_count + loaded.soup.triangle_count()),
                  double(state.soup_bytes + SoupSpill<TriangleRecord>::soup_bytes(loaded.soup)),
                  options);
  note_file(model, loaded, loaded.report, summary);
  append_soup(model, loaded, options, spill_folder, state);
}

}  // namespace

DiskRoom measure_disk_room(const std::filesystem::path& spill_folder,
                           const std::filesystem::path& output, const PreprocessOptions& options) {
  DiskRoom room;
  room.spill_folder = spill_folder;
  room.output_folder = std::filesystem::absolute(output).parent_path();
  if (options.assumed_free_disk_bytes != 0) {
    room.spill_free = room.output_free = options.assumed_free_disk_bytes;
    return room;
  }
  std::error_code error;
  const auto spill = std::filesystem::space(room.spill_folder, error);
  if (!error) room.spill_free = spill.available;
  const auto out = std::filesystem::space(room.output_folder, error);
  if (!error) room.output_free = out.available;
  struct stat a {
  }, b{};
  room.same_device = ::stat(room.spill_folder.c_str(), &a) != 0 ||
                     ::stat(room.output_folder.c_str(), &b) != 0 || a.st_dev == b.st_dev;
  return room;
}

IngestedModel ingest(const std::vector<std::filesystem::path>& inputs,
                     const PreprocessOptions& options, const std::filesystem::path& spill_folder,
                     const DiskRoom& room, PreprocessSummary& summary) {
  IngestedModel model;
  IngestState state;
  // At most 2M centroids, at least 2^16: a site stands for the mean of hundreds of sampled
  // centroids at the default region size. A cap of 4M gave the 10M scene the same regions
  // (26,081 against 26,071), duplication (1.2623 against 1.2630) and flights in memory (six
  // objects, four runs each, within their noise) at twice the coarse mesh's time; 1M began to
  // show in the flights (the tetrahedron's 7 % slower; docs/BENCHMARKS.md).
  state.sample_capacity = std::size_t(
      std::clamp<std::uint64_t>(options.memory_bytes / (8 * sizeof(Vec3)), 1 << 16, kMostSampledCentroids));
  model.sample.reserve(std::min<std::size_t>(state.sample_capacity, 1 << 16));

  // One part file at a time per thread: the ingest never holds the assembly.
  const std::vector<InputPiece> jobs = input_pieces(inputs);
  check_part_count(jobs, options);
  const auto threads = std::size_t(tbb::this_task_arena::max_concurrency());
  std::vector<PieceEstimate> estimates;
  estimates.reserve(jobs.size());
  for (const InputPiece& job : jobs) estimates.push_back(estimate_piece(job));
  const std::vector<std::uint64_t> rooms = check_read_room(jobs, estimates, options, threads);
  // Parsing, placement, edge parity and bounds run on all threads, a few pieces at once; the
  // soups are appended in input order on one.
  Progress progress("reading parts", jobs.size(), options.progress, options.on_progress);
  std::size_t next_job = 0;
  produce_in_parallel_consume_in_order(
      jobs.size(), ingest_depth(largest_estimate(estimates), options.memory_bytes, threads),
      [&](std::size_t j) {
        return std::make_shared<LoadedSoup>(
            load_soup(jobs[j], estimates[j], options, spill_folder, room, threads, rooms[j]));
      },
      [&](const std::shared_ptr<LoadedSoup>& loaded) {
        // In input order (ids, part numbers and the sample do not depend on the threads).
        append_piece(model, *loaded, jobs[next_job++], options, spill_folder, room, state, summary,
                     threads);
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
