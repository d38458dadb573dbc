#pragma once
/// @file ContactFile.h
/// The contacts of a flight as CSV (`fly --contacts`), one row per contact:
///   step,kind,part,part_name,part_path,environment_triangle,object_triangle,x,y,z
/// kind is "surface" (an environment triangle meets an object triangle; x,y,z is a point of
/// their intersection: the mean of FlyingObject::contact_geometry's corners, within 2^-40 of
/// the coordinates' magnitude), "solid" (the object was
/// checked as a solid: hull, box or swept; no object triangle nor point), "object_inside" or
/// "obstacle_inside" (containment: part is the containing or contained environment part, and
/// the triangle and point fields are empty). Names are quoted as CSV quotes them.

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>

#include "tetrapage/formats/Pose.h"
#include "tetrapage/formats/TriangleSoup.h"
#include "tetrapage/runtime/CollisionIndex.h"
#include "tetrapage/runtime/FlyingObject.h"
#include "tetrapage/tools/CsvFile.h"

namespace tetrapage {

class ContactFile {
 public:
  /// Opens `path` under a temporary name (removed unless commit() runs). @throw IoError.
  ContactFile(const std::filesystem::path& path, const CollisionIndex& index);

  /// The rows of one step's answer. @throw IoError; what the index throws paging a shard in.
  /// `object` answered `result` last (its contacts' geometry is read from it).
  void write_step(std::uint64_t step, FlyingObject& object, const QueryResult& result);
  std::uint64_t rows() const { return file_.rows(); }
  /// Flushes and renames the file into place. @throw IoError.
  void commit() { file_.commit(); }

 private:
  void write_row(std::uint64_t step, const char* kind, std::uint32_t part,
                 const std::string& triangle_fields);

  CsvFile file_;
  const CollisionIndex& index_;
};

}  // namespace tetrapage
