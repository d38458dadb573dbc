#include "tetrapage/formats/IndexReader.h"

#include <fcntl.h>
#include <hdf5.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <atomic>
#include <cstring>
#include <mutex>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "ChunkCodec.h"
#include "Hdf5Handle.h"
#include "tetrapage/formats/Error.h"
#include "tetrapage/formats/SpinThenBlock.h"

namespace tetrapage {

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

}  // namespace

struct IndexReader::Impl {
  std::filesystem::path path;
  std::chrono::microseconds spin_before_sleep{100};
  IndexHeader header;
  std::uint64_t file_bytes = 0;
  Descriptor descriptor;
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
  std::vector<std::string> tables;

  std::string where() const { return "index '" + path.string() + "'"; }
  [[noreturn]] void format_error(const std::string& what) const {
    throw FormatError(where() + ": " + what);
  }
  [[noreturn]] void hdf5_format_error(const std::string& what) const {
    throw FormatError(where() + ": " + what + ": " + detail::take_hdf5_error());
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

  // ---- attributes -------------------------------------------------------------------------

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
    if (H5Tis_variable_str(type.get()) > 0) {
      DatatypeHandle memory(H5Tcopy(H5T_C_S1));
      if (!memory || H5Tset_size(memory.get(), H5T_VARIABLE) < 0 ||
          H5Tset_cset(memory.get(), H5Tget_cset(type.get())) < 0)
        hdf5_format_error("cannot read root attribute '" + std::string(name) + "'");
      char* text = nullptr;
      if (H5Aread(attribute.get(), memory.get(), &text) < 0)
        hdf5_format_error("cannot read root attribute '" + std::string(name) + "'");
      std::string value = text != nullptr ? std::string(text) : std::string();
      H5free_memory(text);
      return value;
    }
    std::string value(H5Tget_size(type.get()), '\0');
    if (H5Aread(attribute.get(), type.get(), value.data()) < 0)
      hdf5_format_error("cannot read root attribute '" + std::string(name) + "'");
    value.resize(std::strlen(value.c_str()));  // fixed-length strings are padded with NULs
    return value;
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

  template <class T>
  std::vector<T> read_dataset(const std::string& name, std::uint64_t columns) const {
    DatasetHandle dataset = open_dataset(name);
    const std::uint64_t rows = check_dataset(dataset.get(), name, element_of<T>(), columns);
    std::vector<T> values(rows * std::max<std::uint64_t>(columns, 1));
    if (!values.empty() && H5Dread(dataset.get(), memory_type(element_of<T>()), H5S_ALL, H5S_ALL,
                                   H5P_DEFAULT, values.data()) < 0)
      hdf5_format_error("cannot read '" + name + "'");
    return values;
  }

  template <class T>
  std::vector<T> read_table(std::string_view name) const {
    detail::enter_hdf5();
    if (!std::binary_search(tables.begin(), tables.end(), name))
      format_error("table '/tables/" + std::string(name) + "' is missing");
    return read_dataset<T>("/tables/" + std::string(name), 0);
  }

  // ---- shard data -------------------------------------------------------------------------

  void check_shard_data_layout() {
    const std::string name = "/shards/data";
    // 8-byte words (the shuffle filter's element); extents and chunks are counted in bytes.
    data_extent = check_dataset(shard_data.get(), name, Element::uint64, 0) * kWordBytes;
    PropertyListHandle creation(H5Dget_create_plist(shard_data.get()));
    if (!creation) hdf5_format_error("cannot inspect '" + name + "'");
    if (H5Pget_layout(creation.get()) != H5D_CHUNKED) format_error("'" + name + "' is not chunked");
    hsize_t chunk = 0;
    if (H5Pget_chunk(creation.get(), 1, &chunk) != 1 || chunk == 0 || chunk > 0xffffffffu / kWordBytes)
      format_error("'" + name + "' has an unusable chunk shape");
    chunk_bytes = static_cast<std::uint32_t>(chunk * kWordBytes);
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

  // ---- raw reads --------------------------------------------------------------------------

  void pread_all(std::byte* buffer, std::uint64_t bytes, std::uint64_t offset,
                 const std::string& what) const {
    while (bytes > 0) {
      const ssize_t got = ::pread(descriptor.get(), buffer, bytes, static_cast<off_t>(offset));
      if (got < 0) {
        if (errno == EINTR) continue;
        throw IoError("cannot read " + what + " of " + where() + ": " + std::strerror(errno));
      }
      if (got == 0)
        format_error(what + " lies past the end of the file (truncated at " +
                     std::to_string(offset) + " bytes?)");
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
      hdf5_format_error("cannot locate " + chunk_name(shard, k));
    if (stored_bytes == 0) format_error(chunk_name(shard, k) + " is not stored");
    if (stored_bytes > max_stored_bytes())
      format_error(chunk_name(shard, k) + " claims " + std::to_string(stored_bytes) +
                   " stored bytes for a " + std::to_string(chunk_bytes) + "-byte chunk");
    stored.resize(stored_bytes);
    if (H5Dread_chunk(shard_data.get(), H5P_DEFAULT, &coordinate, &mask, stored.data()) < 0)
      hdf5_format_error("cannot read " + chunk_name(shard, k));
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
    const std::string problem = detail::decode_chunk(stored, filter_mask, target, chunk_bytes);
    if (!problem.empty()) format_error(chunk_name(shard, k) + ": " + problem);
    if (target.data() != payload.data() + begin) std::memcpy(payload.data() + begin, target.data(), bytes);
  }

  void read_shard(std::uint32_t shard, std::vector<std::byte>& payload) const {
    check_shard(shard);
    payload.resize(sizes[shard]);
    if (payload.empty()) return;
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
  Impl& r = *impl_;
  r.path = path;
  r.descriptor = Descriptor(::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC));
  if (r.descriptor.get() < 0)
    throw IoError("cannot open " + r.where() + ": " + std::strerror(errno));
  struct stat status {};
  if (::fstat(r.descriptor.get(), &status) != 0)
    throw IoError("cannot inspect " + r.where() + ": " + std::strerror(errno));
  if (!S_ISREG(status.st_mode)) throw IoError("cannot open " + r.where() + ": not a regular file");
  r.file_bytes = static_cast<std::uint64_t>(status.st_size);

  const htri_t is_hdf5 = H5Fis_hdf5(path.c_str());
  if (is_hdf5 <= 0) {
    detail::take_hdf5_error();
    r.format_error("not an HDF5 file (no HDF5 signature in its " + std::to_string(r.file_bytes) +
                   " bytes); expected a tetrapage index");
  }
  r.file = FileHandle(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT));
  if (!r.file) r.hdf5_format_error("HDF5 cannot open it (damaged or truncated)");
  {
    PropertyListHandle creation(H5Fget_create_plist(r.file.get()));
    hsize_t user_block = 0;
    if (!creation || H5Pget_userblock(creation.get(), &user_block) < 0)
      r.hdf5_format_error("cannot inspect the file creation properties");
    r.raw_reads = user_block == 0;
  }

  // Root attributes; the format name first, so a foreign HDF5 file gets the clearest message.
  GroupHandle root(H5Gopen2(r.file.get(), "/", H5P_DEFAULT));
  if (!root) r.hdf5_format_error("cannot open the root group");
  const hid_t g = root.get();
  if (H5Aexists(g, "format") <= 0)
    r.format_error("no root attribute 'format': not a tetrapage index (expected format '" +
                   std::string(kIndexFormatName) + "')");
  const std::string format = r.read_string_attribute(g, "format");
  if (format != kIndexFormatName)
    r.format_error("root attribute 'format' is '" + format + "', expected '" +
                   std::string(kIndexFormatName) + "': not a tetrapage index");
  const std::uint64_t version = r.read_number_attribute<std::uint64_t>(g, "version", 1)[0];
  if (version != kIndexVersion)
    r.format_error("version " + std::to_string(version) + " is not supported (this program reads "
                   "version " + std::to_string(kIndexVersion) + "): rebuild the index");
  IndexHeader& h = r.header;
  h.version = static_cast<std::uint32_t>(version);
  h.precision = r.read_string_attribute(g, "precision");
  if (h.precision != "float" && h.precision != "double" && h.precision != "exact")
    r.format_error("root attribute 'precision' is '" + h.precision +
                   "', expected 'exact', 'float' or 'double'");
  h.input_triangles = r.read_number_attribute<std::uint64_t>(g, "input_triangles", 1)[0];
  h.stored_triangles = r.read_number_attribute<std::uint64_t>(g, "stored_triangles", 1)[0];
  h.region_count = r.read_number_attribute<std::uint64_t>(g, "region_count", 1)[0];
  h.shard_count = r.read_number_attribute<std::uint64_t>(g, "shard_count", 1)[0];
  h.max_rounding_distance = r.read_number_attribute<double>(g, "max_rounding_distance", 1)[0];
  const auto bounds = r.read_number_attribute<double>(g, "bounds", 6);
  h.bounds.lo = {bounds[0], bounds[1], bounds[2]};
  h.bounds.hi = {bounds[3], bounds[4], bounds[5]};
  h.source = r.read_string_attribute(g, "source");
  h.build_report_json = r.read_string_attribute(g, "build_report");
  h.created_by = r.read_string_attribute(g, "created_by");
  if (h.shard_count >= 0xffffffffu)
    r.format_error("root attribute 'shard_count' is " + std::to_string(h.shard_count) +
                   ", more than 2^32 - 1");

  // Shapes of the mesh (read lazily by read_mesh).
  {
    DatasetHandle vertices = r.open_dataset("/mesh/vertices");
    r.check_dataset(vertices.get(), "/mesh/vertices", Element::float64, 3);
    DatasetHandle tets = r.open_dataset("/mesh/tets");
    const auto tet_rows = r.check_dataset(tets.get(), "/mesh/tets", Element::uint32, 4);
    DatasetHandle neighbours = r.open_dataset("/mesh/neighbours");
    const auto neighbour_rows =
        r.check_dataset(neighbours.get(), "/mesh/neighbours", Element::uint32, 4);
    if (tet_rows != neighbour_rows)
      r.format_error("'/mesh/tets' has " + std::to_string(tet_rows) +
                     " rows but '/mesh/neighbours' has " + std::to_string(neighbour_rows));
  }

  // Tables: just their names; each is checked when read.
  {
    GroupHandle tables(H5Lexists(r.file.get(), "tables", H5P_DEFAULT) > 0
                           ? H5Gopen2(r.file.get(), "tables", H5P_DEFAULT)
                           : H5I_INVALID_HID);
    if (!tables) r.format_error("group '/tables' is missing");
    hsize_t index = 0;
    const auto collect = [](hid_t, const char* name, const H5L_info_t*, void* names) -> herr_t {
      static_cast<std::vector<std::string>*>(names)->emplace_back(name);
      return 0;
    };
    if (H5Literate(tables.get(), H5_INDEX_NAME, H5_ITER_INC, &index, collect, &r.tables) < 0)
      r.hdf5_format_error("cannot list '/tables'");
    std::sort(r.tables.begin(), r.tables.end());
  }

  // Shards: extents, layout and chunk addresses.
  r.offsets = r.read_dataset<std::uint64_t>("/shards/offsets", 0);
  r.sizes = r.read_dataset<std::uint64_t>("/shards/sizes", 0);
  if (r.offsets.size() != h.shard_count || r.sizes.size() != h.shard_count)
    r.format_error("'/shards/offsets' has " + std::to_string(r.offsets.size()) +
                   " entries and '/shards/sizes' " + std::to_string(r.sizes.size()) +
                   ", but root attribute 'shard_count' is " + std::to_string(h.shard_count));
  r.shard_data = r.open_dataset("/shards/data");
  r.check_shard_data_layout();
  const auto problems = r.extent_problems();
  if (!problems.empty())
    r.format_error("inconsistent shard extents: " + problems.front() +
                   (problems.size() > 1
                        ? " (and " + std::to_string(problems.size() - 1) + " more problems)"
                        : std::string()));
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
  const auto vertices = r.read_dataset<double>("/mesh/vertices", 3);
  const auto tets = r.read_dataset<std::uint32_t>("/mesh/tets", 4);
  const auto neighbours = r.read_dataset<std::uint32_t>("/mesh/neighbours", 4);
  TetMesh mesh;
  mesh.vertices.resize(vertices.size() / 3);
  std::memcpy(mesh.vertices.data(), vertices.data(), vertices.size() * sizeof(double));
  mesh.tets.resize(tets.size() / 4);
  std::memcpy(mesh.tets.data(), tets.data(), tets.size() * sizeof(std::uint32_t));
  mesh.neighbours.resize(neighbours.size() / 4);
  std::memcpy(mesh.neighbours.data(), neighbours.data(), neighbours.size() * sizeof(std::uint32_t));
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
      payload.resize(r.sizes[s]);
      bool intact = true;
      for (std::uint64_t k = 0; k < r.chunk_count(s); ++k) {
        try {
          std::uint32_t mask = 0;
          r.read_stored_chunk(s, k, mask, stored);
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
      const std::string dataset = "/tables/" + name;
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
