#pragma once
/// @file IndexReaderImpl.h (private)
/// IndexReader's state and its steps, shared by IndexReader.cpp (opening, attributes, datasets,
/// shard reads) and IndexValidation.cpp (every check of the opened file against what its header
/// and the format state, before any answer is read from it).

#include <fcntl.h>
#include <hdf5.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
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
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/SpinThenBlock.h"
#include "tetrapage/formats/base/TextNumbers.h"
#include "tetrapage/formats/index/IndexReader.h"
#include "tetrapage/formats/index/IndexSchema.h"

namespace tetrapage {

namespace schema = index_schema;

namespace index_reader_detail {

/// A dataset's values into rows of as many values (Vec3, tets): memcpy, but never from the
/// null data of an empty vector (undefined behaviour even for 0 bytes).
template <class Value, class Row>
void copy_rows(const std::vector<Value>& values, std::vector<Row>& rows) {
  static_assert(sizeof(Row) % sizeof(Value) == 0);
  if (!values.empty()) std::memcpy(rows.data(), values.data(), values.size() * sizeof(Value));
}

}  // namespace index_reader_detail

using namespace index_reader_detail;

using detail::AttributeHandle;
using detail::DatasetHandle;
using detail::DataspaceHandle;
using detail::DatatypeHandle;
using detail::FileHandle;
using detail::GroupHandle;
using detail::PropertyListHandle;

namespace index_reader_detail {

constexpr std::uint64_t kUnallocated = ~std::uint64_t{0};
/// One pread() may span small holes between a shard's chunks (HDF5 metadata blocks can land
/// between them) rather than splitting into one read per chunk.
constexpr std::uint64_t kMaxHoleBytes = 64 * 1024;
// /shards/data is stored as 8-byte little-endian words: the shuffle's element (ChunkCodec.h).
constexpr std::uint64_t kWordBytes = detail::kShuffleElementBytes;

enum class Element { uint8, uint32, uint64, float64 };

inline const char* element_name(Element element) {
  switch (element) {
    case Element::uint8:
      return "uint8";
    case Element::uint32:
      return "uint32";
    case Element::uint64:
      return "uint64";
    case Element::float64:
      return "float64";
  }
  return "?";
}

inline std::string describe_type(hid_t type) {
  const H5T_class_t type_class = H5Tget_class(type);
  const std::size_t bits = 8 * H5Tget_size(type);
  switch (type_class) {
    case H5T_INTEGER:
      return std::string(H5Tget_sign(type) == H5T_SGN_NONE ? "uint" : "int") + std::to_string(bits);
    case H5T_FLOAT:
      return "float" + std::to_string(bits);
    case H5T_STRING:
      return "string";
    case H5T_COMPOUND:
      return "compound";
    default:
      return "type class " + std::to_string(static_cast<int>(type_class));
  }
}

inline bool type_matches(hid_t type, Element element) {
  const H5T_class_t type_class = H5Tget_class(type);
  const std::size_t size = H5Tget_size(type);
  switch (element) {
    case Element::uint8:
    case Element::uint32:
    case Element::uint64: {
      const std::size_t expected = element == Element::uint8    ? 1
                                   : element == Element::uint32 ? 4
                                                                : 8;
      return type_class == H5T_INTEGER && size == expected && H5Tget_sign(type) == H5T_SGN_NONE;
    }
    case Element::float64:
      return type_class == H5T_FLOAT && size == 8;
  }
  return false;
}

inline std::uint64_t element_bytes(Element element) {
  switch (element) {
    case Element::uint8:
      return 1;
    case Element::uint32:
      return 4;
    case Element::uint64:
    case Element::float64:
      return 8;
  }
  return 8;
}

inline hid_t memory_type(Element element) {
  switch (element) {
    case Element::uint8:
      return H5T_NATIVE_UINT8;
    case Element::uint32:
      return H5T_NATIVE_UINT32;
    case Element::uint64:
      return H5T_NATIVE_UINT64;
    case Element::float64:
      return H5T_NATIVE_DOUBLE;
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

inline std::uint64_t load_le(const unsigned char* bytes, std::size_t count) {
  std::uint64_t value = 0;
  for (std::size_t i = count; i-- > 0;) value = (value << 8) | bytes[i];
  return value;
}

/// Where a variable-length string's bytes lie: HDF5's global heap collection (the HDF5 file
/// format, "Global Heap"), walked object by object as HDF5 does when it loads one, checked
/// before HDF5 reads it (HDF5 1.10 trusts the sizes it finds there and reads past the
/// collection). `collection` is the collection's bytes; "" or what is wrong.
inline std::string heap_object_problem(const std::vector<unsigned char>& collection,
                                       std::size_t length_bytes,
                                       const detail::StoredVlenString& stored,
                                       std::uint64_t& object_at) {
  const auto align8 = [](std::uint64_t x) { return (x + 7) / 8 * 8; };
  const std::uint64_t header = align8(8 + length_bytes), object_header = 8 + length_bytes;
  if (collection.size() < header || std::memcmp(collection.data(), "GCOL", 4) != 0 ||
      collection[4] != 1)
    return "no global heap collection there";
  const std::uint64_t size = collection.size();
  bool found = false;
  std::uint64_t at = header;
  while (at < size) {
    if (size - at < object_header) break;  // too small for an object: free space, as HDF5 reads it
    const std::uint64_t index = load_le(&collection[at], 2);
    const std::uint64_t bytes = load_le(&collection[at + 8], length_bytes);
    if (bytes > size)
      return "object " + std::to_string(index) + " claims " + std::to_string(bytes) + " bytes";
    // Index 0 is the free space, whose size counts its header.
    const std::uint64_t step = index == 0 ? bytes : object_header + align8(bytes);
    if (step == 0 || step > size - at)
      return "object " + std::to_string(index) + " of " + std::to_string(bytes) +
             " bytes runs past the collection";
    if (index == stored.heap_index && index != 0) {
      if (bytes != stored.length)
        return "object " + std::to_string(index) + " holds " + std::to_string(bytes) +
               " bytes, not " + std::to_string(stored.length);
      found = true;
      object_at = at + object_header;
    }
    at += step;
  }
  return found ? std::string()
               : "no object " + std::to_string(stored.heap_index) + " in the collection";
}

}  // namespace index_reader_detail

using namespace index_reader_detail;

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
  void ensure_located() const;
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
  [[noreturn]] void format_error(const std::string& what) const;
  [[noreturn]] void hdf5_format_error(const std::string& what) const;

  /// Whether the open file's size or modification time is not what it was when opened: a
  /// file rewritten or truncated under a running reader, which a message should say rather
  /// than describe the bytes it now finds.
  bool file_changed(std::uint64_t& bytes_now) const;

  /// @throw FormatError for a shard's chunk that cannot be read or decoded: "the file changed or
  /// is truncated" when it did, or when the chunk read as zeros (HDF5 reads zeros past the end
  /// of a file), else `problem` as it is. With `hdf5`, HDF5's reason is appended.
  [[noreturn]] void shard_read_error(const std::string& what, const std::string& problem,
                                     bool read_zeros = false, bool hdf5 = false) const;

  void check_shard(std::uint32_t shard) const;
  std::uint64_t first_chunk(std::uint32_t shard) const { return offsets[shard] / chunk_bytes; }
  std::uint64_t chunk_count(std::uint32_t shard) const;
  std::string chunk_name(std::uint32_t shard, std::uint64_t k) const;

  // ---- opening ----------------------------------------------------------------------------

  void open_file();

  void open_image(std::span<const std::byte> bytes);

  // The user block and the sizes of addresses and lengths of the file HDF5 opened.
  void inspect_opened_file();

  /// Superblocks 0 and 1, and the object headers and B-trees that go with them, carry no
  /// checksums: HDF5 1.10 decodes their damaged bytes unchecked (and can crash doing so), so
  /// such a file is refused before HDF5 reads it. The writer makes superblock 3. A file
  /// without HDF5's signature is refused here too.
  void require_checksummed_superblock() const;

  /// The root attributes; the format name first, so a foreign HDF5 file gets the clearest message.
  void read_header(hid_t g);

  /// The shapes of the mesh's datasets (read_mesh reads them).
  void check_mesh_shapes();

  /// Links kept in the group's object header, as the writer keeps them: the dense storage of
  /// another writer (a fractal heap and a B-tree) is refused before HDF5 walks it, since HDF5
  /// 1.10 crashes cleaning up after a damaged one.
  void require_compact_links(hid_t group, const char* name) const;

  /// The root's attributes and the links of the root and its groups where the writer keeps
  /// them, in object headers; each group is checked before a path through it is followed.
  void require_compact_storage(hid_t root) const;

  /// The names under /tables (each is read on demand).
  void list_tables();

  // ---- what the header says, checked -------------------------------------------------------

  /// The header's own values: a known precision, a rounding distance that is a distance (and
  /// 0 where nothing is rounded), bounds that are finite and not inverted (or the empty box).
  void check_header_values() const;

  /// The writer's empty box (lo 1e300, hi -1e300), for a model without triangles.
  static bool is_empty_convention(const BoundingBox& b);

  /// The shortest text that reads back as `value` ("1e-07", "nan").
  static std::string number_text(double value);

  /// The tables the preprocess writes have lengths the other tables fix (docs/FORMAT.md):
  /// checked from their shapes before any is read, and again (as a bound) when one is.
  void check_table_lengths();

  /// The counts the header states against the data they count: regions against the coarse
  /// mesh's tets, stored triangles against the shards' counts, input triangles against the
  /// parts' counts (where those tables exist). Readers size and loop by the header's counts.
  void check_header_counts() const;

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

  static std::string length_reason(const std::string& name);

  bool has_table_named(std::string_view name) const {
    return std::binary_search(tables.begin(), tables.end(), name);
  }

  /// A table's length from its shape, without reading it.
  std::uint64_t table_length(std::string_view name) const;

  /// The model's bounds against the data: the coarse mesh covers them (the preprocess encloses
  /// the model in a larger box), and they hold every shard's stored triangles (grown by the
  /// rounding distance and the few ulps the builder adds).
  void check_bounds_against_data() const;

  std::vector<Vec3> mesh_vertices() const;

  // ---- attributes -------------------------------------------------------------------------

  bool has_attribute(hid_t object, const char* name) const;

  AttributeHandle open_attribute(hid_t object, const char* name) const;

  std::string read_string_attribute(hid_t object, const char* name) const;

  /// A variable-length string attribute, read from the global heap object that holds it once
  /// its claimed length is checked against the file and the object against its collection.
  /// Not through HDF5's conversion: HDF5 1.10 allocates the claimed length twice (and, for a
  /// damaged type, the length times a damaged character size: fuzz_index) before reading.
  std::string stored_string(hid_t attribute, const char* name) const;

  template <class T>
  std::vector<T> read_number_attribute(hid_t object, const char* name, std::size_t count) const {
    AttributeHandle attribute = open_attribute(object, name);
    DatatypeHandle type(H5Aget_type(attribute.get()));
    DataspaceHandle space(H5Aget_space(attribute.get()));
    if (!type || !space)
      hdf5_format_error("cannot inspect root attribute '" + std::string(name) + "'");
    const H5T_class_t type_class = H5Tget_class(type.get());
    const bool is_integer = std::is_integral_v<T>;
    const bool class_ok =
        is_integer ? (type_class == H5T_INTEGER && H5Tget_sign(type.get()) == H5T_SGN_NONE)
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

  DatasetHandle open_dataset(const std::string& name) const;

  /// Checks element type and shape (rank 1 if columns == 0, else [rows, columns]); returns rows.
  std::uint64_t check_dataset(hid_t dataset, const std::string& name, Element element,
                              std::uint64_t columns) const;

  /// A dataset's claimed size against the file's, before anything is sized by it: stored
  /// unfiltered, it cannot decode to more bytes than the file has; through a compressing
  /// filter, to more than deflate's ratio allows.
  void check_dataset_size(hid_t dataset, const std::string& name, Element element,
                          std::uint64_t rows, std::uint64_t columns) const;

  /// Each stored chunk's size from the chunk index against the file's: HDF5 allocates and
  /// reads a filtered chunk at the size its index claims (fuzz_index: 3.5 GB in a 60 KB file).
  void check_stored_chunks(hid_t dataset, const std::string& name, std::uint64_t rows,
                           std::uint64_t chunk_rows) const;

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
    return read_dataset<T>(schema::table_path(name), 0, expected->second,
                           length_reason(expected->first));
  }

  // ---- shard data -------------------------------------------------------------------------

  void check_shard_data_layout();

  std::vector<std::string> extent_problems() const;

  void locate_chunks();

  /// The checks of every open after HDF5 opened the file: the header, the mesh's shapes, the
  /// shard extents and layout, the tables.
  void check_opened_index();

  // ---- raw reads --------------------------------------------------------------------------

  /// pread() of the file, or a copy from the in-memory image (0 past its end).
  ssize_t read_at(std::byte* buffer, std::uint64_t bytes, std::uint64_t offset) const;

  void pread_all(std::byte* buffer, std::uint64_t bytes, std::uint64_t offset,
                 const std::string& what) const;

  /// More than a chunk can take stored (LZ4's worst case and the frame's and checksum's bytes
  /// are far below): a larger claim is damage, not a size to allocate.
  std::uint64_t max_stored_bytes() const { return 2 * std::uint64_t(chunk_bytes) + 64; }

  /// The stored bytes of one chunk (into `stored`, reusing its capacity) and its filter mask,
  /// through HDF5's direct chunk read.
  void read_stored_chunk(std::uint32_t shard, std::uint64_t k, std::uint32_t& mask,
                         std::vector<std::byte>& stored) const;

  /// Bytes of the shard's payload that chunk k holds.
  std::uint64_t payload_in_chunk(std::uint32_t shard, std::uint64_t k) const;

  /// A stored chunk's size against the payload it must decode to, before the payload is
  /// allocated: LZ4 cannot decode more than kMaxLz4Ratio bytes per stored byte.
  void check_stored_claim(std::uint32_t shard, std::uint64_t k, std::uint64_t stored_bytes) const;

  /// Checks and decompresses stored chunk k of a shard into its place in `payload`. A page-in
  /// decodes the last chunk's payload only; with `whole_chunk` (validate) every block of it is
  /// decoded, there.
  void decode_into(std::uint32_t shard, std::uint64_t k, std::span<const std::byte> stored,
                   std::uint32_t filter_mask, std::vector<std::byte>& payload,
                   std::vector<std::byte>* whole_chunk = nullptr) const;

  void read_shard(std::uint32_t shard, std::vector<std::byte>& payload) const;

  /// Held over a page-in's direct chunk reads; one for the process, as HDF5's lock is.
  static std::mutex& chunk_read_mutex();
};

}  // namespace tetrapage
