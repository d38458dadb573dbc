#pragma once
// Internal: what every mesh reader shares: the soup under construction (with the degenerate
// filter), error messages that name the file and the line or element, and the readers.

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "InputFile.h"
#include "VertexTable.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/TextNumbers.h"
#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/formats/mesh/MeshReader.h"

namespace tetrapage::detail {

/// "file: line 12: " for text formats.
inline std::string where_line(const InputFile& file) {
  return file.name() + ": line " + std::to_string(file.line_number()) + ": ";
}
/// "file: vertex 12: " for binary formats (0-based element index, as the file stores them).
inline std::string where_element(const InputFile& file, std::string_view element,
                                 std::uint64_t index) {
  return file.name() + ": " + std::string(element) + " " + std::to_string(index) + ": ";
}

inline std::string number_text(double value) {
  std::string text;
  append_double(text, value);
  return text;
}

/// @throw InputError naming the place and the coordinate: NaN or infinite values are not data.
[[noreturn]] inline void throw_not_finite(const std::string& where, const Vec3& p) {
  throw InputError(where + "coordinate is not finite (" + number_text(p[0]) + ", " +
                   number_text(p[1]) + ", " + number_text(p[2]) + ")");
}
inline bool is_finite(const Vec3& p) {
  return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

/// Builds the soup of one file: vertices, triangles (global indices), parts. finish() drops
/// the degenerate triangles and counts them in the report.
class SoupBuilder {
 public:
  /// With `chunks`, the kept triangles go to chunks->take a chunk at a time (finish() then
  /// returns the parts alone): the builder holds the vertex table and one chunk.
  SoupBuilder(std::string file_name, ReadReport& report, const SoupChunks* chunks = nullptr)
      : file_name_(std::move(file_name)), report_(report), chunks_(chunks) {
    if (chunks_ != nullptr)
      table_.limit(chunks_->held_vertices, chunks_->vertex_folder, chunks_->vertex_cache_bytes);
  }

  /// No later triangle uses a vertex added before it (an STL): a chunk's vertices are let go
  /// with it.
  void vertices_unshared() { vertices_unshared_ = true; }

  /// Starts a part; later triangles go to it. An empty path is the name. A path already
  /// used gets "#2", "#3", ... appended (a soup's paths are unique). Returns the part's id.
  std::uint32_t begin_part(std::string name, std::string path = {}) {
    if (path.empty()) path = name;
    if (!used_paths_.insert(path).second) {
      // Each path's next suffix is kept: n parts of one name take linear time, not quadratic.
      std::uint64_t& k = next_suffix_.try_emplace(path, 2).first->second;
      const std::string taken = path + '#';
      while (!used_paths_.insert(taken + std::to_string(k)).second) ++k;
      path = taken + std::to_string(k++);
    }
    if (path == name) path.clear();  // keeps part_paths empty while every path is the name
    part_ = soup_.add_part(std::move(name), std::move(path));
    return part_;
  }
  /// Sends later triangles to an earlier part again (parts need not be consecutive).
  void resume_part(std::uint32_t part) { part_ = part; }
  /// Gives the triangles added [first, end) (counted before finish() drops any) to a part.
  void assign_part(std::uint64_t first, std::uint64_t end, std::uint32_t part) {
    std::fill(soup_.part_of.begin() + static_cast<std::ptrdiff_t>(first),
              soup_.part_of.begin() + static_cast<std::ptrdiff_t>(end), part);
  }
  /// Reserves for the counts a header announces. A header may lie: no format stores a vertex
  /// in fewer than 3 bytes or a face in fewer than 4, so the file size caps the reservation.
  void reserve(std::uint64_t vertices, std::uint64_t triangles, std::uint64_t file_bytes) {
    if (chunks_ != nullptr) {
      if (!vertices_unshared_) table_.reserve(std::min(vertices, file_bytes / 3));
      vertices = 0;
      triangles = std::min<std::uint64_t>(triangles, chunks_->triangles);
    }
    soup_.vertices.reserve(static_cast<std::size_t>(std::min(vertices, file_bytes / 3)));
    const auto faces = static_cast<std::size_t>(std::min(triangles, file_bytes / 4));
    soup_.triangles.reserve(faces);
    soup_.part_of.reserve(faces);
  }

  std::uint64_t vertex_count() const {
    return chunks_ != nullptr ? vertex_base_ + table_.size() : soup_.vertices.size();
  }
  void add_vertex(const Vec3& p) {
    if (chunks_ != nullptr) {
      if (chunks_->on_vertex) chunks_->on_vertex(p);
      table_.push_back(p);
    } else {
      soup_.vertices.push_back(p);
    }
  }

  /// Indices are global (into every vertex added so far) and already range-checked.
  void add_triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    soup_.triangles.push_back({a, b, c});
    soup_.part_of.push_back(part_);
    ++report_.triangles_read;
    // An unshared table (an STL's) is let go with a chunk: not between a facet's triangles.
    if (chunks_ != nullptr && soup_.triangles.size() >= chunks_->triangles &&
        !(vertices_unshared_ && in_polygon_))
      hand_over_chunk();
  }
  /// A face of any size, fan-triangulated around its first corner (fewer than 3 corners: the
  /// caller rejects it first).
  void add_polygon(std::span<const std::uint32_t> corners) {
    if (corners.size() > 3) ++report_.polygons_triangulated;
    in_polygon_ = true;
    for (std::size_t i = 1; i + 1 < corners.size(); ++i)
      add_triangle(corners[0], corners[i], corners[i + 1]);
    in_polygon_ = false;
    if (chunks_ != nullptr && vertices_unshared_ && soup_.triangles.size() >= chunks_->triangles)
      hand_over_chunk();
  }

  /// Drops degenerate triangles and returns the soup (in chunks: the last chunk handed over,
  /// the parts alone).
  /// @throw InputError if no triangle is left.
  TriangleSoup finish();

 private:
  // Vertex v (a global index) of the vertices added.
  Vec3 vertex(std::uint32_t v) {
    return chunks_ != nullptr ? table_.at(v - vertex_base_) : soup_.vertices[v];
  }
  // True (and counted in the report) when triangle `t` of the soup, the file's triangle at
  // `position`, repeats a corner or has collinear corners.
  bool drop_if_degenerate(std::size_t t, std::uint64_t position);
  // The kept triangles added since the last chunk, with the vertices they use, to chunks_.
  void hand_over_chunk();
  [[noreturn]] void throw_no_triangle_left() const;

  std::string file_name_;
  ReadReport& report_;
  const SoupChunks* chunks_ = nullptr;
  TriangleSoup soup_;
  std::uint32_t part_ = 0;
  std::set<std::string> used_paths_;
  std::map<std::string, std::uint64_t> next_suffix_;  // a repeated path's next "#k"
  bool vertices_unshared_ = false;
  bool in_polygon_ = false;
  std::uint64_t vertex_base_ = 0;        // vertices let go with earlier chunks
  std::uint64_t triangles_before_ = 0;   // the file's triangles handed over (or dropped) before
  std::uint64_t kept_before_ = 0;        // triangles kept in chunks handed over
  VertexTable table_;                    // in chunks: the vertices (soup_ holds none)
  // In chunks: the file's vertex -> the chunk's, for the chunk being made.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> chunk_map_;
};

/// Hands a soup read whole to `chunks` as one chunk; returns its parts alone.
inline TriangleSoup hand_over_whole(TriangleSoup&& whole, const SoupChunks& chunks) {
  TriangleSoup parts;
  parts.part_names = std::move(whole.part_names);
  parts.part_paths = std::move(whole.part_paths);
  chunks.take(std::move(whole));
  return parts;
}

/// Whitespace-separated tokens of a text file, with the line they came from; a token never
/// spans lines. `comment` (if not '\0') starts a comment that runs to the end of the line.
class TokenReader {
 public:
  explicit TokenReader(InputFile& file, char comment = '\0') : file_(file), comment_(comment) {}

  /// The next token; empty at the end of the file.
  std::string_view next() {
    for (;;) {
      const std::string_view token = next_token(rest_);
      if (!token.empty() && token.front() != comment_) return token;
      if (!file_.next_line(rest_)) return {};
    }
  }
  /// The next token, which must be there. @throw FormatError naming `what` at the end of file.
  std::string_view expect(std::string_view what) {
    const std::string_view token = next();
    if (token.empty()) {
      throw FormatError(where_line(file_) + "the file ends where " + std::string(what) +
                        " was expected");
    }
    return token;
  }
  /// Drops what is left of the current line.
  void skip_line() { rest_ = {}; }
  /// Bytes not tokenised yet: the rest of the current line and what the file has left.
  std::uint64_t bytes_left() const { return rest_.size() + file_.bytes_left(); }
  const InputFile& file() const { return file_; }

 private:
  InputFile& file_;
  char comment_;
  std::string_view rest_;
};

/// Little- or big-endian scalar at `bytes` (no alignment needed).
template <class T>
T load_scalar(const char* bytes, bool big_endian) {
  unsigned char raw[sizeof(T)];
  std::memcpy(raw, bytes, sizeof(T));
  if (big_endian != (std::endian::native == std::endian::big)) std::reverse(raw, raw + sizeof(T));
  T value;
  std::memcpy(&value, raw, sizeof(T));
  return value;
}

/// Largest vertex count a soup can index.
constexpr std::uint64_t max_vertices = std::numeric_limits<std::uint32_t>::max();

/// The counts a header states, read before any allocation (a face a triangle unless the file
/// shows more: a binary PLY's face bytes bound its corners).
struct MeshCounts {
  std::uint64_t vertices = 0, faces = 0, triangles = 0;
};
/// @throw FormatError, InputError as read_ply and read_off do for the same header.
MeshCounts read_ply_counts(InputFile& file);
/// The triangle count of a binary STL (the file's size is 84 + 50 per triangle), or none for an
/// ASCII or damaged one.
std::optional<std::uint64_t> binary_stl_count(InputFile& file);
MeshCounts read_off_counts(InputFile& file);

/// The readers of our own: with `chunks`, the triangles go there (SoupBuilder).
TriangleSoup read_obj(InputFile& file, ReadReport& report, const SoupChunks* chunks = nullptr);
TriangleSoup read_stl(InputFile& file, ReadReport& report, const SoupChunks* chunks = nullptr);
TriangleSoup read_ply(InputFile& file, ReadReport& report, const SoupChunks* chunks = nullptr);
TriangleSoup read_off(InputFile& file, ReadReport& report, const SoupChunks* chunks = nullptr);
/// Any format Assimp knows; one part per mesh node instance.
TriangleSoup read_assimp(const std::filesystem::path& path, ReadReport& report);
/// A glTF 2.0 file (.gltf, .glb) read by our own reader (GltfReader.cpp), or nothing when
/// Assimp reads it (GltfDocument::needs_assimp: glTF 1.0, Draco, sparse accessors, ...).
std::optional<TriangleSoup> read_gltf(const std::filesystem::path& path, ReadReport& report,
                                      const SoupChunks* chunks);

}  // namespace tetrapage::detail
