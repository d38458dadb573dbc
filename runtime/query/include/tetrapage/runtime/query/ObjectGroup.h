#pragma once
/// @file ObjectGroup.h
/// Several rigid objects moving through one index (the study's section 5.3): each object
/// against the environment (its own FlyingObject), and each pair of objects against each other.
///
/// The object/object answer is exact on the placed vertices (apply_pose, the canonical
/// placement) of both objects: a pair collides when some triangle of one meets some triangle
/// of the other (touching counts), as a brute force over all placed triangle pairs with the
/// exact triangle test answers; or, without touching surfaces, when a component of one lies
/// inside a closed component of the other. A sweep on x over the objects' world boxes finds the
/// pairs that can meet; for each, both objects' BVHs are descended together, a node box of one
/// taken into the other's frame with a margin beyond every rounding (it only prunes); every
/// remaining triangle pair is decided by the exact test on world coordinates.
///
/// A group is used from one thread at a time (step may use TBB's threads inside when asked);
/// the index and the object models may be shared with anything else.

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/runtime/paging/CollisionIndex.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/runtime/query/ObjectModel.h"

namespace tetrapage {

struct GroupQueryOptions {
  /// Each object against the environment, with these options (skipped without an index).
  bool check_environment = true;
  QueryOptions environment;
  /// Each pair of objects against each other: the first triangle pair found per colliding pair,
  /// or all of them. Always exact (the accuracy above is the environment's).
  bool check_pairs = true;
  QueryMode pair_mode = QueryMode::first_hit;
  /// Also report a pair whose surfaces do not touch when one object holds the other (a
  /// component of one inside a closed component of the other).
  bool pair_containment = true;
  /// Run the objects' environment queries on TBB's threads (the pairs stay on the caller's).
  bool parallel = false;
};

/// How two objects collide without touching surfaces.
enum class PairContainment : std::uint8_t {
  none,
  first_inside_second,  ///< a component of `first` lies inside a closed component of `second`
  second_inside_first,
};

/// A triangle of the pair's first object meeting a triangle of its second.
struct TrianglePair {
  std::uint32_t first_triangle = 0;
  std::uint32_t second_triangle = 0;
  bool operator==(const TrianglePair&) const = default;
  auto operator<=>(const TrianglePair&) const = default;
};

/// Two objects (their indices in the group, first < second) that collide.
struct CollidingPair {
  std::uint32_t first = 0;
  std::uint32_t second = 0;
  /// Surfaces touch: none. Otherwise which object holds the other (no triangle pair).
  PairContainment containment = PairContainment::none;
  /// The pair's triangle pairs: GroupResult::triangle_pairs[begin, end), sorted (all_contacts:
  /// every one; first_hit: the first found).
  std::uint32_t triangle_pairs_begin = 0;
  std::uint32_t triangle_pairs_end = 0;
};

struct GroupCounters {
  std::uint64_t box_pairs = 0;       ///< pairs whose world boxes overlap (the broad phase's)
  std::uint64_t candidates = 0;      ///< triangles near the other object, searched in its BVH
  std::uint64_t triangle_tests = 0;  ///< exact triangle pair tests
  double environment_seconds = 0;
  double pair_seconds = 0;
};

struct GroupResult {
  /// Per object, its answer against the environment (empty without an index or when
  /// check_environment is off).
  std::vector<QueryResult> environment;
  /// The colliding pairs, sorted by (first, second).
  std::vector<CollidingPair> pairs;
  std::vector<TrianglePair> triangle_pairs;
  /// Per object, its world box at the step's pose.
  std::vector<geometry::Box> world_boxes;
  GroupCounters counters;

  std::span<const TrianglePair> triangles_of(const CollidingPair& pair) const {
    return std::span<const TrianglePair>(triangle_pairs)
        .subspan(pair.triangle_pairs_begin, pair.triangle_pairs_end - pair.triangle_pairs_begin);
  }
};

class ObjectGroup {
 public:
  /// The objects, each with its own FlyingObject on `index`. A null index makes a group that
  /// answers object/object questions only.
  /// @throw InputError for no object, a null model, or more than 2^32 - 1 objects.
  ObjectGroup(std::shared_ptr<const CollisionIndex> index,
              std::vector<std::shared_ptr<const ObjectModel>> models);
  ~ObjectGroup();
  ObjectGroup(ObjectGroup&&) noexcept;
  ObjectGroup& operator=(ObjectGroup&&) noexcept;

  std::size_t size() const;
  const std::shared_ptr<const ObjectModel>& model(std::size_t object) const;
  const std::shared_ptr<const CollisionIndex>& index() const { return index_; }

  /// Dynamic obstacles merged into every object's environment query (FlyingObject::
  /// set_obstacles); null: none. Object/object pairs are not affected.
  /// @throw InputError for an overlay on another index, or a group without an index.
  void set_obstacles(std::shared_ptr<const DynamicObstacles> obstacles);

  /// One step: object i at poses[i]. Reuses `result`'s buffers.
  /// @throw InputError for a pose count other than size(), or as FlyingObject::query for a bad
  ///        pose (naming the object); what the environment queries throw.
  void step(std::span<const Pose> poses, const GroupQueryOptions& options, GroupResult& result);
  GroupResult step(std::span<const Pose> poses, const GroupQueryOptions& options = {}) {
    GroupResult result;
    step(poses, options, result);
    return result;
  }

 private:
  struct Parts;
  void query_environment(std::span<const Pose> poses, const GroupQueryOptions& options,
                         GroupResult& result);
  void test_pairs(const GroupQueryOptions& options, GroupResult& result);

  std::shared_ptr<const CollisionIndex> index_;
  std::unique_ptr<Parts> parts_;
};

}  // namespace tetrapage
