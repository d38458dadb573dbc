#pragma once
/// @file QueryAnswerFile.h
/// The answers of `tetrapage fly --query contacts|distance|toi --answers FILE` as CSV, each
/// row `step,` and the site columns of AnswerSite.h (kind, the environment part, the object
/// part, both points), then the query's own columns:
///   contacts: one row per contact pair (every pair of each step) and one per containment:
///     ...,shape,x1,y1,z1,x2,y2,z2,polygon,environment_nx,environment_ny,environment_nz,
///     object_nx,object_ny,object_nz
///     where the triangles meet: shape point, segment or polygon (none for a near pair, a
///     solid or a containment); x1..z2 the point, or the segment's ends, or the polygon's
///     first two corners; polygon every corner of a coplanar overlap as "x y z;x y z;..."; the
///     normals are unit, by the right-hand rule of each triangle's corners.
///   distance: one row per step: ...,separation,distance,lower_bound,upper_bound
///     (separation touching, apart or farther; the site is the closest pair, the containment,
///     or empty when farther).
///   toi: one row per step, the motion from the previous pose (step 0: the pose alone):
///     ...,impact,free_until,contact_at,iterations
///     (impact none, hit or unresolved; the site is the first contact or the containment at
///     contact_at).
/// (`--query collide` writes step,collides: AnswerFile.h.)

#include <cstdint>
#include <filesystem>
#include <string>

#include "tetrapage/runtime/paging/CollisionIndex.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/tools/CsvFile.h"

namespace tetrapage {

enum class FlyQuery : std::uint8_t { collide, contacts, distance, time_of_impact };

/// "collide", "contacts", "distance" or "toi". @throw InputError naming anything else.
FlyQuery parse_fly_query(const std::string& text);
const char* fly_query_name(FlyQuery query);

class QueryAnswerFile {
 public:
  /// Opens `path` under a temporary name for `query` (not collide). @throw IoError.
  QueryAnswerFile(const std::filesystem::path& path, FlyQuery query, const CollisionIndex& index);

  /// The contact rows of a step (its geometry from the object at the step's pose).
  void write_contacts(std::uint64_t step, FlyingObject& object, const QueryResult& result);
  void write_distance(std::uint64_t step, FlyingObject& object, const DistanceResult& result);
  void write_impact(std::uint64_t step, FlyingObject& object, const ImpactResult& result);
  std::uint64_t rows() const { return file_.rows(); }
  /// Flushes and renames the file into place. @throw IoError.
  void commit() { file_.commit(); }

 private:
  CsvFile file_;
  const CollisionIndex& index_;
};

}  // namespace tetrapage
