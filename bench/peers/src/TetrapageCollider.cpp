#include "tetrapage/bench/TetrapageCollider.h"

#include <algorithm>

#include "tetrapage/formats/base/ByteSize.h"
#include "tetrapage/formats/base/Error.h"

namespace tetrapage {
namespace {

// "Everything in memory": a budget no index of this machine reaches, so nothing is evicted.
constexpr std::uint64_t kUnboundedBudget = std::uint64_t(1) << 40;

std::shared_ptr<const CollisionIndex> open_index(const std::filesystem::path& path,
                                                 const TetrapageColliderOptions& options) {
  CollisionIndexOptions index_options;
  index_options.memory_budget_bytes = options.memory_budget_bytes.value_or(kUnboundedBudget);
  index_options.prefetch = options.prefetch;
  auto index = std::make_shared<const CollisionIndex>(path, index_options);
  if (!options.memory_budget_bytes) index->preload();
  return index;
}

}  // namespace

TetrapageCollider::TetrapageCollider(const std::filesystem::path& index, TriangleSoup object,
                                     TetrapageColliderOptions options)
    : options_(options), index_(open_index(index, options_)), object_(index_, std::move(object)) {
  preload_page_ins_ = index_->cache().counters().page_ins;
  index_->cache().reset_counters();  // the flight's figures start here
}

std::string TetrapageCollider::description() const {
  std::string text = "tetrapage runtime, exact, ";
  if (!options_.memory_budget_bytes) return text + "in memory (every shard preloaded)";
  text += "paged, budget " + format_byte_size(*options_.memory_budget_bytes) + ", cold cache";
  return text + (options_.prefetch ? ", prefetch thread" : ", no prefetch");
}

bool TetrapageCollider::collides(const Pose& pose) {
  object_.query(pose, query_options_, result_);
  const StepCounters& c = result_.counters;
  totals_.add(c);
  locate_seconds_ += c.locate_seconds;
  search_seconds_ += c.search_seconds;
  shard_seconds_ += c.shard_seconds;
  test_seconds_ += c.test_seconds;
  return result_.collides;
}

std::uint64_t TetrapageCollider::structure_bytes() const { return index_->cache().counters().resident_bytes; }

nlohmann::json TetrapageCollider::figures() const {
  const ShardCacheCounters cache = index_->cache().counters();
  const double lookups = double(cache.hits + cache.misses);
  nlohmann::json report = {{"budget_bytes", index_->options().memory_budget_bytes},
          {"index_shard_bytes", index_->total_shard_bytes()},
          {"shards", index_->shard_count()},
          {"preload_page_ins", preload_page_ins_},
          {"page_ins", cache.page_ins},
          {"bytes_read", cache.bytes_loaded},
          {"cache_hit_rate", lookups > 0 ? double(cache.hits) / lookups : 1.0},
          {"peak_resident_shard_bytes", cache.peak_resident_bytes},
          {"page_in_latency_us", {{"p50", cache.page_in_p50_us}, {"p99", cache.page_in_p99_us},
                                  {"max", cache.page_in_max_us}}},
          {"phase_seconds", {{"locate", locate_seconds_}, {"search", search_seconds_}, {"shards", shard_seconds_},
                             {"tests", test_seconds_}}}};
  totals_.add_to(report);
  return report;
}

}  // namespace tetrapage
