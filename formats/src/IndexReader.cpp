#include "tetrapage/formats/IndexReader.h"
#include "tetrapage/formats/IndexSchema.h"

#include <fcntl.h>
#include <hdf5.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <chrono>
#include <atomic>
#include <cstdio>
#include <cstring>
#include <map>
#include <mutex>
#include <numeric>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "ChunkCodec.h"
#include "Hdf5Handle.h"
#include "TextNumbers.h"
#include "tetrapage/formats/Error.h"
#include "tetrapage/formats/SpinThenBlock.h"

namespace tetrapage {

namespace schema = index_schema;

namespace {

/// A dataset's values into rows of as many values (Vec3, tets): memcpy, but never from the
/// null data of an empty vector (undefined behaviour even for 0 bytes).
template <class Value, class Row>
void copy_rows(const std::vector<Value>& values, std::vector<Row>& rows) {
  static_assert(sizeof(Row) % sizeof(Value) == 0);
  if (!values.empty()) std::memcpy(rows.data(), values.data(), values.size() * sizeof(Value));
}

}  // namespace

using detail::AttributeHandle;
using detail::DatasetHandle;
using detail::DataspaceHandle;
using detail::DatatypeHandle;
using detail::FileHandle;
using detail::GroupHandle;
using detail::PropertyListHandle;

namespace {

constexpr std::uint64_t kUnallocated = ~std::uint64_t{0};
/// One pread() may span small holes between a shard's chunks (HDF5 metadata blocks can land
/// between them) rather than splitting into one read per chunk.
constexpr std::uint64_t kMaxHoleBytes = 64 * 1024;
// /shards/data is stored as 8-byte little-endian words: the shuffle's element (ChunkCodec.h).
constexpr std::uint64_t kWordBytes = detail::kShuffleElementBytes;

enum class Element { uint8, uint32, uint64, float64 };

const char* element_name(Element element) {
  switch (element) {
    case Element::uint8: return "uint8";
    case Element::uint32: return "uint32";
    case Element::uint64: return "uint64";
    case Element::float64: return "float64";
  }
  return "?";
}

std::string describe_type(hid_t type) {
  const H5T_class_t type_class = H5Tget_class(type);
  const std::size_t bits = 8 * H5Tget_size(type);
  switch (type_class) {
    case H5T_INTEGER:
      return std::string(H5Tget_sign(type) == H5T_SGN_NONE ? "uint" : "int") + std::to_string(bits);
    case H5T_FLOAT: return "float" + std::to_string(bits);
    case H5T_STRING: return "string";
    case H5T_COMPOUND: return "compound";
    default: return "type class " + std::to_string(static_cast<int>(type_class));
  }
}

bool type_matches(hid_t type, Element element) {
  const H5T_class_t type_class = H5Tget_class(type);
  const std::size_t size = H5Tget_size(type);
  switch (element) {
    case Element::uint8:
    case Element::uint32:
    case Element::uint64: {
      const std::size_t expected =
          element == Element::uint8 ? 1 : element == Element::uint32 ? 4 : 8;
      return type_class == H5T_INTEGER && size == expected && H5Tget_sign(type) == H5T_SGN_NONE;
    }
    case Element::float64: return type_class == H5T_FLOAT && size == 8;
  }
  return false;
}

std::uint64_t element_bytes(Element element) {
  switch (element) {
    case Element::uint8: return 1;
    case Element::uint32: return 4;
    case Element::uint64:
    case Element::float64: return 8;
  }
  return 8;
}

hid_t memory_type(Element element) {
  switch (element) {
    case Element::uint8: return H5T_NATIVE_UINT8;
    case Element::uint32: return H5T_NATIVE_UINT32;
    case Element::uint64: return H5T_NATIVE_UINT64;
    case Element::float64: return H5T_NATIVE_DOUBLE;
  }
  return H5T_NATIVE_UINT8;
}

template <class T>
constexpr Element element_of() {
  if constexpr (std::is_same_v<T, std::uint8_t>) return Element::uint8;
  if constexpr (std::is_same_v<T, std::uint32_t>) return Element::uint32;
  if constexpr (std::is_same_v<T, std::uint64_t>) return Element::uint64;
  return Element::float64;
}

/// An owned POSIX file descriptor.
class Descriptor {
 public:
  Descriptor() = default;
  explicit Descriptor(int descriptor) : descriptor_(descriptor) {}
  ~Descriptor() {
    if (descriptor_ >= 0) ::close(descriptor_);
  }
  Descriptor(Descriptor&& other) noexcept : descriptor_(std::exchange(other.descriptor_, -1)) {}
  Descriptor& operator=(Descriptor&& other) noexcept {
    std::swap(descriptor_, other.descriptor_);
    return *this;
  }
  int get() const { return descriptor_; }

 private:
  int descriptor_ = -1;
};

struct ChunkLocation {
  std::uint64_t address = kUnallocated;
  std::uint64_t stored_bytes = 0;
  std::uint32_t filter_mask = 0;
};

// What a decoded dataset can hold for each stored byte: 1 unfiltered; through a filter, at
// most deflate's limit (1032:1; LZ4's is 255:1). A larger claim is damage, not a size.
constexpr std::uint64_t kMaxFilterRatio = 1032;
// LZ4 writes at least one byte per 255 it decodes (a chunk's frame and checksum add more).
constexpr std::uint64_t kMaxLz4Ratio = 256;
// The writer's largest chunk of /shards/data (IndexWriterOptions).
constexpr std::uint64_t kMaxChunkBytes = 64u << 20;
// The least a stored chunk of /shards/data takes: a frame header, a block and the checksum.
constexpr std::uint64_t kMinStoredChunkBytes = 16;

std::uint64_t load_le(const unsigned char* bytes, std::size_t count) {
  std::uint64_t value = 0;
  for (std::size_t i = count; i-- > 0;) value = (value << 8) | bytes[i];
  return value;
}

/// Where a variable-length string's bytes lie: HDF5's global heap collection (the HDF5 file
/// format, "Global Heap"), walked object by object as HDF5 does when it loads one, checked
/// before HDF5 reads it (HDF5 1.10 trusts the sizes it finds there and reads past the
/// collection). `collection` is the collection's bytes; "" or what is wrong.
std::string heap_object_problem(const std::vector<unsigned char>& collection, std::size_t length_bytes,
                                const detail::StoredVlenString& stored, std::uint64_t& object_at) {
  const auto align8 = [](std::uint64_t x) { return (x + 7) / 8 * 8; };
  const std::uint64_t header = align8(8 + length_bytes), object_header = 8 + length_bytes;
  if (collection.size() < header || std::memcmp(collection.data(), "GCOL", 4) != 0 || collection[4] != 1)
    return "no global heap collection there";
  const std::uint64_t size = collection.size();
  bool found = false;
  std::uint64_t at = header;
  while (at < size) {
    if (size - at < object_header) break;  // too small for an object: free space, as HDF5 reads it
    const std::uint64_t index = load_le(&collection[at], 2);
    const std::uint64_t bytes = load_le(&collection[at + 8], length_bytes);
    if (bytes > size) return "object " + std::to_string(index) + " claims " + std::to_string(bytes) + " bytes";
    // Index 0 is the free space, whose size counts its header.
    const std::uint64_t step = index == 0 ? bytes : object_header + align8(bytes);
    if (step == 0 || step > size - at)
      return "object " + std::to_string(index) + " of " + std::to_string(bytes) + " bytes runs past the collection";
    if (index == stored.heap_index && index != 0) {
      if (bytes != stored.length)
        return "object " + std::to_string(index) + " holds " + std::to_string(bytes) + " bytes, not " +
               std::to_string(stored.length);
      found = true;
      object_at = at + object_header;
    }
    at += step;
  }
  return found ? std::string() : "no object " + std::to_string(stored.heap_index) + " in the collection";
}

}  // namespace

struct IndexReader::Impl {
  std::filesystem::path path;
  std::chrono::microseconds spin_before_sleep{100};
  IndexHeader header;
  std::uint64_t file_bytes = 0;
  timespec modified{};  // when the file was last changed, as it was opened
  Descriptor descriptor;
  // An index opened from bytes in memory (HDF5's core driver) has no descriptor: raw reads
  // copy from this image instead.
  std::vector<std::byte> image;
  bool in_memory = false;
  FileHandle file;
  DatasetHandle shard_data;
  std::uint32_t chunk_bytes = 0;
  std::uint64_t data_extent = 0;
  std::vector<std::uint64_t> offsets;
  std::vector<std::uint64_t> sizes;
  // Chunk file locations, found on first need (inspect, validate, shard_chunks): HDF5 1.10's
  // only way to list them, a lookup by coordinate per chunk, costs time linear in the number of
  // chunks, so locating them all took 26 s on a 50,000-shard index. Page-ins never need them.
  std::vector<ChunkLocation> chunks;
  mutable std::once_flag located_once;
  mutable std::atomic<bool> located{false};
  void ensure_located() const {
    std::call_once(located_once, [this] {
      const_cast<Impl*>(this)->locate_chunks();
      located.store(true, std::memory_order_release);
    });
  }
  /// False when the file has a user block: chunk addresses are then not file offsets we can
  /// pread() with confidence, so stored chunks come through H5Dread_chunk instead.
  bool raw_reads = true;
  // The file's user block (where HDF5 addresses start) and its sizes of addresses and lengths.
  std::uint64_t base_address = 0;
  std::size_t address_bytes = 8, length_bytes = 8;
  std::vector<std::string> tables;
  std::uint64_t tet_count = 0;  // rows of /mesh/tets, found at open
  // Lengths the preprocess's tables must have, fixed by the mesh, the shards and the components.
  std::map<std::string, std::uint64_t, std::less<>> expected_lengths;

  std::string where() const { return "index '" + path.string() + "'"; }
  [[noreturn]] void format_error(const std::string& what) const {
    throw FormatError(where() + ": " + what);
  }
  [[noreturn]] void hdf5_format_error(const std::string& what) const {
    throw FormatError(where() + ": " + what + ": " + detail::take_hdf5_error());
  }

  /// Whether the open file's size or modification time is not what it was when opened: a
  /// file rewritten or truncated under a running reader, which a message should say rather
  /// than describe the bytes it now finds.
  bool file_changed(std::uint64_t& bytes_now) const {
    if (in_memory) return false;
    struct stat status {};
    if (::fstat(descriptor.get(), &status) != 0) return false;
    bytes_now = static_cast<std::uint64_t>(status.st_size);
    return bytes_now != file_bytes || status.st_mtim.tv_sec != modified.tv_sec ||
           status.st_mtim.tv_nsec != modified.tv_nsec;
  }

  /// @throw FormatError for a shard's chunk that cannot be read or decoded: "the file changed or
  /// is truncated" when it did, or when the chunk read as zeros (HDF5 reads zeros past the end
  /// of a file), else `problem` as it is. With `hdf5`, HDF5's reason is appended.
  [[noreturn]] void shard_read_error(const std::string& what, const std::string& problem, bool read_zeros = false,
                                     bool hdf5 = false) const {
    const std::string reason = (read_zeros ? std::string("it reads as zeros where data was stored") : problem) +
                               (hdf5 ? ": " + detail::take_hdf5_error() : std::string());
    std::uint64_t bytes_now = 0;
    if (file_changed(bytes_now))
      format_error("the file changed or is truncated: " + what + ": " + reason + " (the file has " +
                   std::to_string(bytes_now) + " bytes, " + std::to_string(file_bytes) + " when opened)");
    if (read_zeros) format_error("the file changed or is truncated: " + what + ": " + reason);
    format_error(what + ": " + reason);
  }

  void check_shard(std::uint32_t shard) const {
    if (shard >= offsets.size())
      throw InputError(where() + ": shard " + std::to_string(shard) + " does not exist (" +
                       std::to_string(offsets.size()) + " shards)");
  }
  std::uint64_t first_chunk(std::uint32_t shard) const { return offsets[shard] / chunk_bytes; }
  std::uint64_t chunk_count(std::uint32_t shard) const {
    return (sizes[shard] + chunk_bytes - 1) / chunk_bytes;
  }
  std::string chunk_name(std::uint32_t shard, std::uint64_t k) const {
    const std::uint64_t c = first_chunk(shard) + k;
    std::string text = "shard " + std::to_string(shard) + ", chunk " + std::to_string(k) + " of " +
                       std::to_string(chunk_count(shard)) + " (chunk " + std::to_string(c) +
                       " of /shards/data";
    if (c < chunks.size() && chunks[c].address != kUnallocated)
      text += " at file offset " + std::to_string(chunks[c].address);
    return text + ")";
  }

  // ---- opening ----------------------------------------------------------------------------

  void open_file() {
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

  void open_image(std::span<const std::byte> bytes) {
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

  // The user block and the sizes of addresses and lengths of the file HDF5 opened.
  void inspect_opened_file() {
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

  /// Superblocks 0 and 1, and the object headers and B-trees that go with them, carry no
  /// checksums: HDF5 1.10 decodes their damaged bytes unchecked (and can crash doing so), so
  /// such a file is refused before HDF5 reads it. The writer makes superblock 3. A file
  /// without HDF5's signature is refused here too.
  void require_checksummed_superblock() const {
    static constexpr std::array<unsigned char, 8> signature{0x89, 'H', 'D', 'F', '\r', '\n', 0x1a, '\n'};
    // HDF5 looks for its signature at 0, 512, 1024, 2048, ... (after a user block).
    for (std::uint64_t offset = 0; offset + signature.size() < file_bytes; offset = offset == 0 ? 512 : 2 * offset) {
      std::array<unsigned char, 9> bytes{};
      if (read_at(reinterpret_cast<std::byte*>(bytes.data()), bytes.size(), offset) !=
          static_cast<ssize_t>(bytes.size()))
        break;
      if (!std::equal(signature.begin(), signature.end(), bytes.begin())) continue;
      const unsigned version = bytes[8];
      if (version < 2)
        format_error("HDF5 superblock version " + std::to_string(version) +
                     ", whose metadata carries no checksums: written by a tetrapage older than index "
                     "version " + std::to_string(kIndexVersion) + " or by another program; rebuild the index");
      return;
    }
    format_error("not an HDF5 file (no HDF5 signature in its " + std::to_string(file_bytes) +
                 " bytes); expected a tetrapage index");
  }

  /// The root attributes; the format name first, so a foreign HDF5 file gets the clearest message.
  void read_header(hid_t g) {
    const htri_t has_format = H5Aexists(g, schema::attribute::format);
    if (has_format < 0) hdf5_format_error("cannot read the root attributes (damaged metadata)");
    if (has_format == 0)
      format_error("no root attribute 'format': not a tetrapage index (expected format '" +
                   std::string(kIndexFormatName) + "')");
    const std::string format = read_string_attribute(g, schema::attribute::format);
    if (format != kIndexFormatName)
      format_error("root attribute 'format' is '" + format + "', expected '" + std::string(kIndexFormatName) +
                   "': not a tetrapage index");
    const std::uint64_t version =
        read_number_attribute<std::uint64_t>(g, schema::attribute::version, 1)[0];
    if (version != kIndexVersion)
      format_error("version " + std::to_string(version) + " is not supported (this program reads version " +
                   std::to_string(kIndexVersion) + "): rebuild the index");
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
      h.tessellation_deflection = read_number_attribute<double>(g, schema::attribute::tessellation_deflection, 1)[0];
      if (!(h.tessellation_deflection >= 0) || !std::isfinite(h.tessellation_deflection))
        format_error("root attribute 'tessellation_deflection' is " + number_text(h.tessellation_deflection) +
                     ", expected a finite number >= 0");
    }
  }

  /// The shapes of the mesh's datasets (read_mesh reads them).
  void check_mesh_shapes() {
    DatasetHandle vertices = open_dataset(schema::dataset::mesh_vertices);
    const auto vertex_rows =
        check_dataset(vertices.get(), schema::dataset::mesh_vertices, Element::float64, 3);
    check_dataset_size(vertices.get(), schema::dataset::mesh_vertices, Element::float64,
                       vertex_rows, 3);
    DatasetHandle tets = open_dataset(schema::dataset::mesh_tets);
    const auto tet_rows = check_dataset(tets.get(), schema::dataset::mesh_tets, Element::uint32, 4);
    check_dataset_size(tets.get(), schema::dataset::mesh_tets, Element::uint32, tet_rows, 4);
    DatasetHandle neighbours = open_dataset(schema::dataset::mesh_neighbours);
    const auto neighbour_rows =
        check_dataset(neighbours.get(), schema::dataset::mesh_neighbours, Element::uint32, 4);
    if (tet_rows != neighbour_rows)
      format_error("'/mesh/tets' has " + std::to_string(tet_rows) + " rows but '/mesh/neighbours' has " +
                   std::to_string(neighbour_rows));
    // Indices are 32-bit: no more vertices or tets than they can name.
    if (vertex_rows > 0xffffffffu || tet_rows >= 0xffffffffu)
      format_error("the mesh has " + std::to_string(vertex_rows) + " vertices and " + std::to_string(tet_rows) +
                   " tets, more than 32-bit indices can name");
    tet_count = tet_rows;
  }

  /// Links kept in the group's object header, as the writer keeps them: the dense storage of
  /// another writer (a fractal heap and a B-tree) is refused before HDF5 walks it, since HDF5
  /// 1.10 crashes cleaning up after a damaged one.
  void require_compact_links(hid_t group, const char* name) const {
    H5G_info_t info{};
    if (H5Gget_info(group, &info) < 0) hdf5_format_error("cannot inspect group '" + std::string(name) + "'");
    if (info.storage_type != H5G_STORAGE_TYPE_COMPACT)
      format_error("group '" + std::string(name) + "' keeps its links in " +
                   (info.storage_type == H5G_STORAGE_TYPE_DENSE ? "dense storage" : "a symbol table") +
                   ", not in its object header as tetrapage writes them: rebuild the index");
  }

  /// The root's attributes and the links of the root and its groups where the writer keeps
  /// them, in object headers; each group is checked before a path through it is followed.
  void require_compact_storage(hid_t root) const {
    H5O_info_t info{};
    if (H5Oget_info2(root, &info, H5O_INFO_HDR | H5O_INFO_NUM_ATTRS) < 0)
      hdf5_format_error("cannot inspect the root group's object header");
    constexpr unsigned kAttributeMessage = 0x0C;  // HDF5's message type of a compact attribute
    if (info.num_attrs > 0 && (info.hdr.mesg.present & (std::uint64_t{1} << kAttributeMessage)) == 0)
      format_error("the root's " + std::to_string(info.num_attrs) +
                   " attributes are in dense storage, not in its object header as tetrapage writes them: "
                   "rebuild the index");
    require_compact_links(root, "/");
    for (const char* name : {schema::group::mesh, schema::group::tables, schema::group::shards}) {
      if (H5Lexists(root, name, H5P_DEFAULT) <= 0) {
        detail::take_hdf5_error();
        continue;  // named as missing where it is needed
      }
      GroupHandle group(H5Gopen2(root, name, H5P_DEFAULT));
      if (!group) hdf5_format_error("cannot open group '/" + std::string(name) + "'");
      require_compact_links(group.get(), ("/" + std::string(name)).c_str());
    }
  }

  /// The names under /tables (each is read on demand).
  void list_tables() {
    const char* group_name = schema::group::tables;
    GroupHandle group(H5Lexists(file.get(), group_name, H5P_DEFAULT) > 0 ? H5Gopen2(file.get(), group_name, H5P_DEFAULT)
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

  // ---- what the header says, checked -------------------------------------------------------

  /// The header's own values: a known precision, a rounding distance that is a distance (and
  /// 0 where nothing is rounded), bounds that are finite and not inverted (or the empty box).
  void check_header_values() const {
    const IndexHeader& h = header;
    if (h.precision != "float" && h.precision != "double" && h.precision != "exact")
      format_error("root attribute 'precision' is '" + h.precision + "', expected 'exact', 'float' or 'double'");
    if (h.shard_count >= 0xffffffffu)
      format_error("root attribute 'shard_count' is " + std::to_string(h.shard_count) + ", more than 2^32 - 1");
    const double distance = h.max_rounding_distance;
    if (!std::isfinite(distance) || distance < 0)
      format_error("root attribute 'max_rounding_distance' is " + number_text(distance) +
                   ", expected a finite distance >= 0");
    if (h.precision != "float" && distance != 0)
      format_error("root attribute 'max_rounding_distance' is " + number_text(distance) + ", but precision '" +
                   h.precision + "' stores coordinates unrounded (expected 0)");
    const BoundingBox& b = h.bounds;
    if (is_empty_convention(b)) return;
    for (int a = 0; a < 3; ++a) {
      if (!std::isfinite(b.lo[a]) || !std::isfinite(b.hi[a]))
        format_error("root attribute 'bounds' holds " + number_text(!std::isfinite(b.lo[a]) ? b.lo[a] : b.hi[a]) +
                     " on axis " + "xyz"[a] + ", expected finite coordinates");
      if (b.lo[a] > b.hi[a])
        format_error("root attribute 'bounds' is inverted on axis " + std::string(1, "xyz"[a]) + " (lo " +
                     number_text(b.lo[a]) + ", hi " + number_text(b.hi[a]) + ")");
    }
  }

  /// The writer's empty box (lo 1e300, hi -1e300), for a model without triangles.
  static bool is_empty_convention(const BoundingBox& b) {
    const BoundingBox empty;
    return b.lo == empty.lo && b.hi == empty.hi;
  }

  /// The shortest text that reads back as `value` ("1e-07", "nan").
  static std::string number_text(double value) {
    std::string text;
    detail::append_double(text, value);
    return text;
  }

  /// The tables the preprocess writes have lengths the other tables fix (docs/FORMAT.md):
  /// checked from their shapes before any is read, and again (as a bound) when one is.
  void check_table_lengths() {
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
      if (components > file_bytes) format_error("'/tables/component_part' claims " + std::to_string(components) +
                                                " entries, more than the " + std::to_string(file_bytes) +
                                                "-byte file can hold");
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

  /// The counts the header states against the data they count: regions against the coarse
  /// mesh's tets, stored triangles against the shards' counts, input triangles against the
  /// parts' counts (where those tables exist). Readers size and loop by the header's counts.
  void check_header_counts() const {
    if (header.region_count != tet_count)
      format_error("root attribute 'region_count' is " + std::to_string(header.region_count) +
                   ", but '/mesh/tets' holds " + std::to_string(tet_count) + " tets");
    check_count_against_table<std::uint32_t>(schema::attribute::stored_triangles,
                                             header.stored_triangles,
                                             schema::table::shard_triangles);
    check_count_against_table<std::uint64_t>(schema::attribute::input_triangles,
                                             header.input_triangles, schema::table::part_triangles);
  }

  /// The root attribute `attribute`, stating `stated`, equals the sum of table `table`.
  template <class T>
  void check_count_against_table(const char* attribute, std::uint64_t stated,
                                 std::string_view table) const {
    if (!has_table_named(table)) return;
    std::uint64_t sum = 0;
    bool overflows = false;
    for (const T value : read_table<T>(table))
      overflows |= __builtin_add_overflow(sum, std::uint64_t(value), &sum);
    if (overflows || sum != stated)
      format_error("root attribute '" + std::string(attribute) + "' is " + std::to_string(stated) +
                   ", but '/tables/" + std::string(table) + "' sums to " +
                   (overflows ? "more than 2^64" : std::to_string(sum)));
  }

  static std::string length_reason(const std::string& name) {
    if (name.starts_with("shard_"))
      return name == schema::table::shard_bounds ? "6 per shard" : "one per shard";
    if (name.starts_with("component_"))
      return name == schema::table::component_bounds ? "6 per component" : "one per component";
    if (name == schema::table::reference_points) return "3 per tet";
    return name == schema::table::interior_offsets ? "one per tet, and one" : "one per tet";
  }

  bool has_table_named(std::string_view name) const { return std::binary_search(tables.begin(), tables.end(), name); }

  /// A table's length from its shape, without reading it.
  std::uint64_t table_length(std::string_view name) const {
    const std::string dataset_name = schema::table_path(name);
    DatasetHandle dataset = open_dataset(dataset_name);
    DataspaceHandle space(H5Dget_space(dataset.get()));
    hsize_t length = 0;
    if (!space || H5Sget_simple_extent_ndims(space.get()) != 1 ||
        H5Sget_simple_extent_dims(space.get(), &length, nullptr) < 0)
      format_error("'" + dataset_name + "' is not a 1-D dataset");
    return length;
  }

  /// The model's bounds against the data: the coarse mesh covers them (the preprocess encloses
  /// the model in a larger box), and they hold every shard's stored triangles (grown by the
  /// rounding distance and the few ulps the builder adds).
  void check_bounds_against_data() const {
    const BoundingBox& b = header.bounds;
    const bool empty_model = is_empty_convention(b);
    BoundingBox mesh_box;
    for (const Vec3& v : mesh_vertices()) mesh_box.extend(v);
    if (!empty_model && tet_count > 0)
      for (int a = 0; a < 3; ++a)
        if (!(mesh_box.lo[a] <= b.lo[a] && b.hi[a] <= mesh_box.hi[a]))
          format_error("root attribute 'bounds' [" + number_text(b.lo[a]) + ", " + number_text(b.hi[a]) +
                       "] on axis " + "xyz"[a] + " is not inside the coarse mesh's [" + number_text(mesh_box.lo[a]) +
                       ", " + number_text(mesh_box.hi[a]) + "]");
    if (!has_table_named(schema::table::shard_bounds)) return;
    const auto boxes = read_table<double>(schema::table::shard_bounds);
    for (std::size_t s = 0; 6 * s + 5 < boxes.size(); ++s) {
      const BoundingBox box{{boxes[6 * s], boxes[6 * s + 1], boxes[6 * s + 2]},
                            {boxes[6 * s + 3], boxes[6 * s + 4], boxes[6 * s + 5]}};
      if (is_empty_convention(box)) continue;  // a shard without triangles
      for (int a = 0; a < 3; ++a) {
        const double slack = header.max_rounding_distance + 0x1p-40 * std::max(std::fabs(b.lo[a]), std::fabs(b.hi[a]));
        if (!empty_model && b.lo[a] - slack <= box.lo[a] && box.hi[a] <= b.hi[a] + slack) continue;
        const std::string shard_box = "shard " + std::to_string(s) + "'s box [" + number_text(box.lo[a]) + ", " +
                                      number_text(box.hi[a]) + "] on axis " + "xyz"[a] + " ('/tables/shard_bounds')";
        if (empty_model) format_error("root attribute 'bounds' is the empty box, but " + shard_box + " is not");
        format_error("root attribute 'bounds' [" + number_text(b.lo[a]) + ", " + number_text(b.hi[a]) +
                     "] does not hold " + shard_box);
      }
    }
  }

  std::vector<Vec3> mesh_vertices() const {
    const auto values = read_dataset<double>(schema::dataset::mesh_vertices, 3);
    std::vector<Vec3> vertices(values.size() / 3);
    copy_rows(values, vertices);
    return vertices;
  }

  // ---- attributes -------------------------------------------------------------------------

  bool has_attribute(hid_t object, const char* name) const {
    const htri_t exists = H5Aexists(object, name);
    if (exists < 0) hdf5_format_error("cannot look up root attribute '" + std::string(name) + "'");
    return exists > 0;
  }

  AttributeHandle open_attribute(hid_t object, const char* name) const {
    const htri_t exists = H5Aexists(object, name);
    if (exists < 0) hdf5_format_error("cannot look up root attribute '" + std::string(name) + "'");
    if (exists == 0) format_error("root attribute '" + std::string(name) + "' is missing");
    AttributeHandle attribute(H5Aopen(object, name, H5P_DEFAULT));
    if (!attribute) hdf5_format_error("cannot open root attribute '" + std::string(name) + "'");
    return attribute;
  }

  std::string read_string_attribute(hid_t object, const char* name) const {
    AttributeHandle attribute = open_attribute(object, name);
    DatatypeHandle type(H5Aget_type(attribute.get()));
    DataspaceHandle space(H5Aget_space(attribute.get()));
    if (!type || !space) hdf5_format_error("cannot inspect root attribute '" + std::string(name) + "'");
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

  /// A variable-length string attribute, read from the global heap object that holds it once
  /// its claimed length is checked against the file and the object against its collection.
  /// Not through HDF5's conversion: HDF5 1.10 allocates the claimed length twice (and, for a
  /// damaged type, the length times a damaged character size: fuzz_index) before reading.
  std::string stored_string(hid_t attribute, const char* name) const {
    detail::StoredVlenString stored;
    if (!detail::read_stored_vlen_string(attribute, address_bytes, stored))
      hdf5_format_error("cannot read root attribute '" + std::string(name) + "'");
    const std::string what = "root attribute '" + std::string(name) + "'";
    if (stored.length > file_bytes)
      format_error(what + " claims a string of " + std::to_string(stored.length) + " bytes, more than the " +
                   std::to_string(file_bytes) + "-byte file holds");
    if (stored.length == 0) return {};  // nothing is stored in the heap
    const std::uint64_t offset = base_address + stored.heap_address;
    const std::string place = " (global heap collection at " + std::to_string(stored.heap_address) + ", object " +
                              std::to_string(stored.heap_index) + ")";
    unsigned char head[16];
    if (offset > file_bytes || file_bytes - offset < sizeof head)
      format_error(what + ": its string" + place + " lies past the end of the " + std::to_string(file_bytes) +
                   "-byte file");
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

  template <class T>
  std::vector<T> read_number_attribute(hid_t object, const char* name, std::size_t count) const {
    AttributeHandle attribute = open_attribute(object, name);
    DatatypeHandle type(H5Aget_type(attribute.get()));
    DataspaceHandle space(H5Aget_space(attribute.get()));
    if (!type || !space) hdf5_format_error("cannot inspect root attribute '" + std::string(name) + "'");
    const H5T_class_t type_class = H5Tget_class(type.get());
    const bool is_integer = std::is_integral_v<T>;
    const bool class_ok = is_integer ? (type_class == H5T_INTEGER &&
                                        H5Tget_sign(type.get()) == H5T_SGN_NONE)
                                     : (type_class == H5T_FLOAT || type_class == H5T_INTEGER);
    const auto points = H5Sget_simple_extent_npoints(space.get());
    if (!class_ok || points != static_cast<hssize_t>(count))
      format_error("root attribute '" + std::string(name) + "' is " + describe_type(type.get()) +
                   " with " + std::to_string(points) + " elements, expected " +
                   std::to_string(count) + (is_integer ? " unsigned integer" : " number") +
                   (count == 1 ? "" : "s"));
    std::vector<T> values(count);
    if (H5Aread(attribute.get(), is_integer ? H5T_NATIVE_UINT64 : H5T_NATIVE_DOUBLE,
                values.data()) < 0)
      hdf5_format_error("cannot read root attribute '" + std::string(name) + "'");
    return values;
  }

  // ---- datasets ---------------------------------------------------------------------------

  DatasetHandle open_dataset(const std::string& name) const {
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

  /// Checks element type and shape (rank 1 if columns == 0, else [rows, columns]); returns rows.
  std::uint64_t check_dataset(hid_t dataset, const std::string& name, Element element,
                              std::uint64_t columns) const {
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

  /// A dataset's claimed size against the file's, before anything is sized by it: stored
  /// unfiltered, it cannot decode to more bytes than the file has; through a compressing
  /// filter, to more than deflate's ratio allows.
  void check_dataset_size(hid_t dataset, const std::string& name, Element element, std::uint64_t rows,
                          std::uint64_t columns) const {
    PropertyListHandle creation(H5Dget_create_plist(dataset));
    if (!creation) hdf5_format_error("cannot inspect '" + name + "'");
    std::uint64_t ratio = 1;
    const int filters = H5Pget_nfilters(creation.get());
    for (int f = 0; f < filters; ++f) {
      unsigned flags = 0;
      std::size_t values = 0;
      if (H5Pget_filter2(creation.get(), static_cast<unsigned>(f), &flags, &values, nullptr, 0, nullptr,
                         nullptr) != H5Z_FILTER_FLETCHER32)
        ratio = kMaxFilterRatio;
    }
    const std::uint64_t row_bytes = std::max<std::uint64_t>(columns, 1) * element_bytes(element);
    if (rows > file_bytes / row_bytes * ratio)
      format_error("'" + name + "' claims " + std::to_string(rows) + " rows of " + std::to_string(row_bytes) +
                   " bytes, more than the " + std::to_string(file_bytes) + "-byte file can hold");
    if (H5Pget_layout(creation.get()) != H5D_CHUNKED) return;
    // HDF5 allocates a whole chunk to read one: a damaged chunk shape must not size gigabytes.
    std::array<hsize_t, 2> chunk{1, 1};
    const int rank = H5Pget_chunk(creation.get(), 2, chunk.data());
    std::uint64_t chunk_bytes = element_bytes(element);
    for (int d = 0; d < std::min(rank, 2); ++d)
      chunk_bytes = chunk[d] > kMaxChunkBytes ? kMaxChunkBytes + 1
                                              : std::min<std::uint64_t>(chunk_bytes * chunk[d], kMaxChunkBytes + 1);
    if (rank < 1 || chunk[0] == 0 || chunk_bytes > kMaxChunkBytes)
      format_error("'" + name + "' has chunks of " + std::to_string(chunk[0]) + " x " + std::to_string(chunk[1]) +
                   " elements, more than " + std::to_string(kMaxChunkBytes) + " bytes");
    check_stored_chunks(dataset, name, rows, chunk[0]);
  }

  /// Each stored chunk's size from the chunk index against the file's: HDF5 allocates and
  /// reads a filtered chunk at the size its index claims (fuzz_index: 3.5 GB in a 60 KB file).
  void check_stored_chunks(hid_t dataset, const std::string& name, std::uint64_t rows, std::uint64_t chunk_rows) const {
    const std::uint64_t chunks = rows / chunk_rows + (rows % chunk_rows != 0);
    if (chunks > file_bytes / kMinStoredChunkBytes)  // the writer stores every chunk it uses
      format_error("'" + name + "' claims " + std::to_string(chunks) + " chunks of " + std::to_string(chunk_rows) +
                   " rows, more than the " + std::to_string(file_bytes) + "-byte file can store");
    for (std::uint64_t first = 0; first < rows; first += chunk_rows) {
      std::array<hsize_t, 2> coordinate{first, 0};
      hsize_t stored = 0;
      if (H5Dget_chunk_storage_size(dataset, coordinate.data(), &stored) < 0) {
        detail::take_hdf5_error();  // an unallocated chunk reads as fill values
        continue;
      }
      if (stored > file_bytes)
        format_error("'" + name + "' stores the chunk at row " + std::to_string(first) + " in " +
                     std::to_string(stored) + " bytes, more than the " + std::to_string(file_bytes) + "-byte file");
    }
  }

  static constexpr std::uint64_t kAnyRows = ~std::uint64_t{0};

  /// The whole dataset; with `expected_rows`, a dataset of another length is rejected first.
  template <class T>
  std::vector<T> read_dataset(const std::string& name, std::uint64_t columns,
                              std::uint64_t expected_rows = kAnyRows,
                              const std::string& expected_by = std::string()) const {
    DatasetHandle dataset = open_dataset(name);
    const std::uint64_t rows = check_dataset(dataset.get(), name, element_of<T>(), columns);
    if (expected_rows != kAnyRows && rows != expected_rows)
      format_error("'" + name + "' has " + std::to_string(rows) + " entries, expected " +
                   std::to_string(expected_rows) + " (" + expected_by + ")");
    check_dataset_size(dataset.get(), name, element_of<T>(), rows, columns);
    std::vector<T> values(rows * std::max<std::uint64_t>(columns, 1));
    if (!values.empty() && H5Dread(dataset.get(), memory_type(element_of<T>()), H5S_ALL, H5S_ALL,
                                   H5P_DEFAULT, values.data()) < 0)
      hdf5_format_error("cannot read '" + name + "'");
    return values;
  }

  template <class T>
  std::vector<T> read_table(std::string_view name) const {
    detail::enter_hdf5();
    // A table read lazily (CollisionIndex's id ranges) may meet a prefetching thread's page-in:
    // HDF5 is not thread-safe.
    const std::lock_guard lock(chunk_read_mutex());
    if (!std::binary_search(tables.begin(), tables.end(), name))
      format_error("table '/tables/" + std::string(name) + "' is missing");
    const auto expected = expected_lengths.find(name);
    if (expected == expected_lengths.end()) return read_dataset<T>(schema::table_path(name), 0);
    return read_dataset<T>(schema::table_path(name), 0, expected->second, length_reason(expected->first));
  }

  // ---- shard data -------------------------------------------------------------------------

  void check_shard_data_layout() {
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
    if (H5Pget_chunk(creation.get(), 1, &chunk) != 1 || chunk == 0 || chunk > kMaxChunkBytes / kWordBytes)
      format_error("'" + name + "' has an unusable chunk shape (" + std::to_string(chunk) + " words; at most " +
                   std::to_string(kMaxChunkBytes / kWordBytes) + ")");
    chunk_bytes = static_cast<std::uint32_t>(chunk * kWordBytes);
    // Every chunk a shard uses is stored, in a few bytes at least: the chunk table that locating
    // them fills (inspect, validate) is sized by this.
    const std::uint64_t chunk_count = data_extent / chunk_bytes + (data_extent % chunk_bytes != 0);
    if (chunk_count > file_bytes / kMinStoredChunkBytes)
      format_error("'" + name + "' claims " + std::to_string(data_extent / kWordBytes) + " words (" +
                   std::to_string(data_extent) + " bytes) in " + std::to_string(chunk_count) +
                   " chunks, more than the " + std::to_string(file_bytes) + "-byte file can hold");
    const int filters = H5Pget_nfilters(creation.get());
    std::array<H5Z_filter_t, 3> expected{H5Z_FILTER_SHUFFLE, detail::kLz4FilterId, H5Z_FILTER_FLETCHER32};
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
                   std::to_string(H5Z_FILTER_SHUFFLE) + ", " + std::to_string(detail::kLz4FilterId) + ", " +
                   std::to_string(H5Z_FILTER_FLETCHER32) + "] (shuffle, LZ4, fletcher32)");
  }

  std::vector<std::string> extent_problems() const {
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
                           "), beyond the " + std::to_string(data_extent) +
                           " bytes of /shards/data");
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

  void locate_chunks() {
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
        format_error("chunk " + std::to_string(c) + " of /shards/data claims " + std::to_string(stored) +
                     " stored bytes for a " + std::to_string(chunk_bytes) + "-byte chunk");
      chunks[c] = ChunkLocation{address, stored, mask};
    }
  }

  /// The checks of every open after HDF5 opened the file: the header, the mesh's shapes, the
  /// shard extents and layout, the tables.
  void check_opened_index() {
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

  // ---- raw reads --------------------------------------------------------------------------

  /// pread() of the file, or a copy from the in-memory image (0 past its end).
  ssize_t read_at(std::byte* buffer, std::uint64_t bytes, std::uint64_t offset) const {
    if (!in_memory) return ::pread(descriptor.get(), buffer, bytes, static_cast<off_t>(offset));
    if (offset >= image.size()) return 0;
    const std::uint64_t count = std::min<std::uint64_t>(bytes, image.size() - offset);
    std::memcpy(buffer, image.data() + offset, count);
    return static_cast<ssize_t>(count);
  }

  void pread_all(std::byte* buffer, std::uint64_t bytes, std::uint64_t offset,
                 const std::string& what) const {
    while (bytes > 0) {
      const ssize_t got = read_at(buffer, bytes, offset);
      if (got < 0) {
        if (errno == EINTR) continue;
        throw IoError("cannot read " + what + " of " + where() + ": " + std::strerror(errno));
      }
      if (got == 0)
        shard_read_error(what, "it lies past the end of the file (at byte " + std::to_string(offset) + ")");
      buffer += got;
      bytes -= static_cast<std::uint64_t>(got);
      offset += static_cast<std::uint64_t>(got);
    }
  }

  /// More than a chunk can take stored (LZ4's worst case and the frame's and checksum's bytes
  /// are far below): a larger claim is damage, not a size to allocate.
  std::uint64_t max_stored_bytes() const { return 2 * std::uint64_t(chunk_bytes) + 64; }

  /// The stored bytes of one chunk (into `stored`, reusing its capacity) and its filter mask,
  /// through HDF5's direct chunk read.
  void read_stored_chunk(std::uint32_t shard, std::uint64_t k, std::uint32_t& mask,
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

  /// Bytes of the shard's payload that chunk k holds.
  std::uint64_t payload_in_chunk(std::uint32_t shard, std::uint64_t k) const {
    return std::min<std::uint64_t>(chunk_bytes, sizes[shard] - k * chunk_bytes);
  }

  /// A stored chunk's size against the payload it must decode to, before the payload is
  /// allocated: LZ4 cannot decode more than kMaxLz4Ratio bytes per stored byte.
  void check_stored_claim(std::uint32_t shard, std::uint64_t k, std::uint64_t stored_bytes) const {
    if (stored_bytes * kMaxLz4Ratio < payload_in_chunk(shard, k))
      format_error(chunk_name(shard, k) + " holds " + std::to_string(stored_bytes) + " stored bytes for " +
                   std::to_string(payload_in_chunk(shard, k)) + " bytes of payload, more than LZ4 decodes to");
  }

  /// Checks and decompresses stored chunk k of a shard into its place in `payload`. A page-in
  /// decodes the last chunk's payload only; with `whole_chunk` (validate) every block of it is
  /// decoded, there.
  void decode_into(std::uint32_t shard, std::uint64_t k, std::span<const std::byte> stored,
                   std::uint32_t filter_mask, std::vector<std::byte>& payload,
                   std::vector<std::byte>* whole_chunk = nullptr) const {
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
    if (target.data() != payload.data() + begin) std::memcpy(payload.data() + begin, target.data(), bytes);
  }

  void read_shard(std::uint32_t shard, std::vector<std::byte>& payload) const {
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
      for (std::uint64_t k = 0; k < count; ++k) check_stored_claim(shard, k, chunks[first + k].stored_bytes);
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
      if (stored[0].capacity() > kKeptBufferBytes) std::vector<std::byte>().swap(stored[0]);  // a rare large shard
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

  /// Held over a page-in's direct chunk reads; one for the process, as HDF5's lock is.
  static std::mutex& chunk_read_mutex() {
    static std::mutex mutex;
    return mutex;
  }
};

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

const std::filesystem::path& IndexReader::path() const { return impl_->path; }
const IndexHeader& IndexReader::header() const { return impl_->header; }
std::uint64_t IndexReader::file_bytes() const { return impl_->file_bytes; }

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
std::vector<std::string> IndexReader::table_names() const { return impl_->tables; }

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
std::uint32_t IndexReader::chunk_bytes() const { return impl_->chunk_bytes; }

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
            case Element::uint8: r.read_dataset<std::uint8_t>(dataset, 0); break;
            case Element::uint32: r.read_dataset<std::uint32_t>(dataset, 0); break;
            case Element::uint64: r.read_dataset<std::uint64_t>(dataset, 0); break;
            case Element::float64: r.read_dataset<double>(dataset, 0); break;
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
