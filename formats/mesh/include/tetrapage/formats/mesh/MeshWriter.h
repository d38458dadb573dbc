#pragma once
/// @file MeshWriter.h
/// Streaming mesh output: parts are appended one at a time so that a generator never holds
/// a whole large model in memory. The file is written under a temporary name and renamed
/// only by commit(), so a failed or interrupted run leaves no file under the output name.
///
/// Parts carry a name and an instance path (TriangleSoup's part_names and part_paths). An
/// unnamed part is called "part<k>" (k: the number of parts before it), except the first,
/// which a reader then names by the file's stem. Parts survive in OBJ, PLY, glTF and
/// manifests (read_mesh gives them back); STL and OFF hold none (mesh_format_keeps_parts).
///
/// Formats, by extension:
/// - .obj: per part `o` and `g` lines (below), then its `v` lines and `f` lines (global
///   1-based indices), streamed. A part whose path is its name: `o NAME`; path "OBJECT/NAME":
///   `o OBJECT` and `g NAME`; any other path: `o PATH` and `g NAME` (read back as path
///   "PATH/NAME"). An unnamed first part has no line. A part without triangles leaves no part
///   for a reader.
/// - .stl: binary, float coordinates, normals computed from the corners; the triangle count
///   is patched at commit(). No parts.
/// - .ply: binary little-endian, double x/y/z, `list uchar uint vertex_indices`. Unless the
///   file is one unnamed part, an element `part` after `face` lists per part `uint faces`
///   (its faces, consecutive in `face`), `list uint uchar name` and `list uint uchar path`
///   (empty: the name); other PLY readers skip it (Assimp 5.2 fails on an element before
///   `face`, hence after).
/// - .off: ASCII. No parts.
///   PLY and OFF need the counts in their header: vertices and faces stream into two side
///   files (`<path>.vertices.tmp`, `<path>.faces.tmp`) that commit() appends behind it.
/// - .gltf (buffer embedded as a base64 data URI) and .glb: one mesh and one node per part
///   (named by the part; Assimp reads it back as "<stem>/<name>"), a primitive per
///   add_part/extend_part call, float positions, uint32 indices. These are held in memory
///   until commit(): meant for small files (objects, examples), not for multi-million-triangle
///   models. Parts without a triangle are left out (glTF accessors cannot be empty).
/// - .json: an assembly manifest (formats/Manifest.h); each part goes to its own binary PLY in
///   "<stem>.parts/" next to it (written to "<stem>.parts.tmp-PID" and renamed at commit), so
///   that preprocess reads one part at a time, whatever the size of the assembly; the
///   manifest names it by its path (unique), "#2", "#3", ... appended where one repeats.
/// Text numbers are the shortest form that reads back as the same double, so OBJ, PLY and
/// OFF keep coordinates bit for bit; STL, glTF and GLB round them to float. The same input
/// always gives the same bytes.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "tetrapage/formats/base/TriangleSoup.h"

namespace tetrapage {

class MeshWriter {
 public:
  /// Opens a temporary file next to `path` (`<path>.tmp`); the format is chosen by the
  /// extension (.obj, .stl (binary), .ply (binary little-endian, double), .off, .gltf, .glb).
  /// `length_unit` (a name metres_per_unit knows) is the unit of the coordinates: a manifest
  /// states it as its "units" (empty: "m"); the other formats hold no unit.
  /// @throw InputError for an extension that cannot be written, an unknown unit, or a
  ///        manifest whose part folder holds files other than part files.
  /// @throw IoError if the temporary file cannot be created.
  explicit MeshWriter(const std::filesystem::path& path, std::string length_unit = {});
  /// Removes the temporary files unless commit() succeeded.
  ~MeshWriter();
  MeshWriter(const MeshWriter&) = delete;
  MeshWriter& operator=(const MeshWriter&) = delete;

  /// Appends a part: its vertices and triangles (indices local to `vertices`), what the file
  /// calls it and its instance path (empty: the name).
  /// @throw InputError for a non-finite vertex, an index out of range, or more than the
  ///        format can hold (2^32-1 triangles in STL or in one PLY part, 2^32-1 vertices in
  ///        PLY, 4 GiB of GLB).
  /// @throw IoError on a write failure (disk full, ...), naming the output file.
  void add_part(std::span<const Vec3> vertices, std::span<const TriangleIndices> triangles,
                std::string_view name = {}, std::string_view path = {});
  /// Appends triangles to the part added last (a part streamed in pieces), with their own
  /// vertices (indices local to `vertices`).
  /// @throw InputError before any add_part, and as add_part; IoError as add_part.
  void extend_part(std::span<const Vec3> vertices, std::span<const TriangleIndices> triangles);

  /// Finishes the file (headers, counts) and renames it to the output name. A second call
  /// does nothing.
  /// @throw IoError on failure; the output name is then left untouched.
  void commit();

  /// Totals of what add_part() received.
  std::uint64_t triangles_written() const;
  std::uint64_t vertices_written() const;
  /// The add_part calls.
  std::uint64_t parts_written() const;

  class Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

/// True when MeshWriter handles the path's extension (so a command can refuse an output name
/// before it spends time reading its input).
bool can_write_mesh(const std::filesystem::path& path);

/// True when the format of the path's extension holds parts (OBJ, PLY, glTF, GLB, manifests);
/// STL and OFF merge them into one.
bool mesh_format_keeps_parts(const std::filesystem::path& path);

/// Writes a whole soup and commits, parts with their names and paths. A soup of one part (or
/// none) is written as one add_part call, vertices and triangles exactly as they are (unused
/// vertices included). A soup of several parts is written with one add_part per part, each
/// with the vertices its triangles use, in first-use order; triangles go part by part, in
/// their order within a part, so they keep their ids when each part's triangles are
/// consecutive in the soup (an OBJ file that returns to an earlier group is the exception).
/// @throw InputError for inconsistent soups (indices or part ids out of range) and as
///        MeshWriter; IoError as MeshWriter.
void write_mesh(const std::filesystem::path& path, const TriangleSoup& soup,
                std::string length_unit = {});

}  // namespace tetrapage
