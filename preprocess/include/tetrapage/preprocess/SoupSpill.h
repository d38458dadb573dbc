#pragma once
/// @file SoupSpill.h
/// The ingested triangles, in input order, held as the soups they came in: shared vertices,
/// three indices and a part per triangle, about 30 bytes a triangle where a record with its
/// corners is 88. In memory, or spilled to a temporary file when the budget says so (removed
/// when the spill is destroyed, also on errors). The later passes read them back as records.

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/preprocess/SpillFile.h"

namespace tetrapage {

/// Record: trivially copyable, with `triangle` (three corners), `id` and `part` members.
template <class Record>
class SoupSpill {
  static_assert(std::is_trivially_copyable_v<Record>);

 public:
  bool spilled() const { return bool(file_); }
  /// Triangles appended.
  std::uint64_t size() const { return count_; }
  /// Bytes held in memory.
  std::uint64_t held_bytes() const { return held_bytes_; }

  /// Appends a soup's triangles; the first gets id size(), its part p becomes part_offset + p.
  /// @throw IoError when a write fails (disk full).
  void append(const TriangleSoup& soup, std::uint32_t part_offset) {
    if (soup.triangle_count() == 0) return;
    Piece piece;
    piece.first_id = count_;
    piece.part_offset = part_offset;
    piece.vertices = soup.vertices;
    piece.triangles = soup.triangles;
    piece.part_of = soup.part_of;
    count_ += soup.triangle_count();
    if (file_) {
      write(piece);
      return;
    }
    held_bytes_ += piece.bytes();
    pieces_.push_back(std::move(piece));
  }

  /// Appends a soup's triangles as append() does, taking its arrays rather than copying them:
  /// a file's soup is never held twice, and a spilling model writes it out and frees it.
  void append(TriangleSoup&& soup, std::uint32_t part_offset) {
    if (soup.triangle_count() == 0) return;
    Piece piece;
    piece.first_id = count_;
    piece.part_offset = part_offset;
    piece.vertices = std::move(soup.vertices);
    piece.triangles = std::move(soup.triangles);
    piece.part_of = std::move(soup.part_of);
    count_ += piece.triangles.size();
    if (file_) {
      write(piece);
      return;
    }
    held_bytes_ += piece.bytes();
    pieces_.push_back(std::move(piece));
  }

  /// The bytes a soup takes once appended.
  static std::uint64_t soup_bytes(const TriangleSoup& soup) {
    return soup.vertices.size() * sizeof(Vec3) + soup.triangles.size() * sizeof(TriangleIndices) +
           soup.part_of.size() * sizeof(std::uint32_t);
  }

  /// The soups held in memory (none once spilled()), one piece per append, in input order:
  /// piece p holds piece_size(p) records of consecutive ids.
  std::size_t piece_count() const { return pieces_.size(); }
  std::size_t piece_size(std::size_t p) const { return pieces_[p].triangles.size(); }
  /// The part of record t of piece p (its `part`), without the rest of the record.
  std::uint32_t piece_part(std::size_t p, std::size_t t) const { return part_of(pieces_[p], t); }
  /// Record t of piece p (t < piece_size(p)), its `tet` zero: only while not spilled().
  Record piece_record(std::size_t p, std::size_t t) const { return record_of(pieces_[p], t); }

  /// The triangles and parts of the records `ids` (ascending, each < size()), appended to
  /// `triangles` and `parts`: only while not spilled(). The ids of a shard lie all over the
  /// input, so each record is a few cache misses; they are resolved in passes that start the
  /// next loads early (one record at a time was a tenth of the shard stage, waiting on memory).
  template <class TriangleOut>
  void gather(std::span<const std::uint64_t> ids, std::vector<TriangleOut>& triangles,
              std::vector<std::uint32_t>& parts) const {
    struct Where {
      const Piece* piece;
      std::size_t t;
    };
    thread_local std::vector<Where> where;
    thread_local std::vector<TriangleIndices> corners;
    where.resize(ids.size());
    corners.resize(ids.size());
    auto piece_it = pieces_.begin();
    for (std::size_t i = 0; i < ids.size(); ++i) {
      const std::uint64_t id = ids[i];
      if (piece_it == pieces_.end() || id < piece_it->first_id ||
          id - piece_it->first_id >= piece_it->triangles.size())
        piece_it = std::upper_bound(pieces_.begin(), pieces_.end(), id,
                                    [](std::uint64_t v, const Piece& p) { return v < p.first_id; }) -
                   1;
      where[i] = {&*piece_it, std::size_t(id - piece_it->first_id)};
      __builtin_prefetch(&piece_it->triangles[where[i].t]);
    }
    for (std::size_t i = 0; i < ids.size(); ++i) {
      corners[i] = where[i].piece->triangles[where[i].t];
      __builtin_prefetch(&where[i].piece->vertices[corners[i][0]]);
    }
    for (std::size_t i = 0; i < ids.size(); ++i) {
      const Piece& piece = *where[i].piece;
      const auto& c = corners[i];
      triangles.push_back({piece.vertices[c[0]], piece.vertices[c[1]], piece.vertices[c[2]]});
      parts.push_back(part_of(piece, where[i].t));
    }
  }

  /// Moves what is held in memory to `file` and spills from now on.
  /// @throw IoError when the file cannot be created or written.
  void spill_to(std::filesystem::path file) {
    if (file_) return;
    file_ = SpillFile(std::move(file));
    for (const Piece& piece : pieces_) write(piece);
    std::vector<Piece>().swap(pieces_);
    held_bytes_ = 0;
  }

  /// Calls visit(std::span<const Record>) on consecutive blocks of at most block_records, in
  /// input order (each record's `tet`, or any other member, is zero).
  /// @throw IoError when the file cannot be read back.
  template <class Visit>
  void for_each_block(std::size_t block_records, Visit&& visit) {
    if (block_records == 0) block_records = 1;
    std::vector<Record> block;
    auto emit = [&](const Piece& piece) {
      const std::size_t n = piece.triangles.size();
      for (std::size_t first = 0; first < n; first += block_records) {
        const std::size_t count = std::min(block_records, n - first);
        block.resize(count);
        for (std::size_t i = 0; i < count; ++i) block[i] = record_of(piece, first + i);
        visit(std::span<const Record>(block));
      }
    };
    if (!file_) {
      for (const Piece& piece : pieces_) emit(piece);
      return;
    }
    file_.rewind();
    Piece piece;
    for (std::uint64_t read = 0; read < count_; read += piece.triangles.size()) {
      read_piece(piece);
      emit(piece);
    }
    file_.seek_end();
  }

  /// Calls visit(TriangleSoup&&, std::uint32_t part_offset) on each soup appended, in order,
  /// as append() took it (vertices, triangles, part_of; no part names).
  /// @throw IoError when the file cannot be read back.
  template <class Visit>
  void for_each_soup(Visit&& visit) {
    const auto emit = [&](Piece&& piece) {
      TriangleSoup soup;
      soup.vertices = std::move(piece.vertices);
      soup.triangles = std::move(piece.triangles);
      soup.part_of = std::move(piece.part_of);
      visit(std::move(soup), piece.part_offset);
    };
    if (!file_) {
      for (const Piece& piece : pieces_) emit(Piece(piece));
      return;
    }
    file_.rewind();
    for (std::uint64_t read = 0; read < count_;) {
      Piece piece;
      read_piece(piece);
      read += piece.triangles.size();
      emit(std::move(piece));
    }
    file_.seek_end();
  }

  /// Frees the triangles and removes the file.
  void clear() {
    file_ = SpillFile();
    std::vector<Piece>().swap(pieces_);
    count_ = 0;
    held_bytes_ = 0;
  }

 private:
  struct Piece {
    std::uint64_t first_id = 0;
    std::uint32_t part_offset = 0;
    std::vector<Vec3> vertices;
    std::vector<TriangleIndices> triangles;
    std::vector<std::uint32_t> part_of;  ///< empty: every triangle is the soup's part 0
    std::uint64_t bytes() const {
      return vertices.size() * sizeof(Vec3) + triangles.size() * sizeof(TriangleIndices) +
             part_of.size() * sizeof(std::uint32_t);
    }
  };
  static std::uint32_t part_of(const Piece& piece, std::size_t t) {
    return piece.part_offset + (piece.part_of.empty() ? 0 : piece.part_of[t]);
  }
  // Record t of a piece, its `tet` (and anything else) zero.
  static Record record_of(const Piece& piece, std::size_t t) {
    const auto& corners = piece.triangles[t];
    Record record{};
    record.triangle = {piece.vertices[corners[0]], piece.vertices[corners[1]], piece.vertices[corners[2]]};
    record.id = piece.first_id + t;
    record.part = part_of(piece, t);
    return record;
  }
  struct Header {
    std::uint64_t first_id, vertices, triangles, parts;
    std::uint32_t part_offset, unused;
  };

  template <class T>
  void write_array(const std::vector<T>& values) {
    file_.write(values.data(), sizeof(T), values.size());
  }
  void write(const Piece& piece) {
    const Header header{piece.first_id, piece.vertices.size(), piece.triangles.size(),
                        piece.part_of.size(), piece.part_offset, 0};
    file_.write(&header, sizeof header, 1);
    write_array(piece.vertices);
    write_array(piece.triangles);
    write_array(piece.part_of);
  }
  template <class T>
  void read_array(std::vector<T>& values, std::uint64_t count) {
    values.resize(count);
    file_.read(values.data(), sizeof(T), count);
  }
  void read_piece(Piece& piece) {
    Header header{};
    file_.read(&header, sizeof header, 1);
    piece.first_id = header.first_id;
    piece.part_offset = header.part_offset;
    read_array(piece.vertices, header.vertices);
    read_array(piece.triangles, header.triangles);
    read_array(piece.part_of, header.parts);
    for (const auto& corners : piece.triangles)
      for (const std::uint32_t v : corners)
        if (v >= piece.vertices.size()) file_.damaged();
  }

  SpillFile file_;
  std::vector<Piece> pieces_;
  std::uint64_t count_ = 0;
  std::uint64_t held_bytes_ = 0;
};

}  // namespace tetrapage
