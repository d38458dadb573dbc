#include "tetrapage/formats/index/IndexWriter.h"
#include "tetrapage/formats/index/IndexSchema.h"

#include <fcntl.h>
#include <hdf5.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <set>
#include <string>
#include <system_error>
#include <vector>

#include "ChunkCodec.h"
#include "Hdf5Handle.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/TemporaryFiles.h"
#include "tetrapage/formats/mesh/FileChecks.h"

namespace tetrapage {

namespace schema = index_schema;

using detail::AttributeHandle;
using detail::DatasetHandle;
using detail::DataspaceHandle;
using detail::DatatypeHandle;
using detail::FileHandle;
using detail::GroupHandle;
using detail::PropertyListHandle;

namespace {

constexpr std::uint32_t kMinChunkBytes = 1024;
// Links per group and attributes per object kept in the object header (HDF5's limit: 65535).
constexpr unsigned kMaxCompactLinks = 4096;
constexpr unsigned kMaxCompactAttributes = 256;
constexpr std::uint32_t kMaxChunkBytes = 64u << 20;
// /shards/data is stored as 8-byte little-endian words: the shuffle's element (ChunkCodec.h).
constexpr std::uint64_t kWordBytes = detail::kShuffleElementBytes;
/// Chunks of the mesh and table datasets hold about this many bytes.
constexpr std::uint64_t kTableChunkBytes = 256 * 1024;

template <class T>
hid_t memory_type();
template <>
hid_t memory_type<std::uint8_t>() { return H5T_NATIVE_UINT8; }
template <>
hid_t memory_type<std::uint32_t>() { return H5T_NATIVE_UINT32; }
template <>
hid_t memory_type<std::uint64_t>() { return H5T_NATIVE_UINT64; }
template <>
hid_t memory_type<double>() { return H5T_NATIVE_DOUBLE; }

// The file types are fixed (little endian) so that files are byte-identical across hosts.
template <class T>
hid_t file_type();
template <>
hid_t file_type<std::uint8_t>() { return H5T_STD_U8LE; }
template <>
hid_t file_type<std::uint32_t>() { return H5T_STD_U32LE; }
template <>
hid_t file_type<std::uint64_t>() { return H5T_STD_U64LE; }
template <>
hid_t file_type<double>() { return H5T_IEEE_F64LE; }

std::string created_by_text() {
  unsigned major = 0, minor = 0, release = 0;
  H5get_libversion(&major, &minor, &release);
  return "tetrapage formats (HDF5 " + std::to_string(major) + "." + std::to_string(minor) + "." +
         std::to_string(release) + ")";
}

}  // namespace

struct IndexWriter::Impl {
  std::filesystem::path path;
  std::filesystem::path temporary;
  std::unique_ptr<TemporaryFileGuard> temporary_guard;  ///< removed by SIGINT/SIGTERM handlers
  IndexWriterOptions options;
  FileHandle file;
  GroupHandle mesh_group;
  GroupHandle tables_group;
  GroupHandle shards_group;
  DatasetHandle shard_data;
  std::vector<std::uint64_t> offsets;
  std::vector<std::uint64_t> sizes;
  std::uint64_t data_extent = 0;  ///< bytes in /shards/data, a multiple of the chunk size
  std::uint64_t stored_bytes = 0;
  std::set<std::string, std::less<>> tables;
  bool mesh_written = false;
  bool file_created = false;
  bool committed = false;
  bool failed = false;

  ~Impl() {
    close_all();
    if (file_created && !committed) {
      std::error_code ignored;
      std::filesystem::remove(temporary, ignored);
    }
  }

  void close_all() {
    shard_data.reset();
    shards_group.reset();
    tables_group.reset();
    mesh_group.reset();
    file.reset();
  }

  [[noreturn]] void fail(const std::string& what) {
    failed = true;
    throw IoError("cannot write " + what + " of index '" + path.string() + "' (temporary file '" +
                  temporary.string() + "'): " + detail::take_hdf5_error());
  }
  void check(herr_t status, const std::string& what) {
    if (status < 0) fail(what);
  }
  hid_t check_id(hid_t id, const std::string& what) {
    if (id < 0) fail(what);
    return id;
  }

  void ensure_writable(const char* action) const {
    if (committed)
      throw InputError("cannot " + std::string(action) + ": index '" + path.string() +
                       "' is already committed");
    if (failed)
      throw InputError("cannot " + std::string(action) + ": an earlier write to index '" +
                       path.string() + "' failed");
  }

  /// A chunked, checksummed dataset whose first dimension may grow; shuffled and compressed
  /// with LZ4 when `compress` (the shard data).
  DatasetHandle create_dataset(hid_t parent, const std::string& name, const std::string& what,
                               hid_t type, std::span<const hsize_t> dims,
                               std::span<const hsize_t> chunk, bool compress) {
    std::array<hsize_t, 2> max_dims{H5S_UNLIMITED, 0};
    for (std::size_t d = 1; d < dims.size(); ++d) max_dims[d] = dims[d];
    DataspaceHandle space(check_id(
        H5Screate_simple(static_cast<int>(dims.size()), dims.data(), max_dims.data()),
        "the dataspace of " + what));
    PropertyListHandle creation(check_id(H5Pcreate(H5P_DATASET_CREATE), "properties of " + what));
    check(H5Pset_chunk(creation.get(), static_cast<int>(chunk.size()), chunk.data()),
          "the chunking of " + what);
    // Order matters: shuffle, LZ4, then the checksum over the compressed bytes. LZ4 need not
    // be registered here: chunks arrive compressed (H5Dwrite_chunk), and an optional filter
    // that HDF5 cannot find is kept in the pipeline for readers. Its one parameter is the
    // block size, the chunk's size: one block a chunk, as encode_chunk writes.
    if (compress) {
      check(H5Pset_shuffle(creation.get()), "the shuffle filter of " + what);
      const unsigned block_bytes = static_cast<unsigned>(options.chunk_bytes);
      check(H5Pset_filter(creation.get(), detail::kLz4FilterId, H5Z_FLAG_OPTIONAL, 1, &block_bytes),
            "the LZ4 filter of " + what);
    }
    check(H5Pset_fletcher32(creation.get()), "the Fletcher-32 filter of " + what);
    return DatasetHandle(check_id(H5Dcreate2(parent, name.c_str(), type, space.get(),
                                             H5P_DEFAULT, creation.get(), H5P_DEFAULT),
                                  what));
  }

  template <class T>
  void write_array(hid_t parent, const std::string& name, const std::string& what,
                   const T* data, std::uint64_t rows, std::uint64_t columns) {
    const std::uint64_t row_bytes = std::max<std::uint64_t>(columns, 1) * sizeof(T);
    const hsize_t chunk_rows =
        std::clamp<std::uint64_t>(kTableChunkBytes / row_bytes, 1, std::max<std::uint64_t>(rows, 1));
    const std::array<hsize_t, 2> dims{rows, columns};
    const std::array<hsize_t, 2> chunk{chunk_rows, columns};
    const std::size_t rank = columns == 0 ? 1 : 2;
    // The mesh and the tables are read whole when an index opens: stored plain (checksummed),
    // since inflating them was two thirds of the open time of a 100M-triangle index.
    DatasetHandle dataset = create_dataset(parent, name, what, file_type<T>(),
                                           std::span(dims).first(rank),
                                           std::span(chunk).first(rank), false);
    if (rows > 0)
      check(H5Dwrite(dataset.get(), memory_type<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, data),
            what);
    if (!dataset.close()) fail(what + " (closing it)");
  }

  template <class T>
  void write_table(std::string_view name, std::span<const T> values) {
    ensure_writable("write a table");
    if (name.empty() || name == "." || name == ".." || name.find('/') != std::string_view::npos)
      throw InputError("invalid table name '" + std::string(name) + "' for index '" +
                       path.string() + "': it must be non-empty, not '.' or '..', without '/'");
    if (tables.size() >= kMaxCompactLinks)
      throw InputError("index '" + path.string() + "' cannot hold more than " + std::to_string(kMaxCompactLinks) +
                       " tables (table '" + std::string(name) + "')");
    if (tables.contains(name))
      throw InputError("table '" + std::string(name) + "' is written twice to index '" +
                       path.string() + "'");
    const std::string what = "table /tables/" + std::string(name);
    write_array<T>(tables_group.get(), std::string(name), what, values.data(), values.size(), 0);
    tables.emplace(name);
  }

  void write_string_attribute(hid_t object, const char* name, const std::string& value) {
    const std::string what = "attribute '" + std::string(name) + "'";
    DatatypeHandle type(check_id(H5Tcopy(H5T_C_S1), what));
    // Variable length: any length (a build report of megabytes) and h5py reads it as str.
    check(H5Tset_size(type.get(), H5T_VARIABLE), what);
    check(H5Tset_cset(type.get(), H5T_CSET_UTF8), what);
    DataspaceHandle space(check_id(H5Screate(H5S_SCALAR), what));
    AttributeHandle attribute(
        check_id(H5Acreate2(object, name, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT), what));
    const char* text = value.c_str();
    check(H5Awrite(attribute.get(), type.get(), &text), what);
    if (!attribute.close()) fail(what + " (closing it)");
  }

  template <class T>
  void write_number_attribute(hid_t object, const char* name, std::span<const T> values,
                              bool scalar) {
    const std::string what = "attribute '" + std::string(name) + "'";
    const hsize_t count = values.size();
    DataspaceHandle space(
        check_id(scalar ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &count, nullptr), what));
    AttributeHandle attribute(check_id(
        H5Acreate2(object, name, file_type<T>(), space.get(), H5P_DEFAULT, H5P_DEFAULT), what));
    check(H5Awrite(attribute.get(), memory_type<T>(), values.data()), what);
    if (!attribute.close()) fail(what + " (closing it)");
  }
  template <class T>
  void write_number_attribute(hid_t object, const char* name, T value) {
    write_number_attribute<T>(object, name, std::span<const T>(&value, 1), true);
  }
};

IndexWriter::IndexWriter(std::filesystem::path path, IndexWriterOptions options)
    : impl_(std::make_unique<Impl>()) {
  detail::enter_hdf5();
  Impl& w = *impl_;
  w.path = std::move(path);
  w.temporary = w.path;
  w.temporary += ".tmp-" + std::to_string(::getpid());
  w.options = options;
  check_outputs(std::span<const std::filesystem::path>(&w.path, 1), {});  // never rename over a device
  if (options.chunk_bytes < kMinChunkBytes || options.chunk_bytes > kMaxChunkBytes ||
      options.chunk_bytes % kWordBytes != 0)
    throw InputError("index '" + w.path.string() + "': chunk size " +
                     std::to_string(options.chunk_bytes) + " bytes is outside [" +
                     std::to_string(kMinChunkBytes) + ", " + std::to_string(kMaxChunkBytes) +
                     "] or not a multiple of 8");
  PropertyListHandle access(w.check_id(H5Pcreate(H5P_FILE_ACCESS), "file access properties"));
  // SEMI: closing the file fails if a handle is still open, so commit() cannot leave data
  // unwritten behind a forgotten handle.
  w.check(H5Pset_fclose_degree(access.get(), H5F_CLOSE_SEMI), "file access properties");
  // HDF5 1.10's formats: superblock 3, object headers 2 and their chunk indexes carry
  // checksums that HDF5 verifies before decoding, so a damaged index is refused as such
  // instead of reaching HDF5's decoders of damaged metadata (docs/RELIABILITY.md).
  w.check(H5Pset_libver_bounds(access.get(), H5F_LIBVER_V110, H5F_LIBVER_V110), "file access properties");
  // Registered before it exists: a signal arriving as it is created still removes it.
  w.temporary_guard = std::make_unique<TemporaryFileGuard>(w.temporary);
  // Links and attributes stay in their (checksummed) object headers: never in the dense
  // storage of fractal heaps and B-trees, whose damaged-file paths crash HDF5 1.10, and which
  // the reader therefore refuses.
  PropertyListHandle creation(w.check_id(H5Pcreate(H5P_FILE_CREATE), "file creation properties"));
  w.check(H5Pset_link_phase_change(creation.get(), kMaxCompactLinks, kMaxCompactLinks),
          "file creation properties");
  w.check(H5Pset_attr_phase_change(creation.get(), kMaxCompactAttributes, kMaxCompactAttributes),
          "file creation properties");
  hid_t file = H5Fcreate(w.temporary.c_str(), H5F_ACC_TRUNC, creation.get(), access.get());
  if (file < 0)
    throw IoError("cannot create index '" + w.path.string() + "' (temporary file '" +
                  w.temporary.string() + "'): " + detail::take_hdf5_error());
  w.file = FileHandle(file);
  w.file_created = true;
  PropertyListHandle group_creation(w.check_id(H5Pcreate(H5P_GROUP_CREATE), "group creation properties"));
  w.check(H5Pset_link_phase_change(group_creation.get(), kMaxCompactLinks, kMaxCompactLinks),
          "group creation properties");
  const auto create_group = [&](const char* name) {
    return GroupHandle(w.check_id(H5Gcreate2(file, name, H5P_DEFAULT, group_creation.get(), H5P_DEFAULT),
                                  std::string("group /") + name));
  };
  w.mesh_group = create_group(schema::group::mesh);
  w.tables_group = create_group(schema::group::tables);
  w.shards_group = create_group(schema::group::shards);
  const std::array<hsize_t, 1> empty{0};
  // 8-byte words, so that HDF5's shuffle filter puts byte k of every word together.
  const std::array<hsize_t, 1> chunk{options.chunk_bytes / kWordBytes};
  w.shard_data = w.create_dataset(file, schema::dataset::shard_data,
                                  std::string("dataset ") + schema::dataset::shard_data,
                                  H5T_STD_U64LE, empty, chunk, true);
}

IndexWriter::~IndexWriter() = default;
IndexWriter::IndexWriter(IndexWriter&&) noexcept = default;
IndexWriter& IndexWriter::operator=(IndexWriter&&) noexcept = default;

void IndexWriter::write_mesh(const TetMesh& mesh) {
  detail::enter_hdf5();
  Impl& w = *impl_;
  w.ensure_writable("write the mesh");
  if (w.mesh_written)
    throw InputError("the mesh is written twice to index '" + w.path.string() + "'");
  const std::string where = "mesh for index '" + w.path.string() + "'";
  if (mesh.neighbours.size() != mesh.tets.size())
    throw InputError(where + " has " + std::to_string(mesh.tets.size()) + " tets but " +
                     std::to_string(mesh.neighbours.size()) + " neighbour rows");
  if (mesh.vertices.size() >= TetMesh::no_neighbour || mesh.tets.size() >= TetMesh::no_neighbour)
    throw InputError(where + " has too many vertices or tets for 32-bit indices");
  for (std::size_t t = 0; t < mesh.tets.size(); ++t)
    for (int i = 0; i < 4; ++i) {
      if (mesh.tets[t][i] >= mesh.vertices.size())
        throw InputError(where + ": tet " + std::to_string(t) + " corner " + std::to_string(i) +
                         " is vertex " + std::to_string(mesh.tets[t][i]) + " of " +
                         std::to_string(mesh.vertices.size()));
      const auto neighbour = mesh.neighbours[t][i];
      if (neighbour != TetMesh::no_neighbour && neighbour >= mesh.tets.size())
        throw InputError(where + ": tet " + std::to_string(t) + " neighbour " +
                         std::to_string(i) + " is tet " + std::to_string(neighbour) + " of " +
                         std::to_string(mesh.tets.size()));
    }
  static_assert(sizeof(Vec3) == 3 * sizeof(double));
  static_assert(sizeof(std::array<std::uint32_t, 4>) == 4 * sizeof(std::uint32_t));
  // By absolute path, from the file: the names live in IndexSchema.h.
  const hid_t group = w.file.get();
  using namespace schema::dataset;
  w.write_array<double>(group, mesh_vertices, std::string("dataset ") + mesh_vertices,
                        mesh.vertices.empty() ? nullptr : mesh.vertices.front().data(),
                        mesh.vertices.size(), 3);
  w.write_array<std::uint32_t>(group, mesh_tets, std::string("dataset ") + mesh_tets,
                               mesh.tets.empty() ? nullptr : mesh.tets.front().data(),
                               mesh.tets.size(), 4);
  w.write_array<std::uint32_t>(group, mesh_neighbours, std::string("dataset ") + mesh_neighbours,
                               mesh.neighbours.empty() ? nullptr : mesh.neighbours.front().data(),
                               mesh.neighbours.size(), 4);
  w.mesh_written = true;
}

void IndexWriter::write_table(std::string_view name, std::span<const std::uint8_t> values) {
  detail::enter_hdf5();
  impl_->write_table(name, values);
}
void IndexWriter::write_table(std::string_view name, std::span<const std::uint32_t> values) {
  detail::enter_hdf5();
  impl_->write_table(name, values);
}
void IndexWriter::write_table(std::string_view name, std::span<const std::uint64_t> values) {
  detail::enter_hdf5();
  impl_->write_table(name, values);
}
void IndexWriter::write_table(std::string_view name, std::span<const double> values) {
  detail::enter_hdf5();
  impl_->write_table(name, values);
}

ChunkCompression parse_chunk_compression(std::string_view name) {
  if (name == "lz4") return ChunkCompression::lz4;
  if (name == "none") return ChunkCompression::none;
  throw InputError("unknown chunk compression '" + std::string(name) + "' (expected lz4 or none)");
}

std::string_view to_string(ChunkCompression compression) {
  return compression == ChunkCompression::none ? "none" : "lz4";
}

EncodedShard encode_shard(std::span<const std::byte> payload, const IndexWriterOptions& options) {
  if (options.chunk_bytes < kMinChunkBytes || options.chunk_bytes > kMaxChunkBytes ||
      options.chunk_bytes % kWordBytes != 0)
    throw InputError("encode_shard: chunk size " + std::to_string(options.chunk_bytes) + " out of range");
  EncodedShard shard;
  shard.payload_bytes = payload.size();
  shard.chunk_bytes = options.chunk_bytes;
  const std::uint64_t chunk_bytes = options.chunk_bytes;
  const std::uint64_t chunks = (payload.size() + chunk_bytes - 1) / chunk_bytes;
  std::vector<std::byte> padded;
  detail::EncodedChunk encoded;
  for (std::uint64_t k = 0; k < chunks; ++k) {
    auto piece = payload.subspan(k * chunk_bytes, std::min<std::uint64_t>(chunk_bytes, payload.size() - k * chunk_bytes));
    if (piece.size() < chunk_bytes) {
      // Zero padding up to the chunk boundary: the next shard starts on a fresh chunk.
      padded.assign(chunk_bytes, std::byte{0});
      std::copy(piece.begin(), piece.end(), padded.begin());
      piece = padded;
    }
    if (options.compression == ChunkCompression::none)
      detail::encode_chunk_uncompressed(piece, std::min<std::uint64_t>(chunk_bytes, payload.size() - k * chunk_bytes),
                                        encoded);
    else
      detail::encode_chunk(piece, encoded);
    shard.chunks.push_back(encoded.bytes);
    shard.filter_masks.push_back(encoded.filter_mask);
  }
  return shard;
}

std::uint32_t IndexWriter::append_shard(std::span<const std::byte> payload) {
  return append_encoded_shard(encode_shard(payload, impl_->options));
}

std::uint32_t IndexWriter::append_encoded_shard(const EncodedShard& encoded) {
  detail::enter_hdf5();
  Impl& w = *impl_;
  w.ensure_writable("append a shard");
  if (w.offsets.size() >= 0xffffffffu)
    throw InputError("index '" + w.path.string() + "' cannot hold more than 2^32 - 1 shards");
  const std::uint64_t chunk_bytes = w.options.chunk_bytes;
  if (encoded.chunk_bytes != chunk_bytes || encoded.chunks.size() != encoded.filter_masks.size() ||
      encoded.chunks.size() != (encoded.payload_bytes + chunk_bytes - 1) / chunk_bytes)
    throw InputError("index '" + w.path.string() + "': a shard encoded for chunks of " +
                     std::to_string(encoded.chunk_bytes) + " bytes cannot be appended to chunks of " +
                     std::to_string(chunk_bytes));
  const auto shard = static_cast<std::uint32_t>(w.offsets.size());
  const std::uint64_t chunks = encoded.chunks.size();
  const std::uint64_t offset = w.data_extent;
  if (chunks > 0) {
    const std::string what = "shard " + std::to_string(shard);
    const std::uint64_t extent = w.data_extent + chunks * chunk_bytes;
    hsize_t extent_words = extent / kWordBytes;
    w.check(H5Dset_extent(w.shard_data.get(), &extent_words), "the extent of /shards/data for " + what);
    for (std::uint64_t k = 0; k < chunks; ++k) {
      const hsize_t chunk_offset = (offset + k * chunk_bytes) / kWordBytes;
      w.check(H5Dwrite_chunk(w.shard_data.get(), H5P_DEFAULT, encoded.filter_masks[k], &chunk_offset,
                             encoded.chunks[k].size(), encoded.chunks[k].data()),
              "chunk " + std::to_string((offset + k * chunk_bytes) / chunk_bytes) + " of /shards/data (" + what + ")");
      w.stored_bytes += encoded.chunks[k].size();
    }
    w.data_extent = extent;
  }
  w.offsets.push_back(offset);
  w.sizes.push_back(encoded.payload_bytes);
  return shard;
}

const IndexWriterOptions& IndexWriter::options() const { return impl_->options; }

std::uint32_t IndexWriter::shard_count() const {
  return static_cast<std::uint32_t>(impl_->offsets.size());
}
std::uint64_t IndexWriter::stored_shard_bytes() const { return impl_->stored_bytes; }
const std::filesystem::path& IndexWriter::path() const { return impl_->path; }
const std::filesystem::path& IndexWriter::temporary_path() const { return impl_->temporary; }

std::uint64_t IndexWriter::commit(const IndexHeader& header) {
  detail::enter_hdf5();
  Impl& w = *impl_;
  w.ensure_writable("commit");
  const std::string where = "index '" + w.path.string() + "'";
  if (header.version != kIndexVersion)
    throw InputError(where + ": header version " + std::to_string(header.version) +
                     ", but this writer writes version " + std::to_string(kIndexVersion));
  if (header.precision != "float" && header.precision != "double" && header.precision != "exact")
    throw InputError(where + ": header precision '" + header.precision +
                     "' is not 'exact', 'float' or 'double'");
  if (header.shard_count != 0 && header.shard_count != w.offsets.size())
    throw InputError(where + ": header says " + std::to_string(header.shard_count) +
                     " shards, but " + std::to_string(w.offsets.size()) + " were appended");
  if (!w.mesh_written) write_mesh(TetMesh{});

  w.write_array<std::uint64_t>(w.file.get(), schema::dataset::shard_offsets,
                               std::string("dataset ") + schema::dataset::shard_offsets,
                               w.offsets.data(), w.offsets.size(), 0);
  w.write_array<std::uint64_t>(w.file.get(), schema::dataset::shard_sizes,
                               std::string("dataset ") + schema::dataset::shard_sizes,
                               w.sizes.data(), w.sizes.size(), 0);
  {
    GroupHandle root(w.check_id(H5Gopen2(w.file.get(), "/", H5P_DEFAULT), "the root group"));
    const hid_t r = root.get();
    w.write_string_attribute(r, schema::attribute::format, std::string(kIndexFormatName));
    w.write_number_attribute<std::uint32_t>(r, schema::attribute::version, kIndexVersion);
    w.write_string_attribute(r, schema::attribute::precision, header.precision);
    w.write_number_attribute<std::uint64_t>(r, schema::attribute::input_triangles,
                                            header.input_triangles);
    w.write_number_attribute<std::uint64_t>(r, schema::attribute::stored_triangles,
                                            header.stored_triangles);
    w.write_number_attribute<std::uint64_t>(r, schema::attribute::region_count,
                                            header.region_count);
    w.write_number_attribute<std::uint64_t>(r, schema::attribute::shard_count, w.offsets.size());
    w.write_number_attribute<double>(r, schema::attribute::max_rounding_distance,
                                     header.max_rounding_distance);
    const std::array<double, 6> bounds{header.bounds.lo[0], header.bounds.lo[1],
                                       header.bounds.lo[2], header.bounds.hi[0],
                                       header.bounds.hi[1], header.bounds.hi[2]};
    w.write_number_attribute<double>(r, schema::attribute::bounds, std::span<const double>(bounds),
                                     false);
    w.write_string_attribute(r, schema::attribute::source, header.source);
    w.write_string_attribute(r, schema::attribute::build_report, header.build_report_json);
    w.write_string_attribute(r, schema::attribute::created_by, created_by_text());
    w.write_string_attribute(r, schema::attribute::length_unit, header.length_unit);
    w.write_number_attribute<double>(r, schema::attribute::tessellation_deflection,
                                     header.tessellation_deflection);
    if (!root.close()) w.fail("the root group (closing it)");
  }
  if (!w.shard_data.close()) w.fail("dataset /shards/data (closing it)");
  if (!w.shards_group.close()) w.fail("group /shards (closing it)");
  if (!w.tables_group.close()) w.fail("group /tables (closing it)");
  if (!w.mesh_group.close()) w.fail("group /mesh (closing it)");
  if (!w.file.close()) w.fail("the file (closing it)");

  const auto io_failure = [&](const std::string& action, int error) {
    w.failed = true;
    return IoError("cannot " + action + " index '" + w.path.string() + "' (temporary file '" +
                   w.temporary.string() + "'): " + std::strerror(error));
  };
  // The rename must not become visible before the data: fsync the file, then the folder.
  const int descriptor = ::open(w.temporary.c_str(), O_RDONLY | O_CLOEXEC);
  if (descriptor < 0) throw io_failure("reopen to flush", errno);
  const int synced = ::fsync(descriptor);
  const int sync_error = errno;
  ::close(descriptor);
  if (synced != 0) throw io_failure("flush (fsync)", sync_error);
  if (::rename(w.temporary.c_str(), w.path.c_str()) != 0) throw io_failure("rename", errno);
  w.committed = true;
  const auto folder = w.path.has_parent_path() ? w.path.parent_path() : std::filesystem::path(".");
  const int folder_descriptor = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (folder_descriptor >= 0) {
    ::fsync(folder_descriptor);  // best effort: some file systems refuse it on folders
    ::close(folder_descriptor);
  }
  std::error_code size_error;
  const auto bytes = std::filesystem::file_size(w.path, size_error);
  if (size_error)
    throw IoError("cannot read the size of index '" + w.path.string() + "': " +
                  size_error.message());
  return bytes;
}

}  // namespace tetrapage
