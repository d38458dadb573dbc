#pragma once
/// @file IndexHeader.h
/// What the root attributes of an index file say about it (docs/FORMAT.md lists them).

#include <cstdint>
#include <string>
#include <string_view>

#include "tetrapage/formats/base/TriangleSoup.h"

namespace tetrapage {

/// Value of the root attribute "format" of every tetrapage index.
inline constexpr std::string_view kIndexFormatName = "tetrapage-index";
/// The only layout version this build writes and reads; any change to the layout bumps it.
inline constexpr std::uint32_t kIndexVersion = 5;

struct IndexHeader {
  std::uint32_t version = kIndexVersion;
  /// How shard coordinates are stored: "exact" (each shard decodes to the input's
  /// coordinates: float32 where that is lossless, else float64), "double", or "float" (rounded
  /// to compact floats, by up to max_rounding_distance).
  std::string precision = "double";
  std::uint64_t input_triangles = 0;
  /// Triangles over all shards, duplicates (a triangle binned into several tets) included.
  std::uint64_t stored_triangles = 0;
  std::uint64_t region_count = 0;
  /// Number of shards; the writer fills it in (a non-zero value must match).
  std::uint64_t shard_count = 0;
  /// Largest distance between an input vertex and its stored (rounded) position.
  double max_rounding_distance = 0;
  BoundingBox bounds;
  /// What the index was built from (file names, a hash: free text).
  std::string source;
  /// The preprocess report, a JSON document (any length).
  std::string build_report_json;
  /// Program that wrote the file; the writer fills it in, the reader reports it.
  std::string created_by;
  /// The model's length unit ("mm", "m", "in", ...), empty when no input said.
  std::string length_unit;
  /// The largest chordal deviation asked of the tessellation of CAD inputs, in the model's
  /// unit; 0 when every input held triangles.
  double tessellation_deflection = 0;
};

/// One line saying how an index stores coordinates and what that means for its answers (for
/// preprocess, inspect and fly): exact for the input, or for a model rounded by up to
/// `max_rounding_distance`.
std::string storage_statement(std::string_view precision, double max_rounding_distance);
inline std::string storage_statement(const IndexHeader& header) {
  return storage_statement(header.precision, header.max_rounding_distance);
}

}  // namespace tetrapage
