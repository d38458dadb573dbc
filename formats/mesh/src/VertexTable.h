#pragma once
// Internal: the vertex table of a mesh file read in chunks (SoupBuilder), its first vertices in
// memory and the rest, past a limit, in an unlinked temporary file read back through a small
// cache of blocks: faces name vertices anywhere in the table, and a table larger than the
// budget must not be held.

#include <cstdint>
#include <filesystem>
#include <vector>

#include "tetrapage/formats/base/TriangleSoup.h"

namespace tetrapage::detail {

class VertexTable {
 public:
  VertexTable() = default;
  ~VertexTable();
  VertexTable(const VertexTable&) = delete;
  VertexTable& operator=(const VertexTable&) = delete;

  /// Holds at most `held` vertices in memory; the rest go to a file in `folder`, read back
  /// through a cache of about `cache_bytes`. Before the first push_back.
  void limit(std::uint64_t held, const std::filesystem::path& folder, std::uint64_t cache_bytes);
  /// Reserves for `count` vertices (at most those held).
  void reserve(std::uint64_t count);

  std::uint64_t size() const { return size_; }
  /// @throw IoError when the file cannot be made or written (disk full).
  void push_back(const Vec3& p);
  /// Vertex i < size() (a copy: the cache may drop its block on the next call).
  /// @throw IoError when the file cannot be read back.
  Vec3 at(std::uint64_t i);
  /// Forgets every vertex (the limit stays).
  void clear();
  /// Vertices written to the file so far.
  std::uint64_t spilled() const { return size_ - held_.size(); }

 private:
  static constexpr std::uint64_t kBlockVertices = 1024;
  struct Slot {
    std::uint64_t block = ~std::uint64_t(0);
    std::vector<Vec3> vertices;
  };
  void open_file();
  void write_tail();

  std::vector<Vec3> held_;
  std::uint64_t held_limit_ = ~std::uint64_t(0);
  std::uint64_t size_ = 0;
  std::filesystem::path folder_;
  std::uint64_t cache_bytes_ = 0;
  int file_ = -1;
  std::vector<Vec3> tail_;  // the block being filled, not written yet
  std::vector<Slot> cache_;
};

}  // namespace tetrapage::detail
