#include "WriteIndex.h"

#include <span>
#include <vector>

#include "tetrapage/formats/index/IndexHeader.h"
#include "tetrapage/formats/index/IndexSchema.h"

namespace tetrapage {
namespace {

namespace schema = index_schema;

// The components table (docs/FORMAT.md): each component's part, closedness and box.
void write_components(IndexWriter& writer, const std::vector<SurfaceComponent>& components) {
  std::vector<std::uint32_t> part;
  std::vector<std::uint8_t> closed;
  std::vector<double> bounds;
  part.reserve(components.size());
  closed.reserve(components.size());
  bounds.reserve(6 * components.size());
  for (const SurfaceComponent& c : components) {
    part.push_back(c.part);
    closed.push_back(c.closed ? 1 : 0);
    bounds.insert(bounds.end(), c.bounds.lo.begin(), c.bounds.lo.end());
    bounds.insert(bounds.end(), c.bounds.hi.begin(), c.bounds.hi.end());
  }
  writer.write_table(schema::table::component_part, std::span<const std::uint32_t>(part));
  writer.write_table(schema::table::component_closed, std::span<const std::uint8_t>(closed));
  writer.write_table(schema::table::component_bounds, std::span<const double>(bounds));
}

void write_shard_tables(IndexWriter& writer, const ShardTables& shards) {
  writer.write_table(schema::table::tet_shard, std::span<const std::uint32_t>(shards.tet_shard));
  writer.write_table(schema::table::shard_tet, std::span<const std::uint32_t>(shards.shard_tet));
  writer.write_table(schema::table::shard_kind, std::span<const std::uint8_t>(shards.shard_kind));
  writer.write_table(schema::table::shard_triangles,
                     std::span<const std::uint32_t>(shards.shard_triangles));
  writer.write_table(schema::table::shard_bounds, std::span<const double>(shards.shard_bounds));
  writer.write_table(schema::table::shard_id_ranges, std::span<const std::uint64_t>(shards.shard_id_ranges));
}

// Strings as a table of their bytes and one of offsets (n + 1, the last the bytes' length).
void write_strings(IndexWriter& writer, std::string_view offsets_table, std::string_view bytes_table,
                   const std::vector<std::string>& strings) {
  std::vector<std::uint64_t> offsets{0};
  std::vector<std::uint8_t> bytes;
  for (const std::string& s : strings) {
    bytes.insert(bytes.end(), s.begin(), s.end());
    offsets.push_back(bytes.size());
  }
  writer.write_table(offsets_table, std::span<const std::uint64_t>(offsets));
  writer.write_table(bytes_table, std::span<const std::uint8_t>(bytes));
}

// The parts (docs/FORMAT.md): each one's name, instance path and triangle count.
void write_parts(IndexWriter& writer, const IngestedModel& model) {
  write_strings(writer, schema::table::part_name_offsets, schema::table::part_name_bytes, model.part_names);
  write_strings(writer, schema::table::part_path_offsets, schema::table::part_path_bytes, model.part_paths);
  writer.write_table(schema::table::part_triangles, std::span<const std::uint64_t>(model.part_triangles));
}

void write_interiors(IndexWriter& writer, const Interiors& interiors) {
  writer.write_table(schema::table::reference_points,
                     std::span<const double>(interiors.reference_points));
  writer.write_table(schema::table::interior_offsets,
                     std::span<const std::uint64_t>(interiors.offsets));
  writer.write_table(schema::table::interior_components,
                     std::span<const std::uint32_t>(interiors.components));
}

}  // namespace

void write_index(IndexWriter& writer, const TetMesh& mesh, const ShardTables& shards,
                 const IngestedModel& model, const Interiors& interiors, const std::string& source,
                 std::chrono::steady_clock::time_point start, PreprocessSummary& summary) {
  writer.write_mesh(mesh);
  write_shard_tables(writer, shards);
  write_components(writer, model.components);
  write_parts(writer, model);
  if (interiors.stored) write_interiors(writer, interiors);
  IndexHeader header;
  header.precision = summary.precision;
  header.input_triangles = model.triangle_count;
  header.stored_triangles = summary.stored_triangles;
  header.region_count = mesh.tet_count();
  header.shard_count = shards.shard_tet.size();
  header.max_rounding_distance = summary.max_rounding_distance;
  header.bounds = model.bounds;
  header.source = source;
  header.length_unit = model.length_unit;
  header.tessellation_deflection = model.tessellation_deflection;
  header.created_by = "tetrapage preprocess";
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  header.build_report_json = summary.to_json();
  summary.bytes_written = writer.commit(header);
}

}  // namespace tetrapage
