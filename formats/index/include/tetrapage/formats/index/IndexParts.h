#pragma once
/// @file IndexParts.h
/// The parts of an indexed model (docs/FORMAT.md, "Parts"): each one's name, instance path and
/// triangle count, read from the index's part tables. Indexes written before those tables
/// existed still open: their parts are named "part K" and their counts are unknown.

#include <cstdint>
#include <string>
#include <vector>

#include "tetrapage/formats/index/IndexReader.h"

namespace tetrapage {

class IndexParts {
 public:
  IndexParts() = default;
  /// Reads the part tables; `listed_parts` is the number of parts the components name (one
  /// more than the largest component_part).
  /// @throw FormatError (naming the file and the table) when the tables are partly present,
  ///        disagree in length, or their offsets do not delimit their bytes.
  static IndexParts read(const IndexReader& reader, std::size_t listed_parts);

  std::size_t count() const { return count_; }
  /// Whether the index records the parts' names (else they are "part K").
  bool named() const { return !name_offsets_.empty(); }
  std::string name(std::uint32_t part) const;
  std::string path(std::uint32_t part) const;
  /// Triangles the part holds in the index (0 when the index does not record them).
  std::uint64_t triangles(std::uint32_t part) const {
    return part < triangles_.size() ? triangles_[part] : 0;
  }

 private:
  std::size_t count_ = 0;
  std::vector<std::uint64_t> name_offsets_, path_offsets_;
  std::string names_, paths_;
  std::vector<std::uint64_t> triangles_;
};

}  // namespace tetrapage
