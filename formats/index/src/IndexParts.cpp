#include "tetrapage/formats/index/IndexParts.h"

#include <algorithm>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/index/IndexSchema.h"

namespace tetrapage {
namespace {

namespace schema = index_schema;

// A strings table pair: n + 1 offsets delimiting the bytes.
void read_strings(const IndexReader& reader, std::string_view offsets_table,
                  std::string_view bytes_table, std::vector<std::uint64_t>& offsets,
                  std::string& bytes) {
  const std::string where = reader.path().string() + ": ";
  offsets = reader.read_table_uint64(offsets_table);
  const auto raw = reader.read_table_uint8(bytes_table);
  bytes.assign(raw.begin(), raw.end());
  if (offsets.empty() || offsets.front() != 0 || offsets.back() != bytes.size() ||
      !std::is_sorted(offsets.begin(), offsets.end()))
    throw FormatError(where + schema::table_path(offsets_table) + " does not delimit the " +
                      std::to_string(bytes.size()) + " bytes of " +
                      schema::table_path(bytes_table));
}

std::string slice(const std::vector<std::uint64_t>& offsets, const std::string& bytes,
                  std::uint32_t i) {
  return bytes.substr(offsets[i], offsets[i + 1] - offsets[i]);
}

}  // namespace

IndexParts IndexParts::read(const IndexReader& reader, std::size_t listed_parts) {
  IndexParts parts;
  parts.count_ = listed_parts;
  const std::string where = reader.path().string() + ": ";
  const std::string_view tables[] = {schema::table::part_name_offsets,
                                     schema::table::part_name_bytes,
                                     schema::table::part_path_offsets,
                                     schema::table::part_path_bytes, schema::table::part_triangles};
  const auto present =
      std::size_t(std::count_if(std::begin(tables), std::end(tables),
                                [&](std::string_view t) { return reader.has_table(t); }));
  if (present == 0) return parts;
  if (present != std::size(tables))
    throw FormatError(where + "the part tables are partly present (" + std::to_string(present) +
                      " of " + std::to_string(std::size(tables)) + "): rebuild the index");
  read_strings(reader, schema::table::part_name_offsets, schema::table::part_name_bytes,
               parts.name_offsets_, parts.names_);
  read_strings(reader, schema::table::part_path_offsets, schema::table::part_path_bytes,
               parts.path_offsets_, parts.paths_);
  parts.triangles_ = reader.read_table_uint64(schema::table::part_triangles);
  const std::size_t count = parts.name_offsets_.size() - 1;
  if (parts.path_offsets_.size() != count + 1 || parts.triangles_.size() != count ||
      count < listed_parts)
    throw FormatError(where + "the part tables list " + std::to_string(count) + " names, " +
                      std::to_string(parts.path_offsets_.size() - 1) + " paths and " +
                      std::to_string(parts.triangles_.size()) + " counts, for " +
                      std::to_string(listed_parts) + " parts the components name");
  parts.count_ = count;
  return parts;
}

std::string IndexParts::name(std::uint32_t part) const {
  if (part >= count_) return "(no part " + std::to_string(part) + ")";
  return named() ? slice(name_offsets_, names_, part) : "part " + std::to_string(part);
}

std::string IndexParts::path(std::uint32_t part) const {
  if (part >= count_ || !named()) return name(part);
  return slice(path_offsets_, paths_, part);
}

}  // namespace tetrapage
