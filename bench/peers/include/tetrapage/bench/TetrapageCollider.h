#pragma once
/// @file TetrapageCollider.h
/// tetrapage's runtime as a peer: a CollisionIndex and a FlyingObject answering the exact mode,
/// first hit. Either everything in memory (every shard paged in while building, under a budget
/// above the index's shard bytes, so that the flight pages nothing in) or paged under a budget,
/// starting from an empty cache.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>

#include "tetrapage/bench/PeerCollider.h"
#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/tools/StepTotals.h"

namespace tetrapage {

struct TetrapageColliderOptions {
  /// The shard budget of a paged run; none: everything in memory, preloaded.
  std::optional<std::uint64_t> memory_budget_bytes;
  /// The background prefetcher (a second thread): off for single-threaded comparisons.
  bool prefetch = false;
};

class TetrapageCollider final : public PeerCollider {
 public:
  /// Opens the index and builds the flying object; in memory, also pages in every shard.
  /// @throw what CollisionIndex, FlyingObject and the shard cache throw.
  TetrapageCollider(const std::filesystem::path& index, TriangleSoup object, TetrapageColliderOptions options);

  std::string description() const override;
  CollisionQuestion question() const override { return CollisionQuestion::surfaces_or_inside; }
  bool collides(const Pose& pose) override;
  /// The decoded shard bytes resident now (all of them in memory).
  std::uint64_t structure_bytes() const override;
  /// Budget, index shard bytes, the preload's page-ins, and the flight's page-ins, hit rate,
  /// peak resident shard bytes and page-in latency (counted from the end of the build); the
  /// step counters per step and the time in each phase.
  nlohmann::json figures() const override;

 private:
  TetrapageColliderOptions options_;
  std::shared_ptr<const CollisionIndex> index_;
  FlyingObject object_;
  QueryOptions query_options_;  // exact, first hit
  QueryResult result_;
  std::uint64_t preload_page_ins_ = 0;
  StepTotals totals_;  // the runtime's step counters, summed (they explain the time)
  double locate_seconds_ = 0, search_seconds_ = 0, shard_seconds_ = 0, test_seconds_ = 0;
};

}  // namespace tetrapage
