#pragma once
/// @file IndexWriter.h
/// Writes a tetrapage index (one HDF5 file, layout in docs/FORMAT.md) under a temporary name
/// and renames it into place on commit, so a reader never sees a half-written index.
/// Shards are streamed: memory holds one chunk and 16 bytes per shard, never the file.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string_view>
#include <vector>

#include "tetrapage/formats/index/IndexHeader.h"
#include "tetrapage/formats/index/TetMesh.h"

namespace tetrapage {

/// How /shards/data chunks are stored. Either way every chunk carries its Fletcher-32 checksum
/// and any HDF5 reader with the LZ4 plugin reads the file (docs/FORMAT.md).
enum class ChunkCompression : std::uint8_t {
  /// Shuffled and LZ4-compressed (kept as they are where that does not shrink them): the
  /// smaller file.
  lz4,
  /// The payload as it is (only a shard's zero padding compressed): about a third more bytes
  /// on disk, but a page-in's read from the page cache skips LZ4 and the unshuffle, a third of
  /// its time (docs/BENCHMARKS.md, "A page-in, phase by phase").
  none,
};

/// "lz4" or "none". @throw InputError for another name (naming it).
ChunkCompression parse_chunk_compression(std::string_view name);
std::string_view to_string(ChunkCompression compression);

struct IndexWriterOptions {
  /// Chunk size of /shards/data in bytes, a multiple of 8 in 1 KiB .. 64 MiB. Every shard
  /// starts on a chunk boundary, and its last chunk is padded. On the 10M scene's shards (15 KB
  /// on average), shuffled 16 KiB chunks decompress with LZ4 2.4x as fast per payload byte as
  /// 64 KiB ones and are 1 % smaller (tetrapage_bench_chunks; docs/FORMAT.md).
  std::uint32_t chunk_bytes = 16384;
  ChunkCompression compression = ChunkCompression::lz4;
};

/// A shard's payload cut into chunks, each compressed and checksummed as the index stores it.
struct EncodedShard {
  std::uint64_t payload_bytes = 0;
  std::uint32_t chunk_bytes = 0;
  std::vector<std::vector<std::byte>> chunks;
  std::vector<std::uint32_t> filter_masks;  ///< HDF5's per-chunk filter mask (shuffle and LZ4 skipped)
};

/// Compresses a payload as IndexWriter::append_shard does, without a file: thread-safe, so
/// that shards can be compressed in parallel and appended in order.
/// @throw InputError if an option is out of range.
EncodedShard encode_shard(std::span<const std::byte> payload, const IndexWriterOptions& options = {});

class IndexWriter {
 public:
  /// Creates "<path>.tmp-<pid>" next to `path`; `path` itself is untouched until commit().
  /// @throw InputError if an option is out of range.
  /// @throw IoError if the temporary file cannot be created.
  explicit IndexWriter(std::filesystem::path path, IndexWriterOptions options = {});
  /// Removes the temporary file unless commit() succeeded.
  ~IndexWriter();
  IndexWriter(IndexWriter&&) noexcept;
  IndexWriter& operator=(IndexWriter&&) noexcept;
  IndexWriter(const IndexWriter&) = delete;
  IndexWriter& operator=(const IndexWriter&) = delete;

  /// Stores the coarse mesh under /mesh (at most once; an empty mesh is written at commit
  /// if this is never called).
  /// @throw InputError if called twice, after commit, or if a corner or neighbour index is
  ///        out of range or the neighbour and tet counts differ.
  /// @throw IoError if HDF5 fails to write.
  void write_mesh(const TetMesh& mesh);

  /// Stores a 1-D table as /tables/<name> (e.g. "tet_shard" per tet, "shard_kind" per shard).
  /// @throw InputError if the name is empty, holds '/' or '.', or is already used; or after
  ///        commit.
  /// @throw IoError if HDF5 fails to write.
  void write_table(std::string_view name, std::span<const std::uint8_t> values);
  void write_table(std::string_view name, std::span<const std::uint32_t> values);
  void write_table(std::string_view name, std::span<const std::uint64_t> values);
  void write_table(std::string_view name, std::span<const double> values);

  /// Compresses and writes the shard's chunks now; returns its number (0, 1, 2, ...).
  /// An empty payload is a valid shard of size 0.
  /// @throw InputError after commit, or past 2^32 - 1 shards.
  /// @throw IoError if HDF5 fails to write.
  std::uint32_t append_shard(std::span<const std::byte> payload);
  /// Writes a shard compressed by encode_shard with this writer's options.
  /// @throw InputError if it was encoded for another chunk size, as append_shard otherwise.
  std::uint32_t append_encoded_shard(const EncodedShard& shard);
  const IndexWriterOptions& options() const;

  /// Shards appended so far.
  std::uint32_t shard_count() const;
  /// Bytes of shard chunks written so far, as stored (compressed, with checksums).
  std::uint64_t stored_shard_bytes() const;
  const std::filesystem::path& path() const;
  const std::filesystem::path& temporary_path() const;

  /// Writes the shard extents and the header attributes, closes and flushes the file, and
  /// renames it to path(). Returns the size of the index in bytes.
  /// @throw InputError if called twice, if header.precision is neither "float" nor "double",
  ///        if header.version is not kIndexVersion, or if a non-zero header.shard_count
  ///        differs from shard_count().
  /// @throw IoError if HDF5, fsync or the rename fails (the temporary file is then removed
  ///        by the destructor).
  std::uint64_t commit(const IndexHeader& header);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tetrapage
