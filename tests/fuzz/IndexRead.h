#pragma once
// What the index fuzz targets do with a file: everything a reader of an index does, as the
// runtime and `tetrapage validate` do it: open, the mesh, every table, every shard read
// (through HDF5's chunk index, then through the located chunks) and decoded by the runtime's
// Shard::decode with every check, then validate(). Each step must succeed or throw a
// tetrapage::Error.

#include <algorithm>
#include <array>
#include <cstddef>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/index/IndexReader.h"
#include "tetrapage/runtime/paging/Shard.h"

namespace tetrapage::fuzz {

/// Each table through the one typed read that accepts it.
inline void read_tables(const IndexReader& reader) {
  using Read = void (*)(const IndexReader&, const std::string&);
  static constexpr std::array<Read, 4> reads{
      [](const IndexReader& r, const std::string& name) { (void)r.read_table_uint8(name); },
      [](const IndexReader& r, const std::string& name) { (void)r.read_table_uint32(name); },
      [](const IndexReader& r, const std::string& name) { (void)r.read_table_uint64(name); },
      [](const IndexReader& r, const std::string& name) { (void)r.read_table_double(name); }};
  for (const std::string& name : reader.table_names())
    for (const Read read : reads) {
      try {
        read(reader, name);
        break;
      } catch (const FormatError&) {
      }
    }
}

inline void read_and_decode_shards(const IndexReader& reader, std::uint32_t shards) {
  std::vector<std::byte> payload;
  for (std::uint32_t s = 0; s < shards; ++s) {
    try {
      reader.read_shard(s, payload);
      if (payload.size() != reader.shard_size(s)) __builtin_trap();
      (void)Shard::decode(payload, "fuzz shard", DecodeChecks::full);
    } catch (const Error&) {
    }
  }
}

/// `open` makes the reader: from a file, or from bytes in memory (HDF5's core driver).
template <class Open>
inline void read_whole_index(Open open) {
  try {
    const IndexReader reader = open();
    try {
      (void)reader.read_mesh();
    } catch (const Error&) {
    }
    read_tables(reader);
    // A bound on the work per input, not on what the reader accepts.
    const std::uint32_t shards = std::min<std::uint32_t>(reader.shard_count(), 256);
    read_and_decode_shards(reader, shards);
    if (shards > 0) {
      try {
        (void)reader.shard_chunks(0);  // locates every chunk: page-ins then pread() them
        (void)reader.stored_shard_size(0);
      } catch (const Error&) {
      }
      read_and_decode_shards(reader, shards);
    }
    (void)reader.validate();
  } catch (const Error&) {
  }
}

/// The reader over an index held in memory: no file is written per input.
inline void read_whole_index(const std::uint8_t* data, std::size_t size) {
  read_whole_index([&] {
    return IndexReader(std::span<const std::byte>(reinterpret_cast<const std::byte*>(data), size),
                       "fuzz input");
  });
}

}  // namespace tetrapage::fuzz
