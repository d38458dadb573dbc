#include "tetrapage/formats/index/IndexReader.h"

#include "IndexReaderImpl.h"

namespace tetrapage {

void IndexReader::Impl::ensure_located() const {
  std::call_once(located_once, [this] {
    const_cast<Impl*>(this)->locate_chunks();
    located.store(true, std::memory_order_release);
  });
}

void IndexReader::Impl::format_error(const std::string& what) const {
  throw FormatError(where() + ": " + what);
}

void IndexReader::Impl::hdf5_format_error(const std::string& what) const {
  throw FormatError(where() + ": " + what + ": " + detail::take_hdf5_error());
}

bool IndexReader::Impl::file_changed(std::uint64_t& bytes_now) const {
  if (in_memory) return false;
  struct stat status {};
  if (::fstat(descriptor.get(), &status) != 0) return false;
  bytes_now = static_cast<std::uint64_t>(status.st_size);
  return bytes_now != file_bytes || status.st_mtim.tv_sec != modified.tv_sec ||
         status.st_mtim.tv_nsec != modified.tv_nsec;
}

void IndexReader::Impl::shard_read_error(const std::string& what, const std::string& problem,
                                         bool read_zeros, bool hdf5) const {
  const std::string reason =
      (read_zeros ? std::string("it reads as zeros where data was stored") : problem) +
      (hdf5 ? ": " + detail::take_hdf5_error() : std::string());
  std::uint64_t bytes_now = 0;
  if (file_changed(bytes_now))
    format_error("the file changed or is truncated: " + what + ": " + reason + " (the file has " +
                 std::to_string(bytes_now) + " bytes, " + std::to_string(file_bytes) +
                 " when opened)");
  if (read_zeros) format_error("the file changed or is truncated: " + what + ": " + reason);
  format_error(what + ": " + reason);
}

void IndexReader::Impl::check_shard(std::uint32_t shard) const {
  if (shard >= offsets.size())
    throw InputError(where() + ": shard " + std::to_string(shard) + " does not exist (" +
                     std::to_string(offsets.size()) + " shards)");
}

std::uint64_t IndexReader::Impl::chunk_count(std::uint32_t shard) const {
  return (sizes[shard] + chunk_bytes - 1) / chunk_bytes;
}

std::string IndexReader::Impl::chunk_name(std::uint32_t shard, std::uint64_t k) const {
  const std::uint64_t c = first_chunk(shard) + k;
  std::string text = "shard " + std::to_string(shard) + ", chunk " + std::to_string(k) + " of " +
                     std::to_string(chunk_count(shard)) + " (chunk " + std::to_string(c) +
                     " of /shards/data";
  if (c < chunks.size() && chunks[c].address != kUnallocated)
    text += " at file offset " + std::to_string(chunks[c].address);
  return text + ")";
}

void IndexReader::Impl::open_file() {
  descriptor = Descriptor(::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC));
  if (descriptor.get() < 0) throw IoError("cannot open " + where() + ": " + std::strerror(errno));
  struct stat status {};
  if (::fstat(descriptor.get(), &status) != 0)
    throw IoError("cannot inspect " + where() + ": " + std::strerror(errno));
  if (!S_ISREG(status.st_mode)) throw IoError("cannot open " + where() + ": not a regular file");
  file_bytes = static_cast<std::uint64_t>(status.st_size);
  modified = status.st_mtim;

  require_checksummed_superblock();
  file = FileHandle(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT));
  inspect_opened_file();
}

void IndexReader::Impl::open_image(std::span<const std::byte> bytes) {
  in_memory = true;
  image.assign(bytes.begin(), bytes.end());
  file_bytes = image.size();
  require_checksummed_superblock();
  PropertyListHandle access(H5Pcreate(H5P_FILE_ACCESS));
  // The core driver reads the image HDF5 copies; nothing is written back (no backing store).
  if (!access || H5Pset_fapl_core(access.get(), 1 << 16, 0) < 0 ||
      H5Pset_file_image(access.get(), image.data(), image.size()) < 0)
    hdf5_format_error("cannot set up an in-memory file");
  file = FileHandle(H5Fopen(path.c_str(), H5F_ACC_RDONLY, access.get()));
  inspect_opened_file();
}

void IndexReader::Impl::inspect_opened_file() {
  if (!file) hdf5_format_error("HDF5 cannot open it (damaged or truncated)");
  PropertyListHandle creation(H5Fget_create_plist(file.get()));
  hsize_t user_block = 0;
  std::size_t address_size = 0, length_size = 0;
  if (!creation || H5Pget_userblock(creation.get(), &user_block) < 0 ||
      H5Pget_sizes(creation.get(), &address_size, &length_size) < 0)
    hdf5_format_error("cannot inspect the file creation properties");
  raw_reads = user_block == 0;
  base_address = user_block;
  address_bytes = address_size;
  length_bytes = length_size;
}

void IndexReader::Impl::read_header(hid_t g) {
  const htri_t has_format = H5Aexists(g, schema::attribute::format);
  if (has_format < 0) hdf5_format_error("cannot read the root attributes (damaged metadata)");
  if (has_format == 0)
    format_error("no root attribute 'format': not a tetrapage index (expected format '" +
                 std::string(kIndexFormatName) + "')");
  const std::string format = read_string_attribute(g, schema::attribute::format);
  if (format != kIndexFormatName)
    format_error("root attribute 'format' is '" + format + "', expected '" +
                 std::string(kIndexFormatName) + "': not a tetrapage index");
  const std::uint64_t version =
      read_number_attribute<std::uint64_t>(g, schema::attribute::version, 1)[0];
  if (version != kIndexVersion)
    format_error("version " + std::to_string(version) +
                 " is not supported (this program reads version " + std::to_string(kIndexVersion) +
                 "): rebuild the index");
  IndexHeader& h = header;
  h.version = static_cast<std::uint32_t>(version);
  h.precision = read_string_attribute(g, schema::attribute::precision);
  h.input_triangles =
      read_number_attribute<std::uint64_t>(g, schema::attribute::input_triangles, 1)[0];
  h.stored_triangles =
      read_number_attribute<std::uint64_t>(g, schema::attribute::stored_triangles, 1)[0];
  h.region_count = read_number_attribute<std::uint64_t>(g, schema::attribute::region_count, 1)[0];
  h.shard_count = read_number_attribute<std::uint64_t>(g, schema::attribute::shard_count, 1)[0];
  h.max_rounding_distance =
      read_number_attribute<double>(g, schema::attribute::max_rounding_distance, 1)[0];
  const auto bounds = read_number_attribute<double>(g, schema::attribute::bounds, 6);
  h.bounds.lo = {bounds[0], bounds[1], bounds[2]};
  h.bounds.hi = {bounds[3], bounds[4], bounds[5]};
  h.source = read_string_attribute(g, schema::attribute::source);
  h.build_report_json = read_string_attribute(g, schema::attribute::build_report);
  h.created_by = read_string_attribute(g, schema::attribute::created_by);
  if (has_attribute(g, schema::attribute::length_unit))
    h.length_unit = read_string_attribute(g, schema::attribute::length_unit);
  if (has_attribute(g, schema::attribute::tessellation_deflection)) {
    h.tessellation_deflection =
        read_number_attribute<double>(g, schema::attribute::tessellation_deflection, 1)[0];
    if (!(h.tessellation_deflection >= 0) || !std::isfinite(h.tessellation_deflection))
      format_error("root attribute 'tessellation_deflection' is " +
                   number_text(h.tessellation_deflection) + ", expected a finite number >= 0");
  }
}

std::vector<Vec3> IndexReader::Impl::mesh_vertices() const {
  const auto values = read_dataset<double>(schema::dataset::mesh_vertices, 3);
  std::vector<Vec3> vertices(values.size() / 3);
  copy_rows(values, vertices);
  return vertices;
}

bool IndexReader::Impl::has_attribute(hid_t object, const char* name) const {
  const htri_t exists = H5Aexists(object, name);
  if (exists < 0) hdf5_format_error("cannot look up root attribute '" + std::string(name) + "'");
  return exists > 0;
}

AttributeHandle IndexReader::Impl::open_attribute(hid_t object, const char* name) const {
  const htri_t exists = H5Aexists(object, name);
  if (exists < 0) hdf5_format_error("cannot look up root attribute '" + std::string(name) + "'");
  if (exists == 0) format_error("root attribute '" + std::string(name) + "' is missing");
  AttributeHandle attribute(H5Aopen(object, name, H5P_DEFAULT));
  if (!attribute) hdf5_format_error("cannot open root attribute '" + std::string(name) + "'");
  return attribute;
}

std::string IndexReader::Impl::read_string_attribute(hid_t object, const char* name) const {
  AttributeHandle attribute = open_attribute(object, name);
  DatatypeHandle type(H5Aget_type(attribute.get()));
  DataspaceHandle space(H5Aget_space(attribute.get()));
  if (!type || !space)
    hdf5_format_error("cannot inspect root attribute '" + std::string(name) + "'");
  if (H5Tget_class(type.get()) != H5T_STRING || H5Sget_simple_extent_npoints(space.get()) != 1)
    format_error("root attribute '" + std::string(name) + "' is " + describe_type(type.get()) +
                 " with " + std::to_string(H5Sget_simple_extent_npoints(space.get())) +
                 " elements, expected one string");
  if (H5Tis_variable_str(type.get()) > 0) return stored_string(attribute.get(), name);
  if (H5Tget_size(type.get()) > file_bytes)
    format_error("root attribute '" + std::string(name) + "' claims a string of " +
                 std::to_string(H5Tget_size(type.get())) + " bytes, more than the " +
                 std::to_string(file_bytes) + "-byte file holds");
  std::string value(H5Tget_size(type.get()), '\0');
  if (H5Aread(attribute.get(), type.get(), value.data()) < 0)
    hdf5_format_error("cannot read root attribute '" + std::string(name) + "'");
  value.resize(std::strlen(value.c_str()));  // fixed-length strings are padded with NULs
  return value;
}

std::string IndexReader::Impl::stored_string(hid_t attribute, const char* name) const {
  detail::StoredVlenString stored;
  if (!detail::read_stored_vlen_string(attribute, address_bytes, stored))
    hdf5_format_error("cannot read root attribute '" + std::string(name) + "'");
  const std::string what = "root attribute '" + std::string(name) + "'";
  if (stored.length > file_bytes)
    format_error(what + " claims a string of " + std::to_string(stored.length) +
                 " bytes, more than the " + std::to_string(file_bytes) + "-byte file holds");
  if (stored.length == 0) return {};  // nothing is stored in the heap
  const std::uint64_t offset = base_address + stored.heap_address;
  const std::string place = " (global heap collection at " + std::to_string(stored.heap_address) +
                            ", object " + std::to_string(stored.heap_index) + ")";
  unsigned char head[16];
  if (offset > file_bytes || file_bytes - offset < sizeof head)
    format_error(what + ": its string" + place + " lies past the end of the " +
                 std::to_string(file_bytes) + "-byte file");
  pread_all(reinterpret_cast<std::byte*>(head), sizeof head, offset, what);
  const std::uint64_t size = load_le(head + 8, std::min<std::size_t>(length_bytes, 8));
  if (size > file_bytes - offset)
    format_error(what + ": its string" + place + " is in a collection of " + std::to_string(size) +
                 " bytes, past the end of the " + std::to_string(file_bytes) + "-byte file");
  std::vector<unsigned char> collection(size);
  pread_all(reinterpret_cast<std::byte*>(collection.data()), size, offset, what);
  std::uint64_t object_at = 0;
  const std::string problem = heap_object_problem(collection, length_bytes, stored, object_at);
  if (!problem.empty()) format_error(what + ": its string" + place + ": " + problem);
  const auto* text = reinterpret_cast<const char*>(collection.data() + object_at);
  return std::string(text, std::find(text, text + stored.length, '\0'));
}

DatasetHandle IndexReader::Impl::open_dataset(const std::string& name) const {
  // Each link on the way must exist, or H5Lexists itself fails.
  for (std::size_t slash = name.find('/', 1);; slash = name.find('/', slash + 1)) {
    const std::string prefix = name.substr(0, slash);
    const htri_t exists = H5Lexists(file.get(), prefix.c_str(), H5P_DEFAULT);
    if (exists < 0) hdf5_format_error("cannot look up '" + prefix + "'");
    if (exists == 0) format_error("'" + prefix + "' is missing");
    if (slash == std::string::npos) break;
  }
  DatasetHandle dataset(H5Dopen2(file.get(), name.c_str(), H5P_DEFAULT));
  if (!dataset) hdf5_format_error("'" + name + "' is not a readable dataset");
  return dataset;
}

void IndexReader::Impl::locate_chunks() {
  const std::uint64_t count = (data_extent + chunk_bytes - 1) / chunk_bytes;
  chunks.assign(count, ChunkLocation{});
  // By coordinate, not H5Dget_chunk_info(index): the latter walks the index from the start
  // on every call (quadratic), a B-tree lookup is logarithmic.
  for (std::uint64_t c = 0; c < count; ++c) {
    hsize_t coordinate = c * chunk_bytes / kWordBytes;
    unsigned mask = 0;
    haddr_t address = HADDR_UNDEF;
    hsize_t stored = 0;
    if (H5Dget_chunk_info_by_coord(shard_data.get(), &coordinate, &mask, &address, &stored) < 0)
      hdf5_format_error("cannot locate chunk " + std::to_string(c) + " of /shards/data");
    if (address == HADDR_UNDEF) continue;
    if (address + stored > file_bytes)
      format_error("chunk " + std::to_string(c) + " of /shards/data lies at bytes [" +
                   std::to_string(address) + ", " + std::to_string(address + stored) +
                   "), past the end of the " + std::to_string(file_bytes) +
                   "-byte file (truncated?)");
    if (stored > max_stored_bytes())
      format_error("chunk " + std::to_string(c) + " of /shards/data claims " +
                   std::to_string(stored) + " stored bytes for a " + std::to_string(chunk_bytes) +
                   "-byte chunk");
    chunks[c] = ChunkLocation{address, stored, mask};
  }
}

ssize_t IndexReader::Impl::read_at(std::byte* buffer, std::uint64_t bytes,
                                   std::uint64_t offset) const {
  if (!in_memory) return ::pread(descriptor.get(), buffer, bytes, static_cast<off_t>(offset));
  if (offset >= image.size()) return 0;
  const std::uint64_t count = std::min<std::uint64_t>(bytes, image.size() - offset);
  std::memcpy(buffer, image.data() + offset, count);
  return static_cast<ssize_t>(count);
}

void IndexReader::Impl::pread_all(std::byte* buffer, std::uint64_t bytes, std::uint64_t offset,
                                  const std::string& what) const {
  while (bytes > 0) {
    const ssize_t got = read_at(buffer, bytes, offset);
    if (got < 0) {
      if (errno == EINTR) continue;
      throw IoError("cannot read " + what + " of " + where() + ": " + std::strerror(errno));
    }
    if (got == 0)
      shard_read_error(what,
                       "it lies past the end of the file (at byte " + std::to_string(offset) + ")");
    buffer += got;
    bytes -= static_cast<std::uint64_t>(got);
    offset += static_cast<std::uint64_t>(got);
  }
}

void IndexReader::Impl::read_stored_chunk(std::uint32_t shard, std::uint64_t k, std::uint32_t& mask,
                                          std::vector<std::byte>& stored) const {
  hsize_t coordinate = (first_chunk(shard) + k) * chunk_bytes / kWordBytes;
  hsize_t stored_bytes = 0;
  if (H5Dget_chunk_storage_size(shard_data.get(), &coordinate, &stored_bytes) < 0)
    shard_read_error(chunk_name(shard, k), "cannot locate it", false, true);
  if (stored_bytes == 0) shard_read_error(chunk_name(shard, k), "it is not stored");
  if (stored_bytes > max_stored_bytes())
    format_error(chunk_name(shard, k) + " claims " + std::to_string(stored_bytes) +
                 " stored bytes for a " + std::to_string(chunk_bytes) + "-byte chunk");
  stored.resize(stored_bytes);
  if (H5Dread_chunk(shard_data.get(), H5P_DEFAULT, &coordinate, &mask, stored.data()) < 0)
    shard_read_error(chunk_name(shard, k), "cannot read it", false, true);
}

std::uint64_t IndexReader::Impl::payload_in_chunk(std::uint32_t shard, std::uint64_t k) const {
  return std::min<std::uint64_t>(chunk_bytes, sizes[shard] - k * chunk_bytes);
}

void IndexReader::Impl::decode_into(std::uint32_t shard, std::uint64_t k,
                                    std::span<const std::byte> stored, std::uint32_t filter_mask,
                                    std::vector<std::byte>& payload,
                                    std::vector<std::byte>* whole_chunk) const {
  const std::uint64_t begin = k * chunk_bytes;
  const std::uint64_t bytes = std::min<std::uint64_t>(chunk_bytes, payload.size() - begin);
  std::span<std::byte> target(payload.data() + begin, bytes);
  if (whole_chunk != nullptr && bytes < chunk_bytes) {
    whole_chunk->resize(chunk_bytes);
    target = *whole_chunk;
  }
  // The writer never stores zeros (an LZ4 frame names its size; zeros are compressed), but
  // HDF5 reads them past the end of a file: checked first, as zeros pass the checksum.
  if (std::all_of(stored.begin(), stored.end(), [](std::byte b) { return b == std::byte{0}; }))
    shard_read_error(chunk_name(shard, k), "", true);
  const std::string problem = detail::decode_chunk(stored, filter_mask, target, chunk_bytes);
  if (!problem.empty()) shard_read_error(chunk_name(shard, k), problem);
  if (target.data() != payload.data() + begin)
    std::memcpy(payload.data() + begin, target.data(), bytes);
}

void IndexReader::Impl::read_shard(std::uint32_t shard, std::vector<std::byte>& payload) const {
  check_shard(shard);
  if (sizes[shard] == 0) {
    payload.clear();
    return;
  }
  // The payload is sized once its chunks are known to be stored, each in enough bytes.
  const std::uint64_t first = first_chunk(shard);
  const std::uint64_t count = chunk_count(shard);
  // Buffers kept by the thread: fresh ones made every page-in fault new pages in (a tenth
  // of a paged flight's main thread in perf).
  constexpr std::size_t kKeptBufferBytes = std::size_t(1) << 20;
  thread_local std::vector<std::vector<std::byte>> stored;
  thread_local std::vector<std::uint32_t> masks;

  // One read when the chunks are located and follow each other in the file (small holes
  // allowed); otherwise each chunk through HDF5's direct chunk read (a B-tree lookup), with
  // the checksum and decompression still outside HDF5's lock.
  bool one_read = raw_reads && located.load(std::memory_order_acquire);
  std::uint64_t low = 0, high = 0, stored_total = 0;
  for (std::uint64_t k = 0; k < count && one_read; ++k) {
    const ChunkLocation& location = chunks[first + k];
    if (location.address == kUnallocated || (k > 0 && location.address < high)) {
      one_read = false;
      break;
    }
    if (k == 0) low = location.address;
    high = location.address + location.stored_bytes;
    stored_total += location.stored_bytes;
  }
  if (one_read && high - low <= stored_total + kMaxHoleBytes) {
    for (std::uint64_t k = 0; k < count; ++k)
      check_stored_claim(shard, k, chunks[first + k].stored_bytes);
    payload.resize(sizes[shard]);
    stored.resize(1);
    stored[0].resize(high - low);
    pread_all(stored[0].data(), stored[0].size(), low, "shard " + std::to_string(shard));
    for (std::uint64_t k = 0; k < count; ++k) {
      const ChunkLocation& location = chunks[first + k];
      decode_into(shard, k,
                  std::span<const std::byte>(stored[0]).subspan(location.address - low,
                                                                location.stored_bytes),
                  location.filter_mask, payload);
    }
    if (stored[0].capacity() > kKeptBufferBytes)
      std::vector<std::byte>().swap(stored[0]);  // a rare large shard
    return;
  }
  // Every chunk of the shard read in one turn, then decoded: HDF5 takes its global lock in
  // each call, and with two threads paging in, the lock's hand-overs between calls (a
  // futex wake and a context switch each) cost more than LZ4 (tetrapage_bench_index).
  if (stored.size() < count) stored.resize(count);
  masks.resize(count);
  {
    // Polled first: the other thread holds it for a few microseconds (SpinThenBlock.h).
    const std::unique_lock lock = lock_spinning_first(chunk_read_mutex(), spin_before_sleep);
    for (std::uint64_t k = 0; k < count; ++k) read_stored_chunk(shard, k, masks[k], stored[k]);
  }
  for (std::uint64_t k = 0; k < count; ++k) check_stored_claim(shard, k, stored[k].size());
  payload.resize(sizes[shard]);
  for (std::uint64_t k = 0; k < count; ++k) decode_into(shard, k, stored[k], masks[k], payload);
  constexpr std::size_t kKeptChunks = kKeptBufferBytes / 16384;
  if (stored.size() > kKeptChunks) {  // a rare large shard: keep a megabyte's worth
    stored.resize(kKeptChunks);
    stored.shrink_to_fit();
  }
}

std::mutex& IndexReader::Impl::chunk_read_mutex() {
  static std::mutex mutex;
  return mutex;
}

IndexReader::IndexReader(const std::filesystem::path& path) : impl_(std::make_unique<Impl>()) {
  detail::enter_hdf5();
  impl_->path = path;
  impl_->open_file();
  impl_->check_opened_index();
}

IndexReader::IndexReader(std::span<const std::byte> image, const std::string& name)
    : impl_(std::make_unique<Impl>()) {
  detail::enter_hdf5();
  impl_->path = name;
  impl_->open_image(image);
  impl_->check_opened_index();
}

IndexReader::~IndexReader() = default;
IndexReader::IndexReader(IndexReader&&) noexcept = default;
IndexReader& IndexReader::operator=(IndexReader&&) noexcept = default;

const std::filesystem::path& IndexReader::path() const {
  return impl_->path;
}
const IndexHeader& IndexReader::header() const {
  return impl_->header;
}
std::uint64_t IndexReader::file_bytes() const {
  return impl_->file_bytes;
}

TetMesh IndexReader::read_mesh() const {
  detail::enter_hdf5();
  const Impl& r = *impl_;
  const auto vertices = r.read_dataset<double>(schema::dataset::mesh_vertices, 3);
  const auto tets = r.read_dataset<std::uint32_t>(schema::dataset::mesh_tets, 4);
  const auto neighbours = r.read_dataset<std::uint32_t>(schema::dataset::mesh_neighbours, 4);
  TetMesh mesh;
  mesh.vertices.resize(vertices.size() / 3);
  copy_rows(vertices, mesh.vertices);
  mesh.tets.resize(tets.size() / 4);
  copy_rows(tets, mesh.tets);
  mesh.neighbours.resize(neighbours.size() / 4);
  copy_rows(neighbours, mesh.neighbours);
  if (mesh.neighbours.size() != mesh.tets.size())
    r.format_error("'/mesh/tets' has " + std::to_string(mesh.tets.size()) +
                   " rows but '/mesh/neighbours' has " + std::to_string(mesh.neighbours.size()));
  for (std::size_t t = 0; t < mesh.tets.size(); ++t)
    for (int i = 0; i < 4; ++i) {
      if (mesh.tets[t][i] >= mesh.vertices.size())
        r.format_error("'/mesh/tets' row " + std::to_string(t) + " names vertex " +
                       std::to_string(mesh.tets[t][i]) + " of " +
                       std::to_string(mesh.vertices.size()));
      const auto neighbour = mesh.neighbours[t][i];
      if (neighbour != TetMesh::no_neighbour && neighbour >= mesh.tets.size())
        r.format_error("'/mesh/neighbours' row " + std::to_string(t) + " names tet " +
                       std::to_string(neighbour) + " of " + std::to_string(mesh.tets.size()));
    }
  return mesh;
}

bool IndexReader::has_table(std::string_view name) const {
  return std::binary_search(impl_->tables.begin(), impl_->tables.end(), name);
}
std::vector<std::string> IndexReader::table_names() const {
  return impl_->tables;
}

std::vector<std::uint8_t> IndexReader::read_table_uint8(std::string_view name) const {
  return impl_->read_table<std::uint8_t>(name);
}
std::vector<std::uint32_t> IndexReader::read_table_uint32(std::string_view name) const {
  return impl_->read_table<std::uint32_t>(name);
}
std::vector<std::uint64_t> IndexReader::read_table_uint64(std::string_view name) const {
  return impl_->read_table<std::uint64_t>(name);
}
std::vector<double> IndexReader::read_table_double(std::string_view name) const {
  return impl_->read_table<double>(name);
}

std::uint32_t IndexReader::shard_count() const {
  return static_cast<std::uint32_t>(impl_->offsets.size());
}
std::uint32_t IndexReader::chunk_bytes() const {
  return impl_->chunk_bytes;
}

std::uint64_t IndexReader::shard_size(std::uint32_t shard) const {
  impl_->check_shard(shard);
  return impl_->sizes[shard];
}

std::uint64_t IndexReader::stored_shard_size(std::uint32_t shard) const {
  const Impl& r = *impl_;
  r.check_shard(shard);
  std::uint64_t bytes = 0;
  if (r.located.load(std::memory_order_acquire)) {
    for (std::uint64_t k = 0; k < r.chunk_count(shard); ++k)
      bytes += r.chunks[r.first_chunk(shard) + k].stored_bytes;
    return bytes;
  }
  // One chunk-index lookup per chunk, rather than locating every chunk of the file.
  for (std::uint64_t k = 0; k < r.chunk_count(shard); ++k) {
    hsize_t coordinate = (r.first_chunk(shard) + k) * r.chunk_bytes / kWordBytes;
    hsize_t stored = 0;
    if (H5Dget_chunk_storage_size(r.shard_data.get(), &coordinate, &stored) < 0)
      r.hdf5_format_error("cannot locate " + r.chunk_name(shard, k));
    bytes += stored;
  }
  return bytes;
}

std::vector<StoredChunk> IndexReader::shard_chunks(std::uint32_t shard) const {
  const Impl& r = *impl_;
  r.check_shard(shard);
  r.ensure_located();
  std::vector<StoredChunk> result;
  for (std::uint64_t k = 0; k < r.chunk_count(shard); ++k) {
    const std::uint64_t c = r.first_chunk(shard) + k;
    const ChunkLocation& location = r.chunks[c];
    result.push_back(StoredChunk{c, location.address, location.stored_bytes,
                                 (location.filter_mask & detail::kCompressionSkipped) == 0});
  }
  return result;
}

std::vector<std::byte> IndexReader::read_shard(std::uint32_t shard) const {
  std::vector<std::byte> payload;
  impl_->read_shard(shard, payload);
  return payload;
}

void IndexReader::read_shard(std::uint32_t shard, std::vector<std::byte>& payload) const {
  impl_->read_shard(shard, payload);
}

void IndexReader::set_spin_before_sleep(std::chrono::microseconds limit) {
  impl_->spin_before_sleep = std::max(limit, std::chrono::microseconds(0));
}

std::vector<std::byte> IndexReader::read_shard_through_hdf5(std::uint32_t shard) const {
  detail::enter_hdf5();
  const Impl& r = *impl_;
  r.check_shard(shard);
  std::vector<std::byte> payload(r.sizes[shard]);
  if (payload.empty()) return payload;
  const std::string what = "cannot read shard " + std::to_string(shard) + " through HDF5";
  // HDF5 decompresses with the LZ4 filter plugin, which it loads on demand.
  if (H5Zfilter_avail(detail::kLz4FilterId) <= 0)
    throw InputError(r.where() + ": " + what + ": HDF5 finds no LZ4 filter (id " +
                     std::to_string(detail::kLz4FilterId) +
                     "); install its plugin (Debian: hdf5-filter-plugin) or set HDF5_PLUGIN_PATH");
  DataspaceHandle file_space(H5Dget_space(r.shard_data.get()));
  // The words that hold the payload (it starts on a chunk boundary, a whole word), read as
  // little-endian words: the bytes as stored, on any machine.
  const hsize_t start = r.offsets[shard] / kWordBytes;
  const hsize_t count = (payload.size() + kWordBytes - 1) / kWordBytes;
  if (!file_space ||
      H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, &start, nullptr, &count, nullptr) < 0)
    r.hdf5_format_error(what);
  DataspaceHandle memory_space(H5Screate_simple(1, &count, nullptr));
  std::vector<std::byte> words(count * kWordBytes);
  if (!memory_space || H5Dread(r.shard_data.get(), H5T_STD_U64LE, memory_space.get(),
                               file_space.get(), H5P_DEFAULT, words.data()) < 0)
    r.hdf5_format_error(what);
  std::memcpy(payload.data(), words.data(), payload.size());
  return payload;
}

std::vector<std::string> IndexReader::validate(
    const std::function<void(std::uint32_t, std::span<const std::byte>)>& each_shard) const {
  detail::enter_hdf5();
  const Impl& r = *impl_;
  std::vector<std::string> problems = r.extent_problems();
  if (problems.empty()) {
    // Chunk by chunk, so that every bad chunk is named, each through a chunk-index lookup, and
    // checked and decoded as a page-in does. Not located first: HDF5 1.10 lists chunk addresses
    // only at a cost linear in the chunks each, and that took 8.8 of the 9.0 s validate() spent
    // on the 10M index.
    std::vector<std::byte> stored, payload, scratch;
    for (std::uint32_t s = 0; s < r.offsets.size(); ++s) {
      payload.clear();
      bool intact = true;
      for (std::uint64_t k = 0; k < r.chunk_count(s); ++k) {
        try {
          std::uint32_t mask = 0;
          r.read_stored_chunk(s, k, mask, stored);
          r.check_stored_claim(s, k, stored.size());
          // Grown with each chunk read, so that a damaged size costs no more than its chunks.
          payload.resize(k * r.chunk_bytes + r.payload_in_chunk(s, k));
          r.decode_into(s, k, stored, mask, payload, &scratch);
        } catch (const FormatError& error) {
          problems.push_back(error.what());
          intact = false;
        }
      }
      if (intact && each_shard) each_shard(s, payload);
    }
  }
  try {
    read_mesh();
  } catch (const FormatError& error) {
    problems.push_back(error.what());
  }
  for (const auto& name : r.tables) {
    try {
      const std::string dataset = schema::table_path(name);
      DatasetHandle table = r.open_dataset(dataset);
      DatatypeHandle type(H5Dget_type(table.get()));
      bool known = false;
      for (Element element : {Element::uint8, Element::uint32, Element::uint64, Element::float64})
        if (type && type_matches(type.get(), element)) {
          known = true;
          switch (element) {
            case Element::uint8:
              r.read_dataset<std::uint8_t>(dataset, 0);
              break;
            case Element::uint32:
              r.read_dataset<std::uint32_t>(dataset, 0);
              break;
            case Element::uint64:
              r.read_dataset<std::uint64_t>(dataset, 0);
              break;
            case Element::float64:
              r.read_dataset<double>(dataset, 0);
              break;
          }
        }
      if (!known)
        problems.push_back(r.where() + ": '" + dataset + "' holds " +
                           (type ? describe_type(type.get()) : std::string("an unknown type")) +
                           ", expected uint8, uint32, uint64 or float64");
    } catch (const FormatError& error) {
      problems.push_back(error.what());
    }
  }
  return problems;
}

}  // namespace tetrapage
