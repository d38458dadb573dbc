#include "Binning.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <memory>
#include <vector>

#include "MortonGrid.h"
#include "OrderedPipeline.h"
#include "tetrapage/formats/base/Progress.h"
#include "tetrapage/preprocess/TriangleBinning.h"

namespace tetrapage {

namespace {

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

// A block's triangles are binned in the Morton order of their centroids: consecutive ones
// then mostly share a tet, where each point location starts (in input order half of them
// needed a walk, of 5.6 tets on average, at 10M).
// Only the order of the work changes (binning is exact whatever the order): the top 32
// bits of the code (10-11 per axis) and the triangle's index in one word, sorted by a
// radix sort (a comparison sort of (code, index) pairs took a tenth of binning's CPU).
std::uint64_t morton_word(const MortonGrid& model_grid, const TriangleRecord& record,
                          std::size_t i) {
  return (model_grid.code(centroid(record.triangle)) >> 31 << 32) | std::uint64_t(i);
}

struct BinningThreadState {
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
using BinningThreadStates = tbb::enumerable_thread_specific<BinningThreadState>;

// Soups in memory: the pieces (one a soup) cut into tasks of at most kTaskTriangles, each
// binned by one thread in its own Morton order, its pairs emitted in id order and
// appended in task order: each bucket then holds its pairs in id order, which its
// counting sort by tet keeps (sorting each tet's pairs by id was 2 % of the 10M CPU).
// Binning block by block (a block per soup, 745 at 10M) made both threads wait at every
// block's end while one built the next block and appended the last one's copies.
void bin_in_memory_soups(const SoupSpill<TriangleRecord>& soups, const TetMesh& mesh,
                         const MortonGrid& model_grid, std::span<const std::uint32_t> bucket_of,
                         std::span<CopyBucket> buckets, BinningThreadStates& states,
                         Progress& progress) {
  const std::size_t bucket_count = buckets.size();
  const std::vector<InMemoryTask> tasks = in_memory_tasks(soups);
  struct TaskPairs {
    std::vector<std::vector<CopyPair>> by_bucket;
    std::size_t triangles = 0;
  };
  produce_in_parallel_consume_in_order(
      tasks.size(), 4 * std::size_t(tbb::this_task_arena::max_concurrency()),
      [&](std::size_t k) {
        BinningThreadState& s = states.local();
        const InMemoryTask& task = tasks[k];
        s.records.resize(task.count);
        s.order.resize(task.count);
        for (std::size_t i = 0; i < task.count; ++i) {
          s.records[i] = soups.piece_record(task.piece, task.first + i);
          s.order[i] = morton_word(model_grid, s.records[i], i);
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
void bin_spilled_soups(SoupSpill<TriangleRecord>& soups, const TetMesh& mesh,
                       const MortonGrid& model_grid, std::span<const std::uint32_t> bucket_of,
                       std::span<CopyBucket> buckets, std::uint64_t memory_bytes,
                       BinningThreadStates& states, Progress& progress) {
  const std::size_t block_records = std::clamp<std::size_t>(
      memory_bytes / 12 / sizeof(TriangleRecord), 1024, 0xffff'ffffu);  // indices in 32 bits
  std::vector<std::uint64_t> binning_order, radix_scratch;
  soups.for_each_block(block_records, [&](std::span<const TriangleRecord> block) {
    binning_order.resize(block.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, block.size(), 4096),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        for (std::size_t i = range.begin(); i < range.end(); ++i)
                          binning_order[i] = morton_word(model_grid, block[i], i);
                      });
    sort_by_high_word(binning_order, radix_scratch);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, block.size(), 256),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        BinningThreadState& s = states.local();
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
      for (std::size_t b = 0; b < buckets.size(); ++b) {
        buckets[b].append(std::span<const TriangleRecord>(s.out[b]));
        // Freed, not cleared: a block's copies crowd into a few buckets, and capacities kept
        // per bucket and thread added up to the whole model's copies (a 10M-triangle terrain
        // at --memory 568M peaked 190 MiB above the budget in binning).
        std::vector<TriangleRecord>().swap(s.out[b]);
      }
    }
    progress.advance(block.size());
  });
}

}  // namespace

void bin_triangles(IngestedModel& model, const TetMesh& mesh,
                   std::span<const std::uint32_t> bucket_of, std::span<CopyBucket> buckets,
                   const PreprocessOptions& options, PreprocessSummary& summary) {
  // The copies as the buckets keep them: (id, tet) pairs while the soups are in memory (a
  // record of 88 bytes made and then read back for each copy was a serial tenth of binning),
  // else records for the spill files.
  const bool pairs = !model.soups.spilled();  // what the buckets keep (CopyBucket)
  BinningThreadStates states([&] {
    BinningThreadState s;
    if (!pairs) s.out.resize(buckets.size());
    return s;
  });
  Progress progress("binning triangles", model.triangle_count, options.progress,
                    options.on_progress);
  const MortonGrid model_grid(model.bounds);
  if (pairs)
    bin_in_memory_soups(model.soups, mesh, model_grid, bucket_of, buckets, states, progress);
  else
    bin_spilled_soups(model.soups, mesh, model_grid, bucket_of, buckets, options.memory_bytes,
                      states, progress);
  progress.finish();
  for (auto& s : states) summary.exact_tet_tests += s.scratch.tet_tests;
  // The soups go now, unless the buckets make their copies' records from them.
  if (model.soups.spilled()) model.soups.clear();
}

}  // namespace tetrapage
