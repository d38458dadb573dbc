#include "tetrapage/formats/index/IndexSummary.h"

#include <algorithm>

#include <nlohmann/json.hpp>

#include "tetrapage/formats/index/IndexHeader.h"
#include "tetrapage/formats/index/IndexParts.h"
#include "tetrapage/formats/index/IndexSchema.h"

namespace tetrapage {

namespace schema = index_schema;

IndexSummary IndexSummary::of(const IndexReader& reader) {
  const IndexHeader& header = reader.header();
  IndexSummary s;
  s.index = reader.path().string();
  s.version = header.version;
  s.precision = header.precision;
  s.storage = storage_statement(header);
  s.length_unit = header.length_unit;
  s.max_rounding_distance = header.max_rounding_distance;
  s.tessellation_deflection = header.tessellation_deflection;
  s.bounds = header.bounds;
  s.file_bytes = reader.file_bytes();
  s.triangles = header.input_triangles;
  s.stored_triangles = header.stored_triangles;
  s.tets = header.region_count;
  s.shards = reader.shard_count();
  const auto shard_kind = reader.read_table_uint8(schema::table::shard_kind);
  const auto shard_triangles = reader.read_table_uint32(schema::table::shard_triangles);
  for (std::uint32_t shard = 0; shard < reader.shard_count(); ++shard) {
    const std::uint64_t stored = reader.stored_shard_size(shard);  // a chunk lookup each
    const std::uint64_t decoded = reader.shard_size(shard);
    s.shard_stored_bytes += stored;
    s.shard_decoded_bytes += decoded;
    const bool grid = shard_kind.at(shard) == 0;
    (grid ? s.grid_shards : s.rtree_shards) += 1;
    (grid ? s.grid_stored_bytes : s.rtree_stored_bytes) += stored;
    s.largest_shard_bytes = std::max(s.largest_shard_bytes, decoded);
    s.largest_shard_triangles = std::max(s.largest_shard_triangles, shard_triangles.at(shard));
  }
  const auto closed = reader.read_table_uint8(schema::table::component_closed);
  const auto component_part = reader.read_table_uint32(schema::table::component_part);
  s.components = closed.size();
  s.closed_components =
      std::uint64_t(std::count_if(closed.begin(), closed.end(), [](auto c) { return c != 0; }));
  std::size_t listed_parts = 0;
  for (const auto p : component_part)
    listed_parts = std::max<std::size_t>(listed_parts, std::size_t(p) + 1);
  s.parts = IndexParts::read(reader, listed_parts).count();
  const auto names = reader.table_names();
  s.interiors =
      std::find(names.begin(), names.end(), schema::table::interior_offsets) != names.end();
  s.created_by = header.created_by;
  s.source = header.source;
  return s;
}

std::string IndexSummary::to_json() const {
  nlohmann::json json{
      {"index", index},
      {"version", version},
      {"precision", precision},
      {"storage", storage},
      {"length_unit", length_unit},
      {"tessellation_deflection", tessellation_deflection},
      {"bounds",
       {{bounds.lo[0], bounds.lo[1], bounds.lo[2]}, {bounds.hi[0], bounds.hi[1], bounds.hi[2]}}},
      {"file_bytes", file_bytes},
      {"triangles", triangles},
      {"stored_triangles", stored_triangles},
      {"tets", tets},
      {"shards", shards},
      {"grid_shards", grid_shards},
      {"rtree_shards", rtree_shards},
      {"shard_stored_bytes", shard_stored_bytes},
      {"shard_decoded_bytes", shard_decoded_bytes},
      {"grid_stored_bytes", grid_stored_bytes},
      {"rtree_stored_bytes", rtree_stored_bytes},
      {"largest_shard_bytes", largest_shard_bytes},
      {"largest_shard_triangles", largest_shard_triangles},
      {"parts", parts},
      {"components", components},
      {"closed_components", closed_components},
      {"interiors", interiors},
      {"created_by", created_by},
      {"source", source}};
  // Only a rounded index has a rounding distance to state.
  if (precision == "float") json["max_rounding_distance"] = max_rounding_distance;
  return json.dump();
}

}  // namespace tetrapage
