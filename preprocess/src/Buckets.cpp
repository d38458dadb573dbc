#include "Buckets.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <atomic>
#include <limits>
#include <string>
#include <utility>

#include "SpillPath.h"
#include "tetrapage/runtime/query/MeshWalk.h"

namespace tetrapage {
namespace {

// The estimated copies of each tet: the sampled centroids located, each standing for its
// share of the triangles (`copies_per_sample`, with room for duplicates).
std::vector<double> estimate_copies(const std::vector<Vec3>& sample, double copies_per_sample,
                                    const TetMesh& mesh, const MortonGrid& mesh_grid) {
  const std::size_t tet_count = mesh.tet_count();
  // At most 2^18 of the sampled centroids (every stride-th) say enough about the loads.
  const std::size_t stride = (sample.size() + (std::size_t(1) << 18) - 1) >> 18;
  std::vector<std::pair<std::uint64_t, Vec3>> coded;
  coded.reserve(sample.size() / stride + 1);
  for (std::size_t i = 0; i < sample.size(); i += stride)
    coded.emplace_back(mesh_grid.code(sample[i]), sample[i]);
  tbb::parallel_sort(coded.begin(), coded.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
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
  return estimate;
}

// A counting sort of copies by their tet's rank: where each copy goes (target), and where each
// tet's copies start (with their count last). Stable, on all threads: fixed chunks of the
// copies count their ranks, and each chunk's copies of a rank go after those of the chunks
// before it (done on one thread, this was a serial 0.05 s at the start of the 10M shard stage).
template <class Copy>
std::vector<std::size_t> place_copies_by_tet(const std::vector<Copy>& copies,
                                             std::span<const std::uint32_t> rank,
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
    const std::size_t ranks =
        std::size_t(*std::max_element(chunk_highest.begin(), chunk_highest.end()) - lowest) + 1;
    // next[c * ranks + r]: chunk c's count of rank lowest + r, then where its next one goes.
    std::vector<std::uint32_t> next(chunks * ranks, 0);
    tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
      std::uint32_t* count = next.data() + c * ranks;
      for (std::size_t i = first_of(c); i < first_of(c + 1); ++i)
        ++count[rank[copies[i].tet] - lowest];
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
      for (std::size_t i = first_of(c); i < first_of(c + 1); ++i)
        target[i] = at[rank[copies[i].tet] - lowest]++;
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
    const auto first = values.begin() + std::ptrdiff_t(start[g]),
               last = values.begin() + std::ptrdiff_t(start[g + 1]);
    if (!std::is_sorted(first, last, less)) std::sort(first, last, less);
  });
}

}  // namespace

TetOrder order_tets(const TetMesh& mesh, const MortonGrid& mesh_grid) {
  const std::size_t tet_count = mesh.tet_count();
  TetOrder tets{std::vector<std::uint32_t>(tet_count), std::vector<std::uint32_t>(tet_count)};
  std::vector<std::uint64_t> code(tet_count);
  tbb::parallel_for(std::size_t(0), tet_count, [&](std::size_t t) {
    const auto c = mesh.corners(t);
    const Vec3 mid{(c[0][0] + c[1][0] + c[2][0] + c[3][0]) / 4,
                   (c[0][1] + c[1][1] + c[2][1] + c[3][1]) / 4,
                   (c[0][2] + c[1][2] + c[2][2] + c[3][2]) / 4};
    code[t] = mesh_grid.code(mid);
  });
  for (std::size_t t = 0; t < tet_count; ++t) tets.order[t] = std::uint32_t(t);
  tbb::parallel_sort(tets.order.begin(), tets.order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return code[a] < code[b] || (code[a] == code[b] && a < b);
  });
  for (std::size_t r = 0; r < tet_count; ++r) tets.rank[tets.order[r]] = std::uint32_t(r);
  return tets;
}

BucketPlan plan_buckets(const IngestedModel& model, const TetMesh& mesh,
                        const MortonGrid& mesh_grid, std::span<const std::uint32_t> tet_order,
                        const PreprocessOptions& options) {
  BucketPlan plan;
  plan.bucket_of.assign(mesh.tet_count(), 0);
  const double copies_per_sample = 1.5 * double(model.triangle_count) / double(model.sample.size());
  const double capacity = double(options.memory_bytes / 3) / double(sizeof(TriangleRecord));
  if (copies_per_sample * double(model.sample.size()) <= capacity) return plan;
  const std::vector<double> estimate =
      estimate_copies(model.sample, copies_per_sample, mesh, mesh_grid);
  double load = 0;
  std::uint32_t bucket = 0;
  for (const std::uint32_t t : tet_order) {
    if (load > 0 && load + estimate[t] > capacity) ++bucket, load = 0;
    load += estimate[t];
    plan.bucket_of[t] = bucket;
  }
  plan.bucket_count = bucket + 1;
  return plan;
}

std::vector<std::size_t> BucketCopies::order_by_tet(std::span<const std::uint32_t> rank) {
  std::vector<std::uint32_t> target;
  if (!soups_) {
    const std::vector<std::size_t> start = place_copies_by_tet(records_, rank, target);
    order_.resize(records_.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, records_.size(), 1 << 16),
                      [&](const auto& range) {
                        for (std::size_t i = range.begin(); i < range.end(); ++i)
                          order_[target[i]] = std::uint32_t(i);
                      });
    sort_groups(order_, start,
                [&](std::uint32_t a, std::uint32_t b) { return records_[a].id < records_[b].id; });
    return start;
  }
  const std::vector<std::size_t> start = place_copies_by_tet(pairs_, rank, target);
  std::vector<CopyPair> placed(pairs_.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pairs_.size(), 1 << 16),
                    [&](const auto& range) {
                      for (std::size_t i = range.begin(); i < range.end(); ++i)
                        placed[target[i]] = pairs_[i];
                    });
  pairs_.swap(placed);
  sort_groups(pairs_, start, [](const CopyPair& a, const CopyPair& b) { return a.id < b.id; });
  return start;
}

void BucketCopies::gather(std::size_t first, std::size_t last,
                          std::vector<geometry::Triangle>& triangles,
                          std::vector<std::uint64_t>& ids,
                          std::vector<std::uint32_t>& parts) const {
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

BucketCopies CopyBucket::take() {
  BucketCopies copies =
      records_ ? BucketCopies(records_->read_all()) : BucketCopies(std::move(pairs_), *soups_);
  records_.reset();
  std::vector<CopyPair>().swap(pairs_);
  return copies;
}

std::vector<CopyBucket> make_buckets(std::size_t bucket_count,
                                     const std::filesystem::path& spill_folder,
                                     const SoupSpill<TriangleRecord>& soups) {
  std::vector<CopyBucket> buckets;
  buckets.reserve(bucket_count);
  for (std::size_t b = 0; b < bucket_count; ++b)
    buckets.emplace_back(spill_path(spill_folder, "bucket" + std::to_string(b)), soups);
  return buckets;
}

}  // namespace tetrapage
