#pragma once
/// @file MeshWriter.h
/// Streaming mesh output: parts are appended one at a time so that a generator never holds
/// a whole large model in memory. The file is written under a temporary name and renamed
/// only by commit(), so a failed or interrupted run leaves no file under the output name.
///
/// Formats, by extension:
/// - .obj: `v` lines then `f` lines per part (global 1-based indices), streamed.
/// - .stl: binary, float coordinates, normals computed from the corners; the triangle count
///   is patched at commit().
/// - .ply: binary little-endian, double x/y/z, `list uchar uint vertex_indices`.
/// - .off: ASCII.
///   PLY and OFF need the counts in their header: vertices and faces stream into two side
///   files (`<path>.vertices.tmp`, `<path>.faces.tmp`) that commit() appends behind it.
/// - .gltf (buffer embedded as a base64 data URI) and .glb: one mesh and one node per part,
///   float positions, uint32 indices. These are held in memory until commit(): meant for small
///   files (objects, examples), not for multi-million-triangle models. Parts without a
///   triangle are left out (glTF accessors cannot be empty).
/// - .json: an assembly manifest (formats/Manifest.h); each part goes to its own binary PLY in
///   "<stem>.parts/" next to it (written to "<stem>.parts.tmp" and renamed at commit), so
///   that preprocess reads one part at a time, whatever the size of the assembly.
/// Text numbers are the shortest form that reads back as the same double, so OBJ, PLY and
/// OFF keep coordinates bit for bit; STL, glTF and GLB round them to float. The same input
/// always gives the same bytes.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>

#include "tetrapage/formats/TriangleSoup.h"

namespace tetrapage {

class MeshWriter {
 public:
  /// Opens a temporary file next to `path` (`<path>.tmp`); the format is chosen by the
  /// extension (.obj, .stl (binary), .ply (binary little-endian, double), .off, .gltf, .glb).
  /// @throw InputError for an extension that cannot be written.
  /// @throw IoError if the temporary file cannot be created.
  explicit MeshWriter(const std::filesystem::path& path);
  /// Removes the temporary files unless commit() succeeded.
  ~MeshWriter();
  MeshWriter(const MeshWriter&) = delete;
  MeshWriter& operator=(const MeshWriter&) = delete;

  /// Appends a part: its vertices and triangles (indices local to `vertices`).
  /// @throw InputError for a non-finite vertex, an index out of range, or more than the
  ///        format can hold (2^32-1 triangles in STL, 2^32-1 vertices in PLY, 4 GiB of GLB).
  /// @throw IoError on a write failure (disk full, ...), naming the output file.
  void add_part(std::span<const Vec3> vertices, std::span<const TriangleIndices> triangles);

  /// Finishes the file (headers, counts) and renames it to the output name. A second call
  /// does nothing.
  /// @throw IoError on failure; the output name is then left untouched.
  void commit();

  /// Totals of what add_part() received.
  std::uint64_t triangles_written() const;
  std::uint64_t vertices_written() const;

  class Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

/// True when MeshWriter handles the path's extension (so a command can refuse an output name
/// before it spends time reading its input).
bool can_write_mesh(const std::filesystem::path& path);

/// Writes a whole soup and commits. A soup of one part (or none) is written as one add_part
/// call, vertices and triangles exactly as they are (unused vertices included). A soup of
/// several parts is written with one add_part per part, each with the vertices its triangles
/// use, in first-use order (so parts become glTF nodes).
/// @throw InputError for inconsistent soups (indices or part ids out of range) and as
///        MeshWriter; IoError as MeshWriter.
void write_mesh(const std::filesystem::path& path, const TriangleSoup& soup);

}  // namespace tetrapage
