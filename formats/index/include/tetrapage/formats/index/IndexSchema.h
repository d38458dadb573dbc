#pragma once
/// @file IndexSchema.h
/// The names inside an index file: its datasets, the preprocess's tables under /tables, and
/// the root attributes (docs/FORMAT.md says what each holds). The writer, the reader, the
/// preprocess, the runtime and the tools name them from here only.

#include <string>
#include <string_view>

namespace tetrapage::index_schema {

/// Groups under the root.
namespace group {
inline constexpr const char* mesh = "mesh";
inline constexpr const char* tables = "tables";
inline constexpr const char* shards = "shards";
}  // namespace group

namespace dataset {
inline constexpr const char* mesh_vertices = "/mesh/vertices";
inline constexpr const char* mesh_tets = "/mesh/tets";
inline constexpr const char* mesh_neighbours = "/mesh/neighbours";
inline constexpr const char* shard_offsets = "/shards/offsets";
inline constexpr const char* shard_sizes = "/shards/sizes";
inline constexpr const char* shard_data = "/shards/data";
}  // namespace dataset

/// Tables the preprocess writes (IndexWriter::write_table); their lengths are fixed by the
/// shards, the tets or the components.
namespace table {
inline constexpr std::string_view tet_shard = "tet_shard";
inline constexpr std::string_view shard_tet = "shard_tet";
inline constexpr std::string_view shard_kind = "shard_kind";
inline constexpr std::string_view shard_triangles = "shard_triangles";
inline constexpr std::string_view shard_bounds = "shard_bounds";
inline constexpr std::string_view reference_points = "reference_points";
inline constexpr std::string_view interior_offsets = "interior_offsets";
inline constexpr std::string_view interior_components = "interior_components";
inline constexpr std::string_view component_part = "component_part";
inline constexpr std::string_view component_closed = "component_closed";
inline constexpr std::string_view component_bounds = "component_bounds";
// Optional (indexes written before them lack them): parts by name, and shards by triangle id.
inline constexpr std::string_view part_name_offsets = "part_name_offsets";
inline constexpr std::string_view part_name_bytes = "part_name_bytes";
inline constexpr std::string_view part_path_offsets = "part_path_offsets";
inline constexpr std::string_view part_path_bytes = "part_path_bytes";
inline constexpr std::string_view part_triangles = "part_triangles";
inline constexpr std::string_view shard_id_ranges = "shard_id_ranges";
}  // namespace table

namespace attribute {
inline constexpr const char* format = "format";
inline constexpr const char* version = "version";
inline constexpr const char* precision = "precision";
inline constexpr const char* input_triangles = "input_triangles";
inline constexpr const char* stored_triangles = "stored_triangles";
inline constexpr const char* region_count = "region_count";
inline constexpr const char* shard_count = "shard_count";
inline constexpr const char* max_rounding_distance = "max_rounding_distance";
inline constexpr const char* bounds = "bounds";
inline constexpr const char* source = "source";
inline constexpr const char* build_report = "build_report";
inline constexpr const char* created_by = "created_by";
// Optional: absent in indexes written before them.
inline constexpr const char* length_unit = "length_unit";
inline constexpr const char* tessellation_deflection = "tessellation_deflection";
}  // namespace attribute

/// A table's dataset path, as messages name it: "/tables/NAME".
inline std::string table_path(std::string_view name) {
  return "/tables/" + std::string(name);
}

}  // namespace tetrapage::index_schema
