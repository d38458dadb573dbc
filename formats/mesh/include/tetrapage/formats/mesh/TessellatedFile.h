#pragma once
/// @file TessellatedFile.h
/// A STEP or IGES file read and tessellated, its distinct shapes held once and its instances
/// placed on demand: into one soup (read_cad), or a chunk at a time (read_mesh_in_chunks), so
/// that an assembly whose placed triangles exceed the memory at hand is never held placed.

#include <cstdint>
#include <filesystem>
#include <memory>

#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/formats/mesh/CadReader.h"
#include "tetrapage/formats/mesh/MeshReader.h"

namespace tetrapage {

class TessellatedFile {
 public:
  /// Checks, pre-scans, reads and tessellates `path` as read_cad does (OCCT in a child process
  /// unless options.isolate is false). `report` is reset and given the file's figures (path,
  /// format, bytes, unit); each placing adds its triangles to the report it is given.
  /// @throw as read_cad; InputError when the placed triangles exceed options.max_triangles.
  TessellatedFile(const std::filesystem::path& path, const TessellationOptions& options,
                  ReadReport& report);
  ~TessellatedFile();
  TessellatedFile(TessellatedFile&&) noexcept;
  TessellatedFile& operator=(TessellatedFile&&) noexcept;

  /// Of every instance placed, before degenerate triangles are dropped.
  std::uint64_t placed_vertices() const;
  std::uint64_t placed_triangles() const;
  /// What the distinct shapes hold in memory (their vertices, triangles and names).
  std::uint64_t held_bytes() const;
  /// The vertices of the largest shape: what placing one instance holds beside the shapes.
  std::uint64_t largest_shape_vertices() const;

  /// Every instance placed into one soup: read_cad's soup.
  /// @throw InputError for a shape that failed to tessellate (unless options.skip_bad_parts),
  ///        more vertices than a soup indexes, or no triangle.
  TriangleSoup place(ReadReport& report) const;
  /// Every instance placed, handed to `chunks.take` a chunk at a time (SoupChunks' contract:
  /// the chunks appended in order are place()'s soup, every placed vertex given to on_vertex);
  /// holds one instance's placed vertices (and 12 B a vertex to number them in a chunk) beside
  /// a chunk. Returns the parts and no triangle.
  /// @throw as place (a chunk has its own vertices: no limit on the placed vertices), and
  ///        whatever `take` throws.
  TriangleSoup place_in_chunks(const SoupChunks& chunks, ReadReport& report) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tetrapage
