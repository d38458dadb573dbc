#pragma once
/// @file ContactFile.h
/// The contacts of a flight as CSV (`fly --contacts`): one row per contact, and one per
/// containment, each `step,` and the site columns of AnswerSite.h (kind surface, near,
/// solid, object_inside or obstacle_inside; the parts on both sides by id, name and path).

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>

#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/runtime/paging/CollisionIndex.h"
#include "tetrapage/runtime/query/FlyingObject.h"
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
  CsvFile file_;
  const CollisionIndex& index_;
};

}  // namespace tetrapage
