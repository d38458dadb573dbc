#pragma once
/// @file PhaseTwo.h (private)
/// One step's test of a shard's candidates (step 5 of the runtime step): phase I's R-tree
/// descent pruned by the object's shapes, each candidate met once, taken to the object's
/// frame and pruned there; then phase II, the candidate against the object's BVH (or its
/// solid), decided on world coordinates, and the contacts found.

#include <cstdint>

#include <utility>
#include <vector>
#include "ContainmentCheck.h"
#include "ObjectSolid.h"
#include "PlacedObject.h"
#include "PruningShapes.h"
#include "tetrapage/runtime/paging/CollisionIndex.h"
#include "tetrapage/runtime/paging/Shard.h"
#include "tetrapage/runtime/query/DynamicObstacles.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/runtime/query/ObjectModel.h"
#include "tetrapage/runtime/query/TriangleIdSet.h"

namespace tetrapage {

/// The environment triangle of each contact of a step with an index triangle, as phase II
/// tested it (its id and corners): the contacts' geometry then needs no lookup by id.
using ContactTriangles = std::vector<std::pair<std::uint64_t, geometry::Triangle>>;

/// What one step's test of its candidates reads and writes: the index and the object, the
/// step's placed shapes and scratch, and its answer.
struct StepContext {
  const CollisionIndex& index;
  const ObjectModel& model;
  PlacedObject& object;
  const PruningShapes& shapes;
  ObjectSolid& solid;  ///< built on the first candidate that needs it
  const Coherence& coherence;
  ContainmentCheck& containment;
  TriangleIdSet& met_triangles;
  ContactTriangles& contact_triangles;
  QueryResult& result;
};

class PhaseTwo {
 public:
  /// The step's test with phase I box `box`, the object asked as a solid when `solid_query`.
  PhaseTwo(const StepContext& step, const QueryOptions& options, bool solid_query,
           const geometry::Box& box);

  /// The shard's candidates, but for those of the parts `overlay` hides (when given).
  void test_shard(const Shard& shard, const DynamicObstacles* overlay = nullptr);
  /// The dynamic parts whose boxes meet the step's box: each part triangle near the box (its
  /// BVH, the box taken into its frame) through the same phase II as a shard's candidate.
  /// `placed`: scratch, rebound to each part.
  void test_dynamic_parts(const DynamicObstacles& overlay, PlacedObject& placed);
  /// first_hit found its contact: the other shards need not be tested.
  bool stopped() const { return stop_; }
  /// With all contacts, each pair once.
  void finish();

 private:
  // Where a candidate comes from: a shard's local triangle, or a dynamic part's triangle.
  struct Source {
    const Shard* shard = nullptr;
    std::uint32_t local = 0;  ///< the shard's local triangle, or the dynamic part's triangle
    DynamicPartId part = kNoDynamicPart;
  };
  void test_candidate(const Source& source, const geometry::Triangle& environment);
  void test_mesh(const Source& source, const geometry::Triangle& environment,
                 const std::array<Vec3, 3>& framed, const geometry::Box& query, double grow);
  void add_contact(const Source& source, const geometry::Triangle& environment,
                   std::uint32_t object_triangle);
  void note_if_enclosed(const Shard& shard, std::uint32_t local,
                        const geometry::Triangle& environment);
  // Triangles that meet only the object's inside still count: some component may lie in it,
  // and no contact has been found.
  bool inside_counts() const { return may_enclose_ && !step_.result.collides; }

  const StepContext step_;
  const QueryOptions& options_;
  const bool solid_query_;
  const bool all_;
  /// Some component of a part could lie wholly inside the object (closed, and some
  /// component fits in the box): only then do the triangles that meet only its inside count.
  const bool may_enclose_;
  const geometry::Box& box_;
  StepCounters& counters_;
  bool stop_ = false;
};

}  // namespace tetrapage
