// The checks of an opened index (IndexReader::Impl): the superblock, the header's values and
// counts against the tables, every dataset's type, shape and chunks, the compact storage of
// links and attributes, the shard data's layout and the stored chunks' claims. Each throws
// FormatError naming the index, the table and the value at fault.

#include "IndexReaderImpl.h"

namespace tetrapage {

void IndexReader::Impl::require_checksummed_superblock() const {
  static constexpr std::array<unsigned char, 8> signature{0x89, 'H',  'D',  'F',
                                                          '\r', '\n', 0x1a, '\n'};
  // HDF5 looks for its signature at 0, 512, 1024, 2048, ... (after a user block).
  for (std::uint64_t offset = 0; offset + signature.size() < file_bytes;
       offset = offset == 0 ? 512 : 2 * offset) {
    std::array<unsigned char, 9> bytes{};
    if (read_at(reinterpret_cast<std::byte*>(bytes.data()), bytes.size(), offset) !=
        static_cast<ssize_t>(bytes.size()))
      break;
    if (!std::equal(signature.begin(), signature.end(), bytes.begin())) continue;
    const unsigned version = bytes[8];
    if (version < 2)
      format_error("HDF5 superblock version " + std::to_string(version) +
                   ", whose metadata carries no checksums: written by a tetrapage older than index "
                   "version " +
                   std::to_string(kIndexVersion) + " or by another program; rebuild the index");
    return;
  }
  format_error("not an HDF5 file (no HDF5 signature in its " + std::to_string(file_bytes) +
               " bytes); expected a tetrapage index");
}

void IndexReader::Impl::check_mesh_shapes() {
  DatasetHandle vertices = open_dataset(schema::dataset::mesh_vertices);
  const auto vertex_rows =
      check_dataset(vertices.get(), schema::dataset::mesh_vertices, Element::float64, 3);
  check_dataset_size(vertices.get(), schema::dataset::mesh_vertices, Element::float64, vertex_rows,
                     3);
  DatasetHandle tets = open_dataset(schema::dataset::mesh_tets);
  const auto tet_rows = check_dataset(tets.get(), schema::dataset::mesh_tets, Element::uint32, 4);
  check_dataset_size(tets.get(), schema::dataset::mesh_tets, Element::uint32, tet_rows, 4);
  DatasetHandle neighbours = open_dataset(schema::dataset::mesh_neighbours);
  const auto neighbour_rows =
      check_dataset(neighbours.get(), schema::dataset::mesh_neighbours, Element::uint32, 4);
  if (tet_rows != neighbour_rows)
    format_error("'/mesh/tets' has " + std::to_string(tet_rows) +
                 " rows but '/mesh/neighbours' has " + std::to_string(neighbour_rows));
  // Indices are 32-bit: no more vertices or tets than they can name.
  if (vertex_rows > 0xffffffffu || tet_rows >= 0xffffffffu)
    format_error("the mesh has " + std::to_string(vertex_rows) + " vertices and " +
                 std::to_string(tet_rows) + " tets, more than 32-bit indices can name");
  tet_count = tet_rows;
}

void IndexReader::Impl::require_compact_links(hid_t group, const char* name) const {
  H5G_info_t info{};
  if (H5Gget_info(group, &info) < 0)
    hdf5_format_error("cannot inspect group '" + std::string(name) + "'");
  if (info.storage_type != H5G_STORAGE_TYPE_COMPACT)
    format_error(
        "group '" + std::string(name) + "' keeps its links in " +
        (info.storage_type == H5G_STORAGE_TYPE_DENSE ? "dense storage" : "a symbol table") +
        ", not in its object header as tetrapage writes them: rebuild the index");
}

void IndexReader::Impl::require_compact_storage(hid_t root) const {
  H5O_info_t info{};
  if (H5Oget_info2(root, &info, H5O_INFO_HDR | H5O_INFO_NUM_ATTRS) < 0)
    hdf5_format_error("cannot inspect the root group's object header");
  constexpr unsigned kAttributeMessage = 0x0C;  // HDF5's message type of a compact attribute
  if (info.num_attrs > 0 && (info.hdr.mesg.present & (std::uint64_t{1} << kAttributeMessage)) == 0)
    format_error(
        "the root's " + std::to_string(info.num_attrs) +
        " attributes are in dense storage, not in its object header as tetrapage writes them: "
        "rebuild the index");
  require_compact_links(root, "/");
  for (const char* name : {schema::group::mesh, schema::group::tables, schema::group::shards}) {
    if (H5Lexists(root, name, H5P_DEFAULT) <= 0) {
      detail::take_hdf5_error();
      continue;  // named as missing where it is needed
    }
    GroupHandle group(H5Gopen2(root, name, H5P_DEFAULT));
    // Appended, not "/" + name: GCC 12 warns (-Wrestrict, falsely) on that insertion here.
    std::string path = "/";
    path += name;
    if (!group) hdf5_format_error("cannot open group '" + path + "'");
    require_compact_links(group.get(), path.c_str());
  }
}

void IndexReader::Impl::list_tables() {
  const char* group_name = schema::group::tables;
  GroupHandle group(H5Lexists(file.get(), group_name, H5P_DEFAULT) > 0
                        ? H5Gopen2(file.get(), group_name, H5P_DEFAULT)
                        : H5I_INVALID_HID);
  if (!group) format_error("group '/tables' is missing");
  hsize_t index = 0;
  const auto collect = [](hid_t, const char* name, const H5L_info_t*, void* names) -> herr_t {
    static_cast<std::vector<std::string>*>(names)->emplace_back(name);
    return 0;
  };
  if (H5Literate(group.get(), H5_INDEX_NAME, H5_ITER_INC, &index, collect, &tables) < 0)
    hdf5_format_error("cannot list '/tables'");
  std::sort(tables.begin(), tables.end());
}

void IndexReader::Impl::check_header_values() const {
  const IndexHeader& h = header;
  if (h.precision != "float" && h.precision != "double" && h.precision != "exact")
    format_error("root attribute 'precision' is '" + h.precision +
                 "', expected 'exact', 'float' or 'double'");
  if (h.shard_count >= 0xffffffffu)
    format_error("root attribute 'shard_count' is " + std::to_string(h.shard_count) +
                 ", more than 2^32 - 1");
  const double distance = h.max_rounding_distance;
  if (!std::isfinite(distance) || distance < 0)
    format_error("root attribute 'max_rounding_distance' is " + number_text(distance) +
                 ", expected a finite distance >= 0");
  if (h.precision != "float" && distance != 0)
    format_error("root attribute 'max_rounding_distance' is " + number_text(distance) +
                 ", but precision '" + h.precision + "' stores coordinates unrounded (expected 0)");
  const BoundingBox& b = h.bounds;
  if (is_empty_convention(b)) return;
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(b.lo[a]) || !std::isfinite(b.hi[a]))
      format_error("root attribute 'bounds' holds " +
                   number_text(!std::isfinite(b.lo[a]) ? b.lo[a] : b.hi[a]) + " on axis " +
                   "xyz"[a] + ", expected finite coordinates");
    if (b.lo[a] > b.hi[a])
      format_error("root attribute 'bounds' is inverted on axis " + std::string(1, "xyz"[a]) +
                   " (lo " + number_text(b.lo[a]) + ", hi " + number_text(b.hi[a]) + ")");
  }
}

bool IndexReader::Impl::is_empty_convention(const BoundingBox& b) {
  const BoundingBox empty;
  return b.lo == empty.lo && b.hi == empty.hi;
}

std::string IndexReader::Impl::number_text(double value) {
  std::string text;
  detail::append_double(text, value);
  return text;
}

void IndexReader::Impl::check_table_lengths() {
  const std::uint64_t shards = header.shard_count;
  using namespace schema::table;
  expected_lengths = {{std::string(shard_tet), shards},
                      {std::string(shard_kind), shards},
                      {std::string(shard_triangles), shards},
                      {std::string(shard_bounds), 6 * shards},
                      {std::string(tet_shard), tet_count},
                      {std::string(reference_points), 3 * tet_count},
                      {std::string(interior_offsets), tet_count + 1}};
  if (has_table_named(schema::table::component_part)) {
    const std::uint64_t components = table_length(schema::table::component_part);
    expected_lengths.emplace(schema::table::component_closed, components);
    if (components > file_bytes)
      format_error("'/tables/component_part' claims " + std::to_string(components) +
                   " entries, more than the " + std::to_string(file_bytes) + "-byte file can hold");
    expected_lengths.emplace(schema::table::component_bounds, 6 * components);
  }
  for (const auto& [name, expected] : expected_lengths) {
    if (!has_table_named(name)) continue;
    const std::uint64_t length = table_length(name);
    if (length != expected)
      format_error("'/tables/" + name + "' has " + std::to_string(length) + " entries, expected " +
                   std::to_string(expected) + " (" + length_reason(name) + ")");
  }
}

void IndexReader::Impl::check_header_counts() const {
  if (header.region_count != tet_count)
    format_error("root attribute 'region_count' is " + std::to_string(header.region_count) +
                 ", but '/mesh/tets' holds " + std::to_string(tet_count) + " tets");
  check_count_against_table<std::uint32_t>(schema::attribute::stored_triangles,
                                           header.stored_triangles, schema::table::shard_triangles);
  check_count_against_table<std::uint64_t>(schema::attribute::input_triangles,
                                           header.input_triangles, schema::table::part_triangles);
}

std::string IndexReader::Impl::length_reason(const std::string& name) {
  if (name.starts_with("shard_"))
    return name == schema::table::shard_bounds ? "6 per shard" : "one per shard";
  if (name.starts_with("component_"))
    return name == schema::table::component_bounds ? "6 per component" : "one per component";
  if (name == schema::table::reference_points) return "3 per tet";
  return name == schema::table::interior_offsets ? "one per tet, and one" : "one per tet";
}

std::uint64_t IndexReader::Impl::table_length(std::string_view name) const {
  const std::string dataset_name = schema::table_path(name);
  DatasetHandle dataset = open_dataset(dataset_name);
  DataspaceHandle space(H5Dget_space(dataset.get()));
  hsize_t length = 0;
  if (!space || H5Sget_simple_extent_ndims(space.get()) != 1 ||
      H5Sget_simple_extent_dims(space.get(), &length, nullptr) < 0)
    format_error("'" + dataset_name + "' is not a 1-D dataset");
  return length;
}

void IndexReader::Impl::check_bounds_against_data() const {
  const BoundingBox& b = header.bounds;
  const bool empty_model = is_empty_convention(b);
  BoundingBox mesh_box;
  for (const Vec3& v : mesh_vertices()) mesh_box.extend(v);
  if (!empty_model && tet_count > 0)
    for (int a = 0; a < 3; ++a)
      if (!(mesh_box.lo[a] <= b.lo[a] && b.hi[a] <= mesh_box.hi[a]))
        format_error("root attribute 'bounds' [" + number_text(b.lo[a]) + ", " +
                     number_text(b.hi[a]) + "] on axis " + "xyz"[a] +
                     " is not inside the coarse mesh's [" + number_text(mesh_box.lo[a]) + ", " +
                     number_text(mesh_box.hi[a]) + "]");
  if (!has_table_named(schema::table::shard_bounds)) return;
  const auto boxes = read_table<double>(schema::table::shard_bounds);
  for (std::size_t s = 0; 6 * s + 5 < boxes.size(); ++s) {
    const BoundingBox box{{boxes[6 * s], boxes[6 * s + 1], boxes[6 * s + 2]},
                          {boxes[6 * s + 3], boxes[6 * s + 4], boxes[6 * s + 5]}};
    if (is_empty_convention(box)) continue;  // a shard without triangles
    for (int a = 0; a < 3; ++a) {
      const double slack =
          header.max_rounding_distance + 0x1p-40 * std::max(std::fabs(b.lo[a]), std::fabs(b.hi[a]));
      if (!empty_model && b.lo[a] - slack <= box.lo[a] && box.hi[a] <= b.hi[a] + slack) continue;
      const std::string shard_box = "shard " + std::to_string(s) + "'s box [" +
                                    number_text(box.lo[a]) + ", " + number_text(box.hi[a]) +
                                    "] on axis " + "xyz"[a] + " ('/tables/shard_bounds')";
      if (empty_model)
        format_error("root attribute 'bounds' is the empty box, but " + shard_box + " is not");
      format_error("root attribute 'bounds' [" + number_text(b.lo[a]) + ", " +
                   number_text(b.hi[a]) + "] does not hold " + shard_box);
    }
  }
}

std::uint64_t IndexReader::Impl::check_dataset(hid_t dataset, const std::string& name,
                                               Element element, std::uint64_t columns) const {
  DatatypeHandle type(H5Dget_type(dataset));
  DataspaceHandle space(H5Dget_space(dataset));
  if (!type || !space) hdf5_format_error("cannot inspect '" + name + "'");
  if (!type_matches(type.get(), element))
    format_error("'" + name + "' holds " + describe_type(type.get()) + ", expected " +
                 element_name(element));
  const int rank = H5Sget_simple_extent_ndims(space.get());
  const int expected_rank = columns == 0 ? 1 : 2;
  std::array<hsize_t, 2> dims{0, 0};
  if (rank != expected_rank || H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr) < 0)
    format_error("'" + name + "' has rank " + std::to_string(rank) + ", expected " +
                 std::to_string(expected_rank));
  if (columns != 0 && dims[1] != columns)
    format_error("'" + name + "' has " + std::to_string(dims[1]) + " columns, expected " +
                 std::to_string(columns));
  return dims[0];
}

void IndexReader::Impl::check_dataset_size(hid_t dataset, const std::string& name, Element element,
                                           std::uint64_t rows, std::uint64_t columns) const {
  PropertyListHandle creation(H5Dget_create_plist(dataset));
  if (!creation) hdf5_format_error("cannot inspect '" + name + "'");
  std::uint64_t ratio = 1;
  const int filters = H5Pget_nfilters(creation.get());
  for (int f = 0; f < filters; ++f) {
    unsigned flags = 0;
    std::size_t values = 0;
    if (H5Pget_filter2(creation.get(), static_cast<unsigned>(f), &flags, &values, nullptr, 0,
                       nullptr, nullptr) != H5Z_FILTER_FLETCHER32)
      ratio = kMaxFilterRatio;
  }
  const std::uint64_t row_bytes = std::max<std::uint64_t>(columns, 1) * element_bytes(element);
  if (rows > file_bytes / row_bytes * ratio)
    format_error("'" + name + "' claims " + std::to_string(rows) + " rows of " +
                 std::to_string(row_bytes) + " bytes, more than the " + std::to_string(file_bytes) +
                 "-byte file can hold");
  if (H5Pget_layout(creation.get()) != H5D_CHUNKED) return;
  // HDF5 allocates a whole chunk to read one: a damaged chunk shape must not size gigabytes.
  std::array<hsize_t, 2> chunk{1, 1};
  const int rank = H5Pget_chunk(creation.get(), 2, chunk.data());
  std::uint64_t chunk_bytes = element_bytes(element);
  for (int d = 0; d < std::min(rank, 2); ++d)
    chunk_bytes = chunk[d] > kMaxChunkBytes
                      ? kMaxChunkBytes + 1
                      : std::min<std::uint64_t>(chunk_bytes * chunk[d], kMaxChunkBytes + 1);
  if (rank < 1 || chunk[0] == 0 || chunk_bytes > kMaxChunkBytes)
    format_error("'" + name + "' has chunks of " + std::to_string(chunk[0]) + " x " +
                 std::to_string(chunk[1]) + " elements, more than " +
                 std::to_string(kMaxChunkBytes) + " bytes");
  check_stored_chunks(dataset, name, rows, chunk[0]);
}

void IndexReader::Impl::check_stored_chunks(hid_t dataset, const std::string& name,
                                            std::uint64_t rows, std::uint64_t chunk_rows) const {
  const std::uint64_t chunks = rows / chunk_rows + (rows % chunk_rows != 0);
  if (chunks > file_bytes / kMinStoredChunkBytes)  // the writer stores every chunk it uses
    format_error("'" + name + "' claims " + std::to_string(chunks) + " chunks of " +
                 std::to_string(chunk_rows) + " rows, more than the " + std::to_string(file_bytes) +
                 "-byte file can store");
  for (std::uint64_t first = 0; first < rows; first += chunk_rows) {
    std::array<hsize_t, 2> coordinate{first, 0};
    hsize_t stored = 0;
    if (H5Dget_chunk_storage_size(dataset, coordinate.data(), &stored) < 0) {
      detail::take_hdf5_error();  // an unallocated chunk reads as fill values
      continue;
    }
    if (stored > file_bytes)
      format_error("'" + name + "' stores the chunk at row " + std::to_string(first) + " in " +
                   std::to_string(stored) + " bytes, more than the " + std::to_string(file_bytes) +
                   "-byte file");
  }
}

void IndexReader::Impl::check_shard_data_layout() {
  const std::string name = schema::dataset::shard_data;
  // 8-byte words (the shuffle filter's element); extents and chunks are counted in bytes.
  const std::uint64_t words = check_dataset(shard_data.get(), name, Element::uint64, 0);
  if (words > file_bytes / kMinStoredChunkBytes * (kMaxChunkBytes / kWordBytes))
    format_error("'" + name + "' claims " + std::to_string(words) + " words, more than the " +
                 std::to_string(file_bytes) + "-byte file can hold");
  data_extent = words * kWordBytes;
  PropertyListHandle creation(H5Dget_create_plist(shard_data.get()));
  if (!creation) hdf5_format_error("cannot inspect '" + name + "'");
  if (H5Pget_layout(creation.get()) != H5D_CHUNKED) format_error("'" + name + "' is not chunked");
  hsize_t chunk = 0;
  if (H5Pget_chunk(creation.get(), 1, &chunk) != 1 || chunk == 0 ||
      chunk > kMaxChunkBytes / kWordBytes)
    format_error("'" + name + "' has an unusable chunk shape (" + std::to_string(chunk) +
                 " words; at most " + std::to_string(kMaxChunkBytes / kWordBytes) + ")");
  chunk_bytes = static_cast<std::uint32_t>(chunk * kWordBytes);
  // Every chunk a shard uses is stored, in a few bytes at least: the chunk table that locating
  // them fills (inspect, validate) is sized by this.
  const std::uint64_t chunk_count = data_extent / chunk_bytes + (data_extent % chunk_bytes != 0);
  if (chunk_count > file_bytes / kMinStoredChunkBytes)
    format_error("'" + name + "' claims " + std::to_string(data_extent / kWordBytes) + " words (" +
                 std::to_string(data_extent) + " bytes) in " + std::to_string(chunk_count) +
                 " chunks, more than the " + std::to_string(file_bytes) + "-byte file can hold");
  const int filters = H5Pget_nfilters(creation.get());
  std::array<H5Z_filter_t, 3> expected{H5Z_FILTER_SHUFFLE, detail::kLz4FilterId,
                                       H5Z_FILTER_FLETCHER32};
  bool pipeline_ok = filters == 3;
  std::string found;
  for (int f = 0; f < filters; ++f) {
    unsigned flags = 0;
    std::size_t values = 0;
    const H5Z_filter_t filter = H5Pget_filter2(creation.get(), static_cast<unsigned>(f), &flags,
                                               &values, nullptr, 0, nullptr, nullptr);
    found += (f == 0 ? "" : ", ") + std::to_string(filter);
    if (f < 3 && filter != expected[static_cast<std::size_t>(f)]) pipeline_ok = false;
  }
  if (!pipeline_ok)
    format_error("'" + name + "' has filters [" + found + "], expected [" +
                 std::to_string(H5Z_FILTER_SHUFFLE) + ", " + std::to_string(detail::kLz4FilterId) +
                 ", " + std::to_string(H5Z_FILTER_FLETCHER32) + "] (shuffle, LZ4, fletcher32)");
}

std::vector<std::string> IndexReader::Impl::extent_problems() const {
  std::vector<std::string> problems;
  std::vector<std::uint32_t> order;
  for (std::uint32_t s = 0; s < offsets.size(); ++s) {
    const std::string shard = "shard " + std::to_string(s);
    if (offsets[s] % chunk_bytes != 0)
      problems.push_back(shard + " starts at byte " + std::to_string(offsets[s]) +
                         ", not on a chunk boundary (chunks of " + std::to_string(chunk_bytes) +
                         " bytes)");
    else if (offsets[s] > data_extent || sizes[s] > data_extent - offsets[s])
      problems.push_back(shard + " spans bytes [" + std::to_string(offsets[s]) + ", " +
                         std::to_string(offsets[s]) + " + " + std::to_string(sizes[s]) +
                         "), beyond the " + std::to_string(data_extent) + " bytes of /shards/data");
    else if (sizes[s] > 0)
      order.push_back(s);
  }
  std::sort(order.begin(), order.end(),
            [&](std::uint32_t a, std::uint32_t b) { return offsets[a] < offsets[b]; });
  for (std::size_t i = 1; i < order.size(); ++i) {
    const auto before = order[i - 1], after = order[i];
    if (offsets[before] + chunk_count(before) * chunk_bytes > offsets[after])
      problems.push_back("shards " + std::to_string(before) + " and " + std::to_string(after) +
                         " share chunks (offsets " + std::to_string(offsets[before]) + " and " +
                         std::to_string(offsets[after]) + ")");
  }
  return problems;
}

void IndexReader::Impl::check_opened_index() {
  {
    GroupHandle root(H5Gopen2(file.get(), "/", H5P_DEFAULT));
    if (!root) hdf5_format_error("cannot open the root group");
    require_compact_storage(root.get());
    read_header(root.get());
  }
  check_header_values();
  check_mesh_shapes();
  offsets = read_dataset<std::uint64_t>(schema::dataset::shard_offsets, 0, header.shard_count,
                                        "root attribute 'shard_count'");
  sizes = read_dataset<std::uint64_t>(schema::dataset::shard_sizes, 0, header.shard_count,
                                      "root attribute 'shard_count'");
  list_tables();
  check_table_lengths();
  check_header_counts();
  shard_data = open_dataset(schema::dataset::shard_data);
  check_shard_data_layout();
  const auto problems = extent_problems();
  if (!problems.empty())
    format_error("inconsistent shard extents: " + problems.front() +
                 (problems.size() > 1
                      ? " (and " + std::to_string(problems.size() - 1) + " more problems)"
                      : std::string()));
  check_bounds_against_data();
}

void IndexReader::Impl::check_stored_claim(std::uint32_t shard, std::uint64_t k,
                                           std::uint64_t stored_bytes) const {
  if (stored_bytes * kMaxLz4Ratio < payload_in_chunk(shard, k))
    format_error(chunk_name(shard, k) + " holds " + std::to_string(stored_bytes) +
                 " stored bytes for " + std::to_string(payload_in_chunk(shard, k)) +
                 " bytes of payload, more than LZ4 decodes to");
}

}  // namespace tetrapage
