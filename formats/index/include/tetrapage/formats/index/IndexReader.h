#pragma once
/// @file IndexReader.h
/// Opens a tetrapage index (docs/FORMAT.md), checks its layout, and reads the coarse mesh,
/// the tables and the shards. A shard is read with one pread() of its consecutive chunks,
/// then checked (Fletcher-32) and decompressed outside HDF5, so several threads page shards in
/// at once instead of queueing behind HDF5's global lock.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "tetrapage/formats/index/IndexHeader.h"
#include "tetrapage/formats/index/TetMesh.h"

namespace tetrapage {

/// Where one chunk of a shard lies in the file (for `inspect`, tests and tools).
struct StoredChunk {
  std::uint64_t chunk = 0;         ///< chunk number in /shards/data
  std::uint64_t file_offset = 0;   ///< byte offset of the stored chunk in the file
  std::uint64_t stored_bytes = 0;  ///< filtered bytes plus the 4-byte checksum
  bool compressed = true;          ///< false when LZ4 was skipped for this chunk
};

class IndexReader {
 public:
  /// Opens the index and checks the root attributes, the presence, type and shape of every
  /// dataset, and the shard extents (aligned to chunks, inside /shards/data, disjoint), and
  /// locates every chunk of /shards/data.
  /// @throw IoError if the file is missing or unreadable.
  /// @throw FormatError if it is not HDF5, is truncated, is not a tetrapage index (format
  ///        attribute), has another version, or any of the checks fails; the message names
  ///        the file, the object and the value found.
  explicit IndexReader(const std::filesystem::path& path);
  /// Opens an index held in memory (HDF5's core driver), with the same checks; `name` stands
  /// for the file in messages. The reader holds the image twice (its own copy, which shards are
  /// read from, and HDF5's): for small indexes received as bytes, and for fuzzing the reader
  /// without a file system.
  /// @throw FormatError as the constructor above.
  IndexReader(std::span<const std::byte> image, const std::string& name);
  ~IndexReader();
  IndexReader(IndexReader&&) noexcept;
  IndexReader& operator=(IndexReader&&) noexcept;
  IndexReader(const IndexReader&) = delete;
  IndexReader& operator=(const IndexReader&) = delete;

  const std::filesystem::path& path() const;
  const IndexHeader& header() const;
  /// Size of the file in bytes.
  std::uint64_t file_bytes() const;

  /// @throw FormatError if a dataset cannot be read (checksum) or an index is out of range.
  TetMesh read_mesh() const;

  bool has_table(std::string_view name) const;
  /// Names under /tables, sorted.
  std::vector<std::string> table_names() const;
  /// @throw FormatError if the table is missing, is not 1-D, has another element type, or
  ///        cannot be read (checksum).
  std::vector<std::uint8_t> read_table_uint8(std::string_view name) const;
  std::vector<std::uint32_t> read_table_uint32(std::string_view name) const;
  std::vector<std::uint64_t> read_table_uint64(std::string_view name) const;
  std::vector<double> read_table_double(std::string_view name) const;

  std::uint32_t shard_count() const;
  /// Chunk size of /shards/data in bytes.
  std::uint32_t chunk_bytes() const;
  /// Payload bytes of a shard (what read_shard returns).
  /// @throw InputError if shard >= shard_count().
  std::uint64_t shard_size(std::uint32_t shard) const;
  /// Bytes the shard occupies in the file (compressed chunks and checksums).
  /// @throw InputError if shard >= shard_count().
  std::uint64_t stored_shard_size(std::uint32_t shard) const;
  /// The chunks of a shard, in order.
  /// @throw InputError if shard >= shard_count().
  std::vector<StoredChunk> shard_chunks(std::uint32_t shard) const;

  /// The shard's payload. Thread-safe; reads the file directly (one pread() when the chunks
  /// are contiguous on disk) and checks and decompresses outside HDF5.
  /// @throw InputError if shard >= shard_count().
  /// @throw FormatError naming the file, shard and chunk on a checksum mismatch, a chunk
  ///        that does not decompress to the chunk size, or a chunk past the end of the file.
  /// @throw IoError if the operating system fails the read.
  std::vector<std::byte> read_shard(std::uint32_t shard) const;
  /// The same into `payload` (resized to the shard's payload), reusing its capacity: a page-in
  /// loop that keeps one buffer per thread touches no fresh memory. Same errors; after one,
  /// `payload`'s bytes are unspecified.
  void read_shard(std::uint32_t shard, std::vector<std::byte>& payload) const;
  /// How long a read_shard waiting for another thread's chunk reads polls before it sleeps
  /// (SpinThenBlock.h; 100 us unless set; 0: it sleeps at once). Set it before reads begin.
  void set_spin_before_sleep(std::chrono::microseconds limit);

  /// The same payload through H5Dread of the shard's byte range (HDF5 checks and decompresses,
  /// under its global lock, with the LZ4 filter plugin that the HDF Group distributes). For
  /// comparison and as an independent check. Thread-safe.
  /// @throw InputError if shard >= shard_count(), or if HDF5 cannot load the LZ4 plugin.
  /// @throw FormatError if HDF5 fails to read (checksum mismatch, truncation).
  std::vector<std::byte> read_shard_through_hdf5(std::uint32_t shard) const;

  /// Reads everything: every chunk's checksum and decompression, every extent, the mesh (and its
  /// index ranges) and every table. Returns one human-readable line per problem, empty when
  /// the index is valid. Does not throw for problems it finds in the file. `each_shard`, when
  /// given, receives every shard's payload whose chunks all check out, in shard order, so that
  /// a caller checking the payloads too reads and decompresses the data once.
  /// @throw IoError if the operating system fails a read; what each_shard throws.
  std::vector<std::string> validate(
      const std::function<void(std::uint32_t shard, std::span<const std::byte> payload)>&
          each_shard = {}) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tetrapage
