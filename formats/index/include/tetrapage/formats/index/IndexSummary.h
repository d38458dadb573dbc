#pragma once
/// @file IndexSummary.h
/// What an index holds and where its bytes go: one set of figures under one set of names, for
/// `tetrapage inspect` (its text and its --report) and Python's `Index.inspect()`.

#include <cstdint>
#include <string>

#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/formats/index/IndexReader.h"

namespace tetrapage {

struct IndexSummary {
  std::string index;  ///< the file's path
  std::uint32_t version = 0;
  std::string precision;
  std::string storage;      ///< storage_statement: exact for the input, or rounded by how much
  std::string length_unit;  ///< empty when no input said
  double max_rounding_distance = 0;
  double tessellation_deflection = 0;  ///< 0 when every input held triangles
  BoundingBox bounds;
  std::uint64_t file_bytes = 0;
  std::uint64_t triangles = 0;         ///< the model's
  std::uint64_t stored_triangles = 0;  ///< over all shards, copies in several shards included
  std::uint64_t tets = 0;
  std::uint64_t shards = 0, grid_shards = 0, rtree_shards = 0;
  std::uint64_t shard_stored_bytes = 0, shard_decoded_bytes = 0;
  std::uint64_t grid_stored_bytes = 0, rtree_stored_bytes = 0;
  std::uint64_t largest_shard_bytes = 0;  ///< decoded
  std::uint32_t largest_shard_triangles = 0;
  std::uint64_t parts = 0;
  std::uint64_t components = 0, closed_components = 0;
  bool interiors = false;  ///< the interiors tables are stored (preprocess --interiors)
  std::string created_by;
  std::string source;

  /// Reads the figures (the header and the shard, component and part tables).
  /// @throw FormatError or InputError as the reader does.
  static IndexSummary of(const IndexReader& reader);
  /// The figures as a JSON object, each under the name of its member (max_rounding_distance
  /// only for a rounded index, precision "float").
  std::string to_json() const;
};

}  // namespace tetrapage
