#include "tetrapage/preprocess/Preprocess.h"
#include "tetrapage/formats/IndexSchema.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>
#include <tbb/parallel_sort.h>
#include <unistd.h>

#include <algorithm>
#include <type_traits>
#include <array>
#include <atomic>
#include <mutex>
#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>
#include <limits>
#include <memory>
#include <numeric>
#include <optional>
#include <random>
#include <sstream>

#include "tetrapage/formats/ByteSize.h"
#include "tetrapage/formats/SurfaceComponents.h"
#include "tetrapage/formats/Error.h"
#include "tetrapage/formats/FileChecks.h"
#include "tetrapage/formats/TemporaryFiles.h"
#include "tetrapage/formats/IndexHeader.h"
#include "tetrapage/formats/IndexWriter.h"
#include "tetrapage/formats/Manifest.h"
#include "tetrapage/formats/MemoryUsage.h"
#include "tetrapage/formats/MeshReader.h"
#include "tetrapage/formats/Pose.h"
#include "tetrapage/formats/Progress.h"
#include "MortonGrid.h"
#include "OrderedPipeline.h"
#include "SpillPath.h"
#include "TriangleRecord.h"
#include "tetrapage/preprocess/CoarseMesh.h"
#include "tetrapage/preprocess/RayParity.h"
#include "tetrapage/preprocess/RecordSpill.h"
#include "tetrapage/preprocess/SoupSpill.h"
#include "tetrapage/preprocess/ShardBuilder.h"
#include "tetrapage/preprocess/ShardCostModel.h"
#include "tetrapage/preprocess/TriangleBinning.h"
#include "tetrapage/runtime/MeshWalk.h"
#include "tetrapage/runtime/geometry/Box.h"
#include "tetrapage/runtime/geometry/PointTetrahedron.h"

namespace tetrapage {

namespace schema = index_schema;
namespace {

using Clock = std::chrono::steady_clock;

// Runs one stage, recording its time and peak resident memory.
class StageClock {
 public:
  StageClock(PreprocessSummary& summary, std::string name) : summary_(summary), name_(std::move(name)) {
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

// Sorts words by their high 32 bits, stably (three passes of a counting sort, 11 bits each).
void sort_by_high_word(std::vector<std::uint64_t>& words, std::vector<std::uint64_t>& scratch) {
  scratch.resize(words.size());
  for (const int shift : {32, 43, 54}) {
    std::array<std::size_t, 2049> start{};
    for (const std::uint64_t w : words) ++start[((w >> shift) & 0x7ff) + 1];
    for (std::size_t d = 1; d < start.size(); ++d) start[d] += start[d - 1];
    for (const std::uint64_t w : words) scratch[start[(w >> shift) & 0x7ff]++] = w;
    words.swap(scratch);
  }
}

// The binned copies of one bucket: records in a spill file or, while the ingested soups are
// held in memory, only (id, tet) pairs, 12 bytes instead of 88.
#pragma pack(push, 4)
struct CopyPair {
  std::uint64_t id;
  std::uint32_t tet;
};
#pragma pack(pop)

// A counting sort of copies by their tet's rank: where each copy goes (target), and where each
// tet's copies start (with their count last). Stable, on all threads: fixed chunks of the
// copies count their ranks, and each chunk's copies of a rank go after those of the chunks
// before it (done on one thread, this was a serial 0.05 s at the start of the 10M shard stage).
template <class Copy>
std::vector<std::size_t> place_copies_by_tet(const std::vector<Copy>& copies, std::span<const std::uint32_t> rank,
                                             std::vector<std::uint32_t>& target) {
  const std::size_t n = copies.size();
  if (n >= std::numeric_limits<std::uint32_t>::max())
    throw InputError("a bucket of " + std::to_string(n) +
                     " triangle copies is beyond 2^32: give a smaller --memory, for more buckets");
  target.resize(n);
  std::vector<std::size_t> group_start;
  if (n > 0) {
    const std::size_t chunks = std::min<std::size_t>(16, (n + 65535) / 65536);
    const auto first_of = [&](std::size_t c) { return c * n / chunks; };
    std::vector<std::uint32_t> chunk_lowest(chunks), chunk_highest(chunks);
    tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
      std::uint32_t lowest = std::numeric_limits<std::uint32_t>::max(), highest = 0;
      for (std::size_t i = first_of(c); i < first_of(c + 1); ++i) {
        lowest = std::min(lowest, rank[copies[i].tet]);
        highest = std::max(highest, rank[copies[i].tet]);
      }
      chunk_lowest[c] = lowest;
      chunk_highest[c] = highest;
    });
    const std::uint32_t lowest = *std::min_element(chunk_lowest.begin(), chunk_lowest.end());
    const std::size_t ranks = std::size_t(*std::max_element(chunk_highest.begin(), chunk_highest.end()) - lowest) + 1;
    // next[c * ranks + r]: chunk c's count of rank lowest + r, then where its next one goes.
    std::vector<std::uint32_t> next(chunks * ranks, 0);
    tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
      std::uint32_t* count = next.data() + c * ranks;
      for (std::size_t i = first_of(c); i < first_of(c + 1); ++i) ++count[rank[copies[i].tet] - lowest];
    });
    std::uint32_t placed = 0;
    for (std::size_t r = 0; r < ranks; ++r) {
      const std::uint32_t start = placed;
      for (std::size_t c = 0; c < chunks; ++c) {
        const std::uint32_t count = next[c * ranks + r];
        next[c * ranks + r] = placed;
        placed += count;
      }
      if (placed > start) group_start.push_back(start);
    }
    tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
      std::uint32_t* at = next.data() + c * ranks;
      for (std::size_t i = first_of(c); i < first_of(c + 1); ++i) target[i] = at[rank[copies[i].tet] - lowest]++;
    });
  }
  group_start.push_back(n);
  return group_start;
}

// Sorts each group [start[g], start[g + 1]) of `values` by `less`, on all threads (a sorted
// group, as the in-memory binning's are, is only checked).
template <class Value, class Less>
void sort_groups(std::vector<Value>& values, const std::vector<std::size_t>& start, Less less) {
  tbb::parallel_for(std::size_t(0), start.size() - 1, [&](std::size_t g) {
    const auto first = values.begin() + std::ptrdiff_t(start[g]), last = values.begin() + std::ptrdiff_t(start[g + 1]);
    if (!std::is_sorted(first, last, less)) std::sort(first, last, less);
  });
}

// One bucket's copies as the shard stage reads them: records read back from a spill file, or
// (id, tet) pairs whose records the soups give when a shard gathers its triangles (a bucket's
// records, 88 bytes a copy, are then never all held: at 10M they were 1.1 GB).
class BucketCopies {
 public:
  explicit BucketCopies(std::vector<TriangleRecord> records) : records_(std::move(records)) {}
  BucketCopies(std::vector<CopyPair> pairs, const SoupSpill<TriangleRecord>& soups)
      : soups_(&soups), pairs_(std::move(pairs)) {}
  /// Orders the copies by their tet's rank, each tet's by id; returns where each tet's copies
  /// start in that order, and their count last. The pairs are moved into that order (a second
  /// array, 12 bytes a copy: the sorts and gathers then read them in order, where reading them
  /// through positions was a cache miss each); the records, 88 bytes, are read through positions.
  std::vector<std::size_t> order_by_tet(std::span<const std::uint32_t> rank) {
    std::vector<std::uint32_t> target;
    if (!soups_) {
      const std::vector<std::size_t> start = place_copies_by_tet(records_, rank, target);
      order_.resize(records_.size());
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, records_.size(), 1 << 16), [&](const auto& range) {
        for (std::size_t i = range.begin(); i < range.end(); ++i) order_[target[i]] = std::uint32_t(i);
      });
      sort_groups(order_, start, [&](std::uint32_t a, std::uint32_t b) { return records_[a].id < records_[b].id; });
      return start;
    }
    const std::vector<std::size_t> start = place_copies_by_tet(pairs_, rank, target);
    std::vector<CopyPair> placed(pairs_.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pairs_.size(), 1 << 16), [&](const auto& range) {
      for (std::size_t i = range.begin(); i < range.end(); ++i) placed[target[i]] = pairs_[i];
    });
    pairs_.swap(placed);
    sort_groups(pairs_, start, [](const CopyPair& a, const CopyPair& b) { return a.id < b.id; });
    return start;
  }
  /// The tet of the i-th copy in order_by_tet's order.
  std::uint32_t tet(std::size_t i) const { return soups_ ? pairs_[i].tet : records_[order_[i]].tet; }
  /// Appends the triangles, ids and parts of copies [first, last) of order_by_tet's order.
  void gather(std::size_t first, std::size_t last, std::vector<geometry::Triangle>& triangles,
              std::vector<std::uint64_t>& ids, std::vector<std::uint32_t>& parts) const {
    if (soups_) {
      const std::size_t had = ids.size();
      // Copied out first: a reference to a packed member would be misaligned.
      for (std::size_t i = first; i < last; ++i) ids.push_back(std::uint64_t{pairs_[i].id});
      soups_->gather(std::span<const std::uint64_t>(ids).subspan(had), triangles, parts);
      return;
    }
    for (std::size_t i = first; i < last; ++i) {
      const TriangleRecord& record = records_[order_[i]];
      triangles.push_back(record.triangle);
      ids.push_back(std::uint64_t{record.id});
      parts.push_back(record.part);
    }
  }

 private:
  const SoupSpill<TriangleRecord>* soups_ = nullptr;
  std::vector<TriangleRecord> records_;
  std::vector<CopyPair> pairs_;
  std::vector<std::uint32_t> order_;  ///< of the records
};

class CopyBucket {
 public:
  CopyBucket(std::filesystem::path file, const SoupSpill<TriangleRecord>& soups)
      : soups_(soups.spilled() ? nullptr : &soups) {
    if (soups_ == nullptr) records_.emplace(std::move(file));
  }
  /// Records while the soups are spilled; (id, tet) pairs while they are in memory.
  void append(std::span<const TriangleRecord> copies) {
    if (!records_) throw Error("a bucket of (id, tet) pairs was given records");
    records_->append(copies);
  }
  void append(std::span<const CopyPair> copies) {
    if (records_) throw Error("a bucket that spills records was given (id, tet) pairs");
    pairs_.insert(pairs_.end(), copies.begin(), copies.end());
  }
  /// The copies, taken out of the bucket (which is then empty, its spill file removed).
  BucketCopies take() {
    BucketCopies copies = records_ ? BucketCopies(records_->read_all()) : BucketCopies(std::move(pairs_), *soups_);
    records_.reset();
    std::vector<CopyPair>().swap(pairs_);
    return copies;
  }

 private:
  const SoupSpill<TriangleRecord>* soups_;
  std::optional<RecordSpill<TriangleRecord>> records_;  ///< when the soups are spilled
  std::vector<CopyPair> pairs_;
};

// The marker of an undecided tet in the interiors' component lists (so never a component id).
constexpr std::uint32_t kInteriorUndecided = 0xffffffffu;

// Ingest: every part file read once, instances placed, soups kept compactly (SoupSpill); a
// reservoir sample of centroids (Algorithm R, fixed seed) bounded by the memory budget.
struct Ingest {
  SoupSpill<TriangleRecord> soups;
  std::vector<Vec3> sample;
  std::uint64_t seen = 0;
  BoundingBox bounds;
  std::vector<std::string> part_names;
  // The surfaces' connected components, model-wide (the ids the records and shards carry).
  std::vector<SurfaceComponent> components;
};

// One input soup (a manifest's part, or a mesh file) with what can be computed off the
// ingest's serial path: centroids, and its surfaces' connected components (its part_of then
// holds each triangle's component, numbered within the soup).
struct LoadedSoup {
  std::uint64_t degenerate_dropped = 0;
  std::uint64_t files_read = 0;
  TriangleSoup soup;
  std::vector<Vec3> centroids;  // per triangle
  std::vector<SurfaceComponent> components;
};

// Coordinates beyond kMaxCoordinateMagnitude overflow the coarse mesh's enlarged box and the
// exact predicates' products: refused, naming the file and the value.
void check_coordinate_magnitudes(const TriangleSoup& soup, const InputPiece& piece) {
  const CoordinateBeyondLimit beyond = find_coordinate_beyond_limit(soup);
  if (!beyond.found) return;
  char value[64];
  std::snprintf(value, sizeof value, "%g", beyond.value);
  const std::string file = piece.manifest ? piece.manifest->parts[piece.part].file.string() : piece.input.string();
  throw InputError(file + ": a vertex coordinate of " + value +
                   " is beyond 1e300 in magnitude: the model's box would overflow; scale the model");
}

LoadedSoup load_soup(const InputPiece& piece) {
  LoadedSoup loaded;
  std::vector<ReadReport> reports;
  loaded.soup = load_input_piece(piece, &reports);
  for (const auto& report : reports) {
    loaded.degenerate_dropped += report.degenerate_dropped;
    ++loaded.files_read;
  }
  TriangleSoup& soup = loaded.soup;
  check_coordinate_magnitudes(soup, piece);
  SurfaceComponents found = find_surface_components(soup);
  soup.part_of = std::move(found.component_of);
  loaded.components = std::move(found.components);
  loaded.centroids.resize(soup.triangle_count());
  for (std::size_t t = 0; t < soup.triangle_count(); ++t) loaded.centroids[t] = centroid(soup.corners(t));
  return loaded;
}

// How many soups the ingest's pipeline may hold at once. One more than the threads left both
// threads idle whenever the in-order append waited for a slow file; four times the threads
// took the 10M ingest from 0.91 to 0.72 s. Bounded so that the soups in flight, taken at 4
// times their files' bytes, stay within an eighth of the budget. (A loaded soup holds double
// vertices, indices and a double centroid a triangle: by arithmetic about 2.6 times a binary
// PLY of float vertices, less for double ones; not measured for every reader.)
std::size_t ingest_depth(const std::vector<InputPiece>& jobs, std::uint64_t memory_bytes, std::size_t threads) {
  std::uint64_t largest = 0;
  for (const InputPiece& job : jobs) {
    std::error_code error;
    if (!job.manifest) {
      largest = std::max<std::uint64_t>(largest, std::filesystem::file_size(job.input, error));
      continue;
    }
    const ManifestPart& part = job.manifest->parts[job.part];
    const std::uint64_t bytes = std::filesystem::file_size(part.file, error);
    if (!error) largest = std::max<std::uint64_t>(largest, bytes * std::max<std::size_t>(part.instances.size(), 1));
  }
  const std::size_t fewest = threads + 1, most = 4 * threads;
  if (largest == 0) return fewest;
  return std::clamp<std::size_t>(std::size_t(memory_bytes / 8 / (4 * largest)), fewest, std::max(fewest, most));
}

void ingest(const std::vector<std::filesystem::path>& inputs, const PreprocessOptions& options,
            const std::filesystem::path& spill_folder, Ingest& in, PreprocessSummary& summary) {
  const std::uint64_t held_limit = options.memory_bytes / 4;
  // At most 2M centroids, at least 2^16: a site stands for the mean of hundreds of sampled
  // centroids at the default region size. A cap of 4M gave the 10M scene the same regions
  // (26,081 against 26,071), duplication (1.2623 against 1.2630) and flights in memory (six
  // objects, four runs each, within their noise) at twice the coarse mesh's time; 1M began to
  // show in the flights (the tetrahedron's 7 % slower; docs/BENCHMARKS.md).
  const std::size_t sample_capacity = std::size_t(
      std::clamp<std::uint64_t>(options.memory_bytes / (8 * sizeof(Vec3)), 1 << 16, 1 << 21));
  in.sample.reserve(std::min<std::size_t>(sample_capacity, 1 << 16));
  std::mt19937_64 random(0x7e7a9a9e);

  // In input order (ids, part numbers and the sample do not depend on the threads).
  auto add_soup = [&](LoadedSoup& loaded) {
    summary.degenerate_dropped += loaded.degenerate_dropped;
    summary.files_read += loaded.files_read;
    const auto part_offset = std::uint32_t(in.part_names.size());
    for (const auto& name : loaded.soup.part_names) in.part_names.push_back(name);
    if (loaded.soup.part_names.empty()) in.part_names.push_back("part" + std::to_string(part_offset));
    if (in.components.size() + loaded.components.size() >= kInteriorUndecided)
      throw InputError("the inputs hold more than 2^32 - 2 connected components");
    const auto component_offset = std::uint32_t(in.components.size());
    for (SurfaceComponent& c : loaded.components) {
      c.part += part_offset;
      in.bounds.extend(c.bounds);
      in.components.push_back(c);
    }
    in.soups.append(loaded.soup, component_offset);
    if (!in.soups.spilled() && (in.soups.held_bytes() > held_limit || options.force_spill))
      in.soups.spill_to(spill_path(spill_folder, "triangles"));
    for (std::size_t t = 0; t < loaded.centroids.size(); ++t, ++in.seen) {
      if (in.sample.size() < sample_capacity) {
        in.sample.push_back(loaded.centroids[t]);
      } else {
        const std::uint64_t slot = std::uniform_int_distribution<std::uint64_t>(0, in.seen)(random);
        if (slot < sample_capacity) in.sample[slot] = loaded.centroids[t];
      }
    }
  };

  // One part file at a time per thread: the ingest never holds the assembly.
  const std::vector<InputPiece> jobs = input_pieces(inputs);
  // Parsing, edge parity, bounds and centroids run on all threads, a few soups at once; the
  // soups are appended in input order on one.
  Progress progress("reading parts", jobs.size(), options.progress);
  const std::size_t in_flight =
      ingest_depth(jobs, options.memory_bytes, std::size_t(tbb::this_task_arena::max_concurrency()));
  produce_in_parallel_consume_in_order(
      jobs.size(), in_flight, [&](std::size_t j) { return std::make_shared<LoadedSoup>(load_soup(jobs[j])); },
      [&](const std::shared_ptr<LoadedSoup>& loaded) {
        add_soup(*loaded);
        progress.advance();
      });
  progress.finish();
  summary.triangles_read = in.seen;
  summary.parts = in.part_names.size();
  summary.components = in.components.size();
  if (in.seen == 0) throw InputError("the inputs hold no triangle (after dropping degenerate ones)");
}

// The interiors: each tet's reference point classified against the closed components, as CSR
// tables by tet (see docs/FORMAT.md), exactly, by vertical ray parity (RayParity.h) over one
// stream of the records per pass.
struct Interiors {
  std::vector<double> reference_points;  // 3 per tet; NaN for a tet without one
  std::vector<std::uint64_t> offsets;    // tet_count + 1
  std::vector<std::uint32_t> components; // kInteriorUndecided marks an undecided tet
  bool stored = false;
};

// A tet whose inside could not be decided: the runtime would answer "unknown" there, and
// containment could be missed, so the preprocess stops unless the user accepts it.
[[noreturn]] void throw_undecided(const Ingest& in, const TetMesh& mesh, std::uint32_t tet, std::uint32_t component) {
  const auto c = mesh.corners(tet);
  char corner[128];
  std::snprintf(corner, sizeof corner, "(first corner %.9g, %.9g, %.9g)", c[0][0], c[0][1], c[0][2]);
  const std::string where = "tet " + std::to_string(tet) + " " + corner;
  if (component == kInteriorUndecided)
    throw InputError("interiors: " + where + " has no point strictly inside it to classify; pass "
                     "--accept-undecided to store it as undecided (containment there is then unknown)");
  throw InputError("interiors: every reference point tried in " + where + " lies on the surface of closed component " +
                   std::to_string(component) + " of part '" + in.part_names[in.components[component].part] +
                   "'; pass --accept-undecided to store the tet as undecided (containment there is then unknown)");
}

Interiors classify_interiors(Ingest& in, const TetMesh& mesh, const PreprocessOptions& options,
                             PreprocessSummary& summary) {
  Interiors result;
  const std::size_t components = in.components.size();
  std::vector<bool> closed(components);
  for (std::size_t c = 0; c < components; ++c) {
    closed[c] = in.components[c].closed;
    summary.closed_components += closed[c];
  }
  if (!options.interiors) return result;
  if (summary.closed_components == 0) {
    summary.interiors = "none closed";
    return result;
  }
  const std::size_t tet_count = mesh.tet_count();
  std::vector<Vec3> points(tet_count);
  // Bytes, not vector<bool>: the parallel loop writes neighbouring entries.
  std::vector<std::uint8_t> has_point(tet_count, 0);
  result.reference_points.resize(3 * tet_count);
  tbb::parallel_for(std::size_t(0), tet_count, [&](std::size_t t) {
    const auto reference = walk_reference_point(mesh, std::uint32_t(t));
    has_point[t] = reference.has_value();
    points[t] = reference ? *reference : mesh.vertices[mesh.tets[t][0]];
    for (int a = 0; a < 3; ++a)
      result.reference_points[3 * t + a] =
          reference ? (*reference)[a] : std::numeric_limits<double>::quiet_NaN();
  });
  // A pass classifies against as many components as its (point, component) pairs allow: a quarter of the
  // budget (RayParity holds 29 bytes per pair, the plan as much again).
  const std::uint64_t pairs_per_pass =
      options.interior_pairs_per_pass != 0
          ? options.interior_pairs_per_pass
          : std::max<std::uint64_t>(1, options.memory_bytes / 4 / 64);
  std::vector<std::vector<std::uint32_t>> inside(tet_count);
  std::vector<std::uint8_t> undecided(tet_count, 0);
  // Per tet, a closed component whose surface its last reference point lay on (for the error).
  std::vector<std::uint32_t> on_component(tet_count, kInteriorUndecided);
  std::uint64_t passes = 0;
  // Classifies the given tets' reference points against every closed component whose box holds
  // them (outside a component's box is outside the component).
  auto classify = [&](std::vector<std::uint32_t> tets, bool show_progress) {
    std::sort(tets.begin(), tets.end(),
              [&](std::uint32_t a, std::uint32_t b) { return points[a][0] < points[b][0]; });
    for (const std::uint32_t t : tets) inside[t].clear(), undecided[t] = 0;
    std::vector<std::vector<std::uint32_t>> of_component(components);
    std::vector<std::vector<std::uint32_t>> pass_components(1);
    std::uint64_t pass_pairs = 0;
    for (std::size_t p = 0; p < components; ++p) {
      if (!closed[p]) continue;
      const BoundingBox& b = in.components[p].bounds;
      auto it = std::lower_bound(tets.begin(), tets.end(), b.lo[0],
                                 [&](std::uint32_t t, double x) { return points[t][0] < x; });
      for (; it != tets.end() && points[*it][0] <= b.hi[0]; ++it)
        if (geometry::box_contains(b, points[*it])) of_component[p].push_back(*it);
      if (of_component[p].empty()) continue;
      if (pass_pairs > 0 && pass_pairs + of_component[p].size() > pairs_per_pass) {
        pass_components.emplace_back();
        pass_pairs = 0;
      }
      pass_components.back().push_back(std::uint32_t(p));
      pass_pairs += of_component[p].size();
    }
    if (pass_components.back().empty()) pass_components.pop_back();
    Progress progress("classifying interiors", in.seen * pass_components.size(),
                      options.progress && show_progress);
    for (const auto& pass : pass_components) {
      ++passes;
      std::vector<std::vector<std::uint32_t>> asked(components);
      for (const std::uint32_t p : pass) asked[p] = std::move(of_component[p]);
      RayParity parity(points, asked);
      asked.clear();
      if (!in.soups.spilled()) {
        // In memory: the soups cut into tasks, the triangles of components not asked about skipped
        // before their records are made (blocks of every record, made on one thread, were a
        // third of this stage).
        std::vector<InMemoryTask> tasks = in_memory_tasks(in.soups);
        std::mutex progress_mutex;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tasks.size(), 1),
                          [&](const tbb::blocked_range<std::size_t>& range) {
                            for (std::size_t k = range.begin(); k < range.end(); ++k) {
                              const InMemoryTask& task = tasks[k];
                              for (std::size_t t = task.first; t < task.first + task.count; ++t) {
                                const std::uint32_t component = in.soups.piece_part(task.piece, t);
                                if (parity.wanted(component))
                                  parity.add_triangle(component, in.soups.piece_record(task.piece, t).triangle);
                              }
                              const std::lock_guard lock(progress_mutex);
                              progress.advance(task.count);
                            }
                          });
      } else {
        in.soups.for_each_block(std::size_t(1) << 16, [&](std::span<const TriangleRecord> block) {
          tbb::parallel_for(tbb::blocked_range<std::size_t>(0, block.size(), 2048),
                            [&](const tbb::blocked_range<std::size_t>& range) {
                              for (std::size_t i = range.begin(); i < range.end(); ++i)
                                if (parity.wanted(block[i].part))
                                  parity.add_triangle(block[i].part, block[i].triangle);
                            });
          progress.advance(block.size());
        });
      }
      parity.for_each_answer([&](std::uint32_t t, std::uint32_t p, bool odd, bool on_surface) {
        if (on_surface)
          undecided[t] = 1, on_component[t] = p;
        else if (odd)
          inside[t].push_back(p);
      });
    }
    progress.finish();
  };
  std::vector<std::uint32_t> all(tet_count);
  for (std::size_t t = 0; t < tet_count; ++t) all[t] = std::uint32_t(t);
  classify(std::move(all), true);
  const std::uint64_t first_passes = passes;
  // A reference point on a closed component's surface is replaced by another point strictly inside
  // its tet and classified again, in passes of its own (a tet's point must be the same for
  // every component).
  constexpr std::array<std::array<double, 4>, 3> kOtherPoints{
      {{0.31, 0.23, 0.27, 0.19}, {0.17, 0.37, 0.21, 0.25}, {0.29, 0.13, 0.39, 0.19}}};
  std::uint64_t moved = 0;
  for (const auto& w : kOtherPoints) {
    std::vector<std::uint32_t> retry;
    for (std::size_t t = 0; t < tet_count; ++t) {
      if (undecided[t] == 0) continue;
      const auto c = mesh.corners(t);
      Vec3 q;
      for (int a = 0; a < 3; ++a)
        q[a] = w[0] * c[0][a] + w[1] * c[1][a] + w[2] * c[2][a] + w[3] * c[3][a];
      if (geometry::locate_in_tetrahedron(q, c).position != geometry::TetrahedronPosition::inside)
        continue;
      points[t] = q;
      for (int a = 0; a < 3; ++a) result.reference_points[3 * t + a] = q[a];
      retry.push_back(std::uint32_t(t));
      ++moved;
    }
    if (retry.empty()) break;
    classify(std::move(retry), false);
  }

  result.offsets.reserve(tet_count + 1);
  result.offsets.push_back(0);
  for (std::size_t t = 0; t < tet_count; ++t) {
    if (!has_point[t] || undecided[t] != 0) {
      if (!options.accept_undecided) throw_undecided(in, mesh, std::uint32_t(t), on_component[t]);
      result.components.push_back(kInteriorUndecided);
      ++summary.interior_undecided;
    } else {
      std::sort(inside[t].begin(), inside[t].end());
      result.components.insert(result.components.end(), inside[t].begin(), inside[t].end());
      if (!inside[t].empty()) ++summary.interior_tets;
    }
    result.offsets.push_back(result.components.size());
  }
  result.stored = true;
  summary.interiors =
      "stored (" + std::to_string(first_passes) + (first_passes == 1 ? " pass" : " passes") + ")";
  if (moved > 0)
    summary.interiors +=
        "; " + std::to_string(moved) + " reference points on a surface moved and classified again";
  return result;
}

// The components table (docs/FORMAT.md): each component's part, closedness and box.
void write_components(IndexWriter& writer, const std::vector<SurfaceComponent>& components) {
  std::vector<std::uint32_t> part;
  std::vector<std::uint8_t> closed;
  std::vector<double> bounds;
  part.reserve(components.size());
  closed.reserve(components.size());
  bounds.reserve(6 * components.size());
  for (const SurfaceComponent& c : components) {
    part.push_back(c.part);
    closed.push_back(c.closed ? 1 : 0);
    bounds.insert(bounds.end(), c.bounds.lo.begin(), c.bounds.lo.end());
    bounds.insert(bounds.end(), c.bounds.hi.begin(), c.bounds.hi.end());
  }
  writer.write_table(schema::table::component_part, std::span<const std::uint32_t>(part));
  writer.write_table(schema::table::component_closed, std::span<const std::uint8_t>(closed));
  writer.write_table(schema::table::component_bounds, std::span<const double>(bounds));
}

}  // namespace

std::string source_line(const std::filesystem::path& input, const std::filesystem::path& index) {
  std::error_code error;
  const std::filesystem::path absolute = std::filesystem::absolute(input, error);
  std::filesystem::path from_index =
      std::filesystem::relative(absolute, std::filesystem::absolute(index, error).parent_path(), error);
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
  constexpr std::uint64_t kMinimum = 4096, kLeaves = 12'000;  // 12,000 leaves: about 100k tets
  return std::size_t(std::max(kMinimum, (triangles + kLeaves - 1) / kLeaves));
}

PreprocessSummary preprocess(const std::vector<std::filesystem::path>& inputs,
                             const std::filesystem::path& output,
                             const PreprocessOptions& options) {
  if (inputs.empty()) throw InputError("no input given");
  check_outputs(std::span<const std::filesystem::path>(&output, 1), inputs);
  const std::size_t stale = remove_stale_temporaries(output).size();
  if (options.memory_bytes < (std::uint64_t(16) << 20))
    throw InputError("--memory " + format_byte_size(options.memory_bytes) +
                     " is below the 16 MiB the pipeline needs to work");
  const auto start = Clock::now();
  const unsigned threads = options.threads == 0 ? unsigned(tbb::info::default_concurrency()) : options.threads;
  tbb::global_control thread_limit(tbb::global_control::max_allowed_parallelism, threads);

  PreprocessSummary summary;
  summary.output = output;
  summary.memory_budget_bytes = options.memory_bytes;
  summary.stale_temporaries_removed = stale;
  summary.resident_at_start_bytes = resident_bytes();
  summary.precision = std::string(to_string(options.precision));
  summary.compression = std::string(to_string(options.compression));
  const std::filesystem::path spill_folder =
      !options.spill_folder.empty() ? options.spill_folder
                                    : std::filesystem::absolute(output).parent_path();

  // The writer's temporary file is removed if anything below throws.
  IndexWriter writer(output, {.compression = options.compression});

  // 1. Ingest.
  Ingest in;
  {
    StageClock clock(summary, "ingest");
    ingest(inputs, options, spill_folder, in, summary);
    clock.stop();
  }
  const std::uint64_t triangle_count = in.seen;

  // 2. Sample and 3. coarse mesh.
  TetMesh mesh;
  SamplingOptions sampling;
  {
    StageClock clock(summary, "coarse mesh");
    // The sample stands for all triangles: scale the leaf size to its share.
    const double share = double(in.sample.size()) / double(triangle_count);
    summary.region_triangles =
        options.region_triangles != 0 ? options.region_triangles : auto_region_triangles(triangle_count);
    sampling.leaf_triangles = std::max<std::size_t>(1, std::size_t(std::llround(double(summary.region_triangles) * share)));
    // Reorders the sample (the buckets' estimate below takes any every-stride-th of it).
    const std::vector<Vec3> sites = sample_sites(in.sample, in.bounds, sampling);
    summary.sites = sites.size();
    mesh = build_coarse_mesh(sites);
    summary.regions = mesh.tet_count();
    clock.stop();
  }
  const std::size_t tet_count = mesh.tet_count();
  // The box the coarse mesh covers: Morton codes of tets and sample points are taken in it.
  const MortonGrid mesh_grid(enlarged_bounds(in.bounds, sampling.margin));

  Interiors interiors;
  {
    StageClock clock(summary, "interiors");
    interiors = classify_interiors(in, mesh, options, summary);
    clock.stop();
  }

  // Tets in Morton order of their centroids: neighbouring shards sit side by side on disk.
  std::vector<std::uint32_t> order(tet_count), rank(tet_count);
  {
    std::vector<std::uint64_t> code(tet_count);
    tbb::parallel_for(std::size_t(0), tet_count, [&](std::size_t t) {
      const auto c = mesh.corners(t);
      const Vec3 mid{(c[0][0] + c[1][0] + c[2][0] + c[3][0]) / 4, (c[0][1] + c[1][1] + c[2][1] + c[3][1]) / 4,
                     (c[0][2] + c[1][2] + c[2][2] + c[3][2]) / 4};
      code[t] = mesh_grid.code(mid);
    });
    for (std::size_t t = 0; t < tet_count; ++t) order[t] = std::uint32_t(t);
    tbb::parallel_sort(order.begin(), order.end(),
                       [&](std::uint32_t a, std::uint32_t b) { return code[a] < code[b] || (code[a] == code[b] && a < b); });
    for (std::size_t r = 0; r < tet_count; ++r) rank[order[r]] = std::uint32_t(r);
  }

  // Buckets of consecutive tets (in Morton order) whose estimated triangle copies fit in a
  // third of the budget; the estimate locates the sampled centroids, with room for duplicates.
  std::vector<std::uint32_t> bucket_of(tet_count, 0);
  std::size_t bucket_count = 1;
  {
    StageClock clock(summary, "buckets");
    const double copies_per_sample = 1.5 * double(triangle_count) / double(in.sample.size());
    const double capacity = double(options.memory_bytes / 3) / double(sizeof(TriangleRecord));
    if (copies_per_sample * double(in.sample.size()) > capacity) {
      // At most 2^18 of the sampled centroids (every stride-th) say enough about the loads.
      const std::size_t stride = (in.sample.size() + (std::size_t(1) << 18) - 1) >> 18;
      std::vector<std::pair<std::uint64_t, Vec3>> coded;
      coded.reserve(in.sample.size() / stride + 1);
      for (std::size_t i = 0; i < in.sample.size(); i += stride)
        coded.emplace_back(mesh_grid.code(in.sample[i]), in.sample[i]);
      tbb::parallel_sort(coded.begin(), coded.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
      // Located in Morton order, each walk starting next to the last one, in fixed chunks (the
      // counts do not depend on the threads).
      std::vector<std::atomic<std::uint32_t>> located_here(tet_count);
      constexpr std::size_t kChunk = 4096;
      tbb::parallel_for(std::size_t(0), (coded.size() + kChunk - 1) / kChunk, [&](std::size_t chunk) {
        std::uint32_t hint = 0;
        for (std::size_t i = chunk * kChunk; i < std::min(coded.size(), (chunk + 1) * kChunk); ++i) {
          const WalkResult located = locate_point(mesh, hint, coded[i].second);
          if (located.tet == TetMesh::no_neighbour) continue;
          hint = located.tet;
          located_here[located.tet].fetch_add(1, std::memory_order_relaxed);
        }
      });
      std::vector<double> estimate(tet_count, 0.0);
      for (std::size_t t = 0; t < tet_count; ++t)
        estimate[t] = copies_per_sample * double(stride) * double(located_here[t].load());
      double load = 0;
      std::uint32_t bucket = 0;
      for (const std::uint32_t t : order) {
        if (load > 0 && load + estimate[t] > capacity) ++bucket, load = 0;
        load += estimate[t];
        bucket_of[t] = bucket;
      }
      bucket_count = bucket + 1;
    }
    clock.stop();
  }
  summary.buckets = bucket_count;
  std::vector<Vec3>().swap(in.sample);

  // 4. Bin: every triangle into every tet it meets, appended to its tets' bucket spills.
  // While the ingested soups are in memory (within a quarter of the budget, at about 30 bytes a
  // triangle), the copies are (id, tet) pairs in memory too, 12 bytes a copy: about half of
  // what the soups take at the usual 1.2-1.4 copies a triangle.
  std::vector<CopyBucket> buckets;
  buckets.reserve(bucket_count);
  for (std::size_t b = 0; b < bucket_count; ++b)
    buckets.emplace_back(spill_path(spill_folder, "bucket" + std::to_string(b)), in.soups);
  summary.spilled = in.soups.spilled();
  {
    StageClock clock(summary, "binning");
    // The copies as the buckets keep them: (id, tet) pairs while the soups are in memory (a
    // record of 88 bytes made and then read back for each copy was a serial tenth of binning),
    // else records for the spill files.
    const bool pairs = !in.soups.spilled();  // what the buckets keep (CopyBucket)
    struct ThreadState {
      BinningScratch scratch;
      std::vector<std::uint32_t> tets;
      std::vector<std::vector<TriangleRecord>> out;
      // A task's (in-memory soups): its records, their Morton order, and the tets of the
      // triangle at each Morton position (flat, from start[position]) with each triangle's
      // position.
      std::vector<TriangleRecord> records;
      std::vector<std::uint64_t> order, radix_scratch;
      std::vector<std::uint32_t> flat, start, position;
    };
    tbb::enumerable_thread_specific<ThreadState> states([&] {
      ThreadState s;
      if (!pairs) s.out.resize(bucket_count);
      return s;
    });
    const std::size_t block_records = std::clamp<std::size_t>(options.memory_bytes / 12 / sizeof(TriangleRecord),
                                                              1024, 0xffff'ffffu);  // indices in 32 bits
    Progress progress("binning triangles", triangle_count, options.progress);
    // A block's triangles are binned in the Morton order of their centroids: consecutive ones
    // then mostly share a tet, where each point location starts (in input order half of them
    // needed a walk, of 5.6 tets on average, at 10M).
    // Only the order of the work changes (binning is exact whatever the order): the top 32
    // bits of the code (10-11 per axis) and the triangle's index in one word, sorted by a
    // radix sort (a comparison sort of (code, index) pairs took a tenth of binning's CPU).
    const MortonGrid model_grid(in.bounds);
    const auto morton_word = [&](const TriangleRecord& record, std::size_t i) {
      return (model_grid.code(centroid(record.triangle)) >> 31 << 32) | std::uint64_t(i);
    };
    if (pairs) {
      // Soups in memory: the pieces (one a soup) cut into tasks of at most kTaskTriangles, each
      // binned by one thread in its own Morton order, its pairs emitted in id order and
      // appended in task order: each bucket then holds its pairs in id order, which its
      // counting sort by tet keeps (sorting each tet's pairs by id was 2 % of the 10M CPU).
      // Binning block by block (a block per soup, 745 at 10M) made both threads wait at every
      // block's end while one built the next block and appended the last one's copies.
      const std::vector<InMemoryTask> tasks = in_memory_tasks(in.soups);
      struct TaskPairs {
        std::vector<std::vector<CopyPair>> by_bucket;
        std::size_t triangles = 0;
      };
      produce_in_parallel_consume_in_order(
          tasks.size(), 4 * std::size_t(tbb::this_task_arena::max_concurrency()),
                  [&](std::size_t k) {
                    ThreadState& s = states.local();
                    const InMemoryTask& task = tasks[k];
                    s.records.resize(task.count);
                    s.order.resize(task.count);
                    for (std::size_t i = 0; i < task.count; ++i) {
                      s.records[i] = in.soups.piece_record(task.piece, task.first + i);
                      s.order[i] = morton_word(s.records[i], i);
                    }
                    sort_by_high_word(s.order, s.radix_scratch);
                    s.flat.clear();
                    s.start.resize(task.count + 1);
                    s.position.resize(task.count);
                    for (std::size_t p = 0; p < task.count; ++p) {
                      const std::size_t i = s.order[p] & 0xffff'ffffu;
                      s.position[i] = std::uint32_t(p);
                      s.start[p] = std::uint32_t(s.flat.size());
                      s.tets.clear();
                      bin_triangle(mesh, s.records[i].triangle, s.scratch, s.tets);
                      s.flat.insert(s.flat.end(), s.tets.begin(), s.tets.end());
                    }
                    s.start[task.count] = std::uint32_t(s.flat.size());
                    auto out = std::make_shared<TaskPairs>();
                    out->by_bucket.resize(bucket_count);
                    out->triangles = task.count;
                    for (std::size_t i = 0; i < task.count; ++i) {
                      const std::uint32_t p = s.position[i];
                      for (std::uint32_t j = s.start[p]; j < s.start[p + 1]; ++j)
                        out->by_bucket[bucket_of[s.flat[j]]].push_back({s.records[i].id, s.flat[j]});
                    }
                    return out;
                  },
                  [&](const std::shared_ptr<TaskPairs>& out) {
                    for (std::size_t b = 0; b < bucket_count; ++b)
                      buckets[b].append(std::span<const CopyPair>(out->by_bucket[b]));
                    progress.advance(out->triangles);
                  });
    }
    // Soups spilled: blocks read back from the spill file, each binned by all threads, the
    // copies as records.
    std::vector<std::uint64_t> binning_order, radix_scratch;
    if (!pairs) in.soups.for_each_block(block_records, [&](std::span<const TriangleRecord> block) {
      binning_order.resize(block.size());
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, block.size(), 4096),
                        [&](const tbb::blocked_range<std::size_t>& range) {
                          for (std::size_t i = range.begin(); i < range.end(); ++i)
                            binning_order[i] = morton_word(block[i], i);
                        });
      sort_by_high_word(binning_order, radix_scratch);
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, block.size(), 256),
                        [&](const tbb::blocked_range<std::size_t>& range) {
                          ThreadState& s = states.local();
                          for (std::size_t k = range.begin(); k < range.end(); ++k) {
                            const std::size_t i = binning_order[k] & 0xffff'ffffu;
                            s.tets.clear();
                            bin_triangle(mesh, block[i].triangle, s.scratch, s.tets);
                            for (const std::uint32_t t : s.tets) {
                              TriangleRecord copy = block[i];
                              copy.tet = t;
                              s.out[bucket_of[t]].push_back(copy);
                            }
                          }
                        });
      for (auto& s : states) {
        for (std::size_t b = 0; b < bucket_count; ++b) {
          buckets[b].append(std::span<const TriangleRecord>(s.out[b]));
          s.out[b].clear();
        }
      }
      progress.advance(block.size());
    });
    progress.finish();
    for (auto& s : states) summary.exact_tet_tests += s.scratch.tet_tests;
    // The soups go now, unless the buckets make their copies' records from them.
    if (in.soups.spilled()) in.soups.clear();
    clock.stop();
  }

  // 5. Shards, bucket by bucket, and 6. the index.
  std::vector<std::uint32_t> tet_shard(tet_count, TetMesh::no_neighbour);
  std::vector<std::uint32_t> shard_tet, shard_triangles;
  std::vector<std::uint8_t> shard_kind;
  std::vector<double> shard_bounds;  // 6 per shard: lo xyz, hi xyz, enclosing the stored triangles
  {
    StageClock clock(summary, "shards");
    const double query_extent = options.query_extent > 0 ? options.query_extent : [&] {
      const Vec3 size = in.bounds.size();
      return 0.05 * std::max({size[0], size[1], size[2]});
    }();
    summary.query_extent = query_extent;
    const ShardCostModel cost_model;
    Progress progress("building shards", tet_count, options.progress);
    for (auto& bucket : buckets) {
      BucketCopies copies = bucket.take();
      // The copies in (tet rank, id) order: each tet's then lie side by side.
      const std::vector<std::size_t> group_start = copies.order_by_tet(rank);
      const std::size_t groups = group_start.size() - 1;
      // Built and compressed on all threads, appended in order on one while the others build
      // on: a pipeline with a few shards in flight (the bucket's shards are never all held).
      struct Ready {
        BuiltShard built;  // its payload freed once encoded
        std::uint64_t payload_bytes = 0;
        EncodedShard encoded;
        BoundingBox bounds;
        std::uint32_t tet = 0;
      };
      produce_in_parallel_consume_in_order(
          groups, 4 * std::size_t(tbb::this_task_arena::max_concurrency()),
                  [&](std::size_t g) {
                    auto ready = std::make_shared<Ready>();
                    const std::size_t first = group_start[g], last = group_start[g + 1];
                    std::vector<geometry::Triangle> triangles;
                    std::vector<std::uint64_t> ids;
                    std::vector<std::uint32_t> parts;
                    triangles.reserve(last - first);
                    ids.reserve(last - first);
                    parts.reserve(last - first);
                    copies.gather(first, last, triangles, ids, parts);
                    for (const geometry::Triangle& t : triangles)
                      for (const auto& p : t) ready->bounds.extend(p);
                    ready->tet = copies.tet(first);
                    const ShardTriangles region{triangles, ids, parts};
                    if (options.shard == ShardChoice::automatic) {
                      ShardCostReport costs =
                          estimate_shard_costs(region, query_extent, options.precision, cost_model);
                      ready->built = std::move(costs.chosen == ShardKind::grid ? costs.grid.built : costs.rtree.built);
                    } else {
                      ready->built = build_shard(
                          region, options.shard == ShardChoice::grid ? ShardKind::grid : ShardKind::rtree,
                          options.precision);
                    }
                    ready->encoded = encode_shard(ready->built.payload, writer.options());
                    ready->payload_bytes = ready->built.payload.size();
                    std::vector<std::byte>().swap(ready->built.payload);
                    return ready;
                  },
                  [&](const std::shared_ptr<Ready>& ready) {
                    const BuiltShard& built = ready->built;
                    // Stored vertices lie within the shard's rounding distance of the input
                    // ones: grow the input box by it (and a few ulps) so the runtime can skip
                    // shards unread.
                    BoundingBox bounds = ready->bounds;
                    for (int a = 0; a < 3; ++a) {
                      const double grow = built.max_rounding_distance +
                                          0x1p-50 * std::max(std::fabs(bounds.lo[a]), std::fabs(bounds.hi[a]));
                      bounds.lo[a] -= grow;
                      bounds.hi[a] += grow;
                    }
                    shard_bounds.insert(shard_bounds.end(), {bounds.lo[0], bounds.lo[1], bounds.lo[2], bounds.hi[0],
                                                             bounds.hi[1], bounds.hi[2]});
                    const std::uint32_t shard = writer.append_encoded_shard(ready->encoded);
                    tet_shard[ready->tet] = shard;
                    shard_tet.push_back(ready->tet);
                    shard_kind.push_back(std::uint8_t(built.kind));
                    shard_triangles.push_back(built.triangle_count);
                    summary.stored_triangles += built.triangle_count;
                    summary.shard_payload_bytes += ready->payload_bytes;
                    summary.max_rounding_distance = std::max(summary.max_rounding_distance, built.max_rounding_distance);
                    (built.kind == ShardKind::grid ? summary.grid_shards : summary.rtree_shards) += 1;
                    summary.float_shards += built.precision == StoredPrecision::float32;
                    progress.advance();
                  });
    }
    progress.finish();
    in.soups.clear();
    summary.empty_regions = tet_count - shard_tet.size();
    summary.duplication_factor = double(summary.stored_triangles) / double(triangle_count);
    clock.stop();
  }
  {
    StageClock clock(summary, "write index");
    writer.write_mesh(mesh);
    writer.write_table(schema::table::tet_shard, std::span<const std::uint32_t>(tet_shard));
    writer.write_table(schema::table::shard_tet, std::span<const std::uint32_t>(shard_tet));
    writer.write_table(schema::table::shard_kind, std::span<const std::uint8_t>(shard_kind));
    writer.write_table(schema::table::shard_triangles,
                       std::span<const std::uint32_t>(shard_triangles));
    writer.write_table(schema::table::shard_bounds, std::span<const double>(shard_bounds));
    write_components(writer, in.components);
    if (interiors.stored) {
      writer.write_table(schema::table::reference_points,
                         std::span<const double>(interiors.reference_points));
      writer.write_table(schema::table::interior_offsets,
                         std::span<const std::uint64_t>(interiors.offsets));
      writer.write_table(schema::table::interior_components,
                         std::span<const std::uint32_t>(interiors.components));
    }
    IndexHeader header;
    header.precision = summary.precision;
    header.input_triangles = triangle_count;
    header.stored_triangles = summary.stored_triangles;
    header.region_count = tet_count;
    header.shard_count = shard_tet.size();
    header.max_rounding_distance = summary.max_rounding_distance;
    header.bounds = in.bounds;
    std::string source;
    for (const auto& input : inputs) source += (source.empty() ? "" : "\n") + source_line(input, output);
    header.source = source;
    header.created_by = "tetrapage preprocess";
    summary.seconds = std::chrono::duration<double>(Clock::now() - start).count();
    header.build_report_json = summary.to_json();
    summary.bytes_written = writer.commit(header);
    clock.stop();
  }
  summary.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  summary.peak_resident_bytes = 0;
  for (const auto& stage : summary.stages)
    summary.peak_resident_bytes = std::max(summary.peak_resident_bytes, stage.peak_resident_bytes);
  return summary;
}

std::string PreprocessSummary::to_json() const {
  nlohmann::ordered_json j;
  j["output"] = output.string();
  j["files_read"] = files_read;
  j["parts"] = parts;
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
  j["max_rounding_distance"] = max_rounding_distance;
  j["float_shards"] = float_shards;
  j["query_extent"] = query_extent;
  j["memory_budget_bytes"] = memory_budget_bytes;
  j["components"] = components;
  j["closed_components"] = closed_components;
  j["interiors"] = interiors;
  j["interior_tets"] = interior_tets;
  j["interior_undecided"] = interior_undecided;
  j["buckets"] = buckets;
  j["spilled"] = spilled;
  j["stale_temporaries_removed"] = stale_temporaries_removed;
  j["seconds"] = seconds;
  j["triangles_per_second"] = seconds > 0 ? double(triangles_read) / seconds : 0.0;
  j["peak_rss_bytes"] = peak_resident_bytes;
  j["resident_at_start_bytes"] = resident_at_start_bytes;
  j["budget_exceeded_bytes"] = peak_resident_bytes > memory_budget_bytes ? peak_resident_bytes - memory_budget_bytes : 0;
  auto& stage_list = j["stages"] = nlohmann::ordered_json::array();
  for (const auto& stage : stages)
    stage_list.push_back({{"name", stage.name}, {"seconds", stage.seconds}, {"peak_rss_bytes", stage.peak_resident_bytes}});
  return j.dump(2);
}

std::string PreprocessSummary::to_text() const {
  std::ostringstream text;
  char line[256];
  std::snprintf(line, sizeof line, "triangles read %llu (degenerate dropped %llu) from %llu files, %llu parts\n",
                (unsigned long long)triangles_read, (unsigned long long)degenerate_dropped,
                (unsigned long long)files_read, (unsigned long long)parts);
  text << line;
  std::snprintf(line, sizeof line,
                "regions %llu (empty %llu; %llu triangles per region asked), shards: grid %llu, rtree %llu; "
                "duplication factor %.3f\n",
                (unsigned long long)regions, (unsigned long long)empty_regions, (unsigned long long)region_triangles,
                (unsigned long long)grid_shards, (unsigned long long)rtree_shards, duplication_factor);
  text << line;
  std::snprintf(line, sizeof line, "index %s: %s (%.1f B/triangle, chunks %s), shards decoded %s\n",
                output.string().c_str(), format_byte_size(bytes_written).c_str(),
                triangles_read ? double(bytes_written) / double(triangles_read) : 0.0, compression.c_str(),
                format_byte_size(shard_payload_bytes).c_str());
  text << line << storage_statement(precision, max_rounding_distance) << "; "
       << float_shards << " of " << (grid_shards + rtree_shards) << " shards in 4-byte floats\n";
  std::snprintf(line, sizeof line,
                "components %llu (closed %llu, open %llu); interiors %s (%llu tets inside, %llu undecided)\n",
                (unsigned long long)components, (unsigned long long)closed_components,
                (unsigned long long)(components - closed_components), interiors.c_str(), (unsigned long long)interior_tets,
                (unsigned long long)interior_undecided);
  text << line;
  if (stale_temporaries_removed > 0)
    text << "removed " << stale_temporaries_removed << " temporary index file(s) left beside the output by killed runs\n";
  for (const auto& stage : stages) {
    std::snprintf(line, sizeof line, "  %-12s %8.2f s  peak RSS %s\n", stage.name.c_str(), stage.seconds,
                  format_byte_size(stage.peak_resident_bytes).c_str());
    text << line;
  }
  std::snprintf(line, sizeof line, "total %.2f s (%.2f M triangles/s), peak RSS %s against --memory %s%s\n", seconds,
                seconds > 0 ? double(triangles_read) / seconds / 1e6 : 0.0,
                format_byte_size(peak_resident_bytes).c_str(), format_byte_size(memory_budget_bytes).c_str(),
                spilled ? " (spilled to disk)" : "");
  text << line;
  if (peak_resident_bytes > memory_budget_bytes) {
    // --memory bounds the stages' data; the process itself and the file being read come on top.
    std::snprintf(line, sizeof line,
                  "budget exceeded by %s: the process held %s before any work (libraries, threads), and "
                  "each input file's soup is held whole while it is read\n",
                  format_byte_size(peak_resident_bytes - memory_budget_bytes).c_str(),
                  format_byte_size(resident_at_start_bytes).c_str());
    text << line;
  }
  return text.str();
}

}  // namespace tetrapage
