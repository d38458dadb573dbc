#pragma once
/// @file ShardKind.h
/// The two spatial indexes a shard can hold and the two precisions its coordinates can be
/// stored in, with their names as they appear in reports and index attributes.

#include <cstdint>
#include <string>
#include <string_view>

#include "tetrapage/formats/base/Error.h"

namespace tetrapage {

/// The spatial index of one region's triangles.
enum class ShardKind : std::uint8_t {
  grid = 0,   ///< a uniform grid, triangles listed in every cell they meet (exact test)
  rtree = 1,  ///< a bulk-loaded R-tree, triangles reordered so that leaves hold ranges
};

/// The type the shard's vertex coordinates (relative to its origin) are stored in. `exact` is
/// what a builder is asked for, never a shard's own type: each shard is stored as float32 when
/// every one of its vertices decodes from float32 to exactly the input's double (input that was
/// float already, at a suitable origin), else as float64; either way the stored model is the
/// input.
enum class StoredPrecision : std::uint8_t {
  float32 = 0,
  float64 = 1,
  exact = 2,
};

/// "grid" or "rtree".
constexpr std::string_view to_string(ShardKind kind) {
  return kind == ShardKind::grid ? "grid" : "rtree";
}

/// "float", "double" or "exact", the spelling of the index header's precision attribute.
constexpr std::string_view to_string(StoredPrecision precision) {
  return precision == StoredPrecision::float32 ? "float" : precision == StoredPrecision::float64 ? "double" : "exact";
}

/// The kind named "grid" or "rtree".
/// @throw InputError naming the text when it is neither.
inline ShardKind parse_shard_kind(std::string_view text) {
  if (text == "grid") return ShardKind::grid;
  if (text == "rtree") return ShardKind::rtree;
  throw InputError("shard kind '" + std::string(text) + "' is not 'grid' or 'rtree'");
}

/// The precision named "exact", "float" (or "float32") or "double" (or "float64").
/// @throw InputError naming the text when it is none of those.
inline StoredPrecision parse_stored_precision(std::string_view text) {
  if (text == "exact") return StoredPrecision::exact;
  if (text == "float" || text == "float32") return StoredPrecision::float32;
  if (text == "double" || text == "float64") return StoredPrecision::float64;
  throw InputError("stored precision '" + std::string(text) + "' is not 'exact', 'float' or 'double'");
}

}  // namespace tetrapage
