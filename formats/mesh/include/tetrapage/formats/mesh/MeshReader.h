#pragma once
/// @file MeshReader.h
/// Reading meshes into a TriangleSoup. OBJ, PLY and OFF go through streaming readers of our
/// own that keep double coordinates; STL and glTF 2.0 (floats by definition) too, a glTF's
/// node transforms composed in double; what our glTF reader does not read (glTF 1.0, an
/// extension changing the geometry, sparse accessors) and the other formats Assimp knows go
/// through Assimp, which Debian builds in single precision.

#include <filesystem>
#include <functional>
#include <span>

#include "tetrapage/formats/base/TriangleSoup.h"
#include "tetrapage/formats/mesh/CadReader.h"

namespace tetrapage {

enum class MeshFormat { obj, stl, ply, off, gltf, glb, step, iges, assimp_other };

/// The format named by a path's extension (case-insensitive).
/// @throw InputError if no reader handles that extension.
MeshFormat mesh_format_from_path(const std::filesystem::path& path);

/// Reads one mesh file. Parts: OBJ objects and groups (`o`, `g`) and the part table our PLY
/// writer adds (MeshWriter.h) are parts, as are glTF mesh nodes and the placed shapes of a
/// STEP or IGES file (tessellated as `tessellation` says: read_cad); anything else is one part
/// named by the file's stem. OBJ: `o NAME` starts an object, `g NAME` a group in it; a face
/// belongs to the part of its group (named by the group, path "object/group", or the group
/// alone outside any object), else of its object (named by it), else to the part named by
/// the file's stem. The same object and group met again continue their part, so a part's
/// triangles need not be consecutive; a part exists from its first face on (a group without
/// faces makes none); a name is the rest of its line, trimmed (`g a b` is one group "a b");
/// `o` or `g` with no name ends the object or the group. Paths are made unique by appending
/// "#2", "#3", ... Triangles keep the file's order: the id of a triangle is its position among
/// the faces' triangles (each face fan-triangulated around its first corner: a face of n
/// corners gives n - 2 consecutive triangles) less the degenerate triangles dropped before it
/// (triangle_position() undoes that).
/// Degenerate triangles (repeated indices, or exactly collinear corners) are
/// dropped and counted in the report; polygons are fan-triangulated. Vertices are kept as the
/// file stores them (STL corners are not merged; unused vertices stay). OBJ faces may only
/// use vertices defined above them (as every OBJ exporter writes them). The report, if
/// given, is reset and filled.
/// @throw IoError if the file cannot be opened or read.
/// @throw FormatError if the file is truncated or malformed (message names the file and the
///        line or element).
/// @throw InputError for NaN/infinite coordinates, indices out of range, or a mesh with no
///        triangle left (message names the file, line or element, and the value).
TriangleSoup read_mesh(const std::filesystem::path& path, ReadReport* report = nullptr,
                       const TessellationOptions& tessellation = {});

/// Where read_mesh_in_chunks sends a file's triangles.
struct SoupChunks {
  std::size_t triangles = 1 << 16;  ///< the most triangles a chunk holds
  /// Each chunk, in file order: vertices (its own), triangles, part_of (the file's part ids).
  std::function<void(TriangleSoup&&)> take;
  /// The most vertices of the file's table held in memory (24 B each); the rest go to an
  /// unlinked temporary file in `vertex_folder` (empty: the system's), read back through a
  /// cache of about vertex_cache_bytes.
  std::uint64_t held_vertices = ~std::uint64_t(0);
  std::filesystem::path vertex_folder;
  std::uint64_t vertex_cache_bytes = std::uint64_t(8) << 20;
  /// Each vertex as it is read, used or not (what a whole read's checks see of the file).
  std::function<void(const Vec3&)> on_vertex;
  /// Fill ReadReport::dropped_positions (8 B a degenerate triangle, held to the end).
  bool keep_dropped_positions = true;
};

/// Reads a mesh file as read_mesh does, handing its kept triangles to `chunks.take` a chunk at a
/// time: the chunks appended in order are read_mesh's soup (the same corners, parts and order;
/// the same report). Returns the parts (part_names, part_paths) and no triangle. OBJ, OFF and
/// PLY hold their vertex table while they are read, an STL a chunk's vertices; a PLY's part
/// table, which follows the faces, is read first in a pass of its own. A glTF holds its JSON's
/// tables and its vertex table, reading each primitive through a block of its buffer. A STEP
/// or IGES file holds its distinct shapes and places its instances a chunk at a time
/// (TessellatedFile).
/// The other formats MeshReadEstimate::chunked does not name are read whole and handed over
/// as one chunk.
/// @throw as read_mesh, and whatever `take` throws.
TriangleSoup read_mesh_in_chunks(const std::filesystem::path& path, ReadReport* report,
                                 const SoupChunks& chunks,
                                 const TessellationOptions& tessellation = {});

/// Reads any file through Assimp (aiProcess_Triangulate), even one of the formats that have a
/// reader of our own: the comparison path for benchmarks and tests. Walks the node hierarchy
/// applying the node transforms; one part per mesh node instance, named by the file stem when
/// there is only one, else "stem/node" ("stem/node#2", ... for repeated node names).
/// Assimp as Debian builds it is single precision.
/// polygons_triangulated stays 0 (Assimp triangulates before we see the faces).
/// @throw IoError if the file cannot be opened; FormatError if Assimp cannot import it
///        (its message is included); InputError as read_mesh.
TriangleSoup read_mesh_with_assimp(const std::filesystem::path& path, ReadReport* report = nullptr);

/// Loads now the libraries that reading `inputs` will load: the CAD module (OpenCASCADE and
/// Assimp) for STEP, IGES and the formats Assimp imports, named directly or inside manifests. A
/// memory reading taken after it counts their pages as the process's own (about 30 MiB), as
/// `fly` and `preprocess` state their promises. Inputs that cannot be listed or have no reader
/// are left to the read that follows, which names what is wrong.
/// @throw IoError when the module is needed and cannot be loaded.
void load_readers_for(std::span<const std::filesystem::path> inputs);

/// What reading a mesh file whole will hold, told before reading it from what is cheap to
/// know: the counts a PLY or OFF header or a binary STL states, else the file's size at the
/// fewest bytes a triangle took in the files measured (an OBJ, an ASCII STL, a file Assimp
/// reads written with fewer digits or fewer vertices shared holds more); a glTF our reader reads
/// is counted from its JSON. STEP and IGES are known once tessellated
/// (TessellatedFile::placed_triangles).
struct MeshReadEstimate {
  std::uint64_t vertices = 0;   ///< the soup's vertex entries (an STL's three a triangle)
  std::uint64_t triangles = 0;  ///< a face a triangle unless the file shows more
  bool counted = false;         ///< from the file's own counts; else from its size
  bool cad = false;             ///< STEP or IGES: no estimate here
  /// The reader's peak heap: its soup and what it holds beside while reading (growing arrays,
  /// the degenerate filter's shrink, Assimp's scene, the read block).
  std::uint64_t reading_bytes = 0;
  /// read_mesh_in_chunks reads the file a chunk at a time, holding chunked_bytes beside the
  /// chunk (the read block) and the vertex table (none for an STL), which may go to disk
  /// (SoupChunks::held_vertices).
  bool chunked = false;
  std::uint64_t chunked_bytes = 0;
  std::uint64_t vertex_table_bytes = 0;
  /// The soup once read: 24 B a vertex, 12 a triangle and 4 for its part.
  std::uint64_t soup_bytes() const { return 24 * vertices + 16 * triangles; }
};

/// Estimates read_mesh's soup and peak for `path`. Never throws: a file whose header cannot be
/// read is estimated from its size, and its reader then says what is wrong.
MeshReadEstimate estimate_mesh_read(const std::filesystem::path& path) noexcept;

/// The position, among the triangles the reader made (the faces in file order, each
/// fan-triangulated), of the kept triangle `id` of the soup read with `report`: `id` plus the
/// dropped triangles at or before that position (report.dropped_positions).
std::uint64_t triangle_position(const ReadReport& report, std::uint64_t id);

/// True when the three corners are exactly collinear (or coincide): an exact predicate.
bool is_degenerate_triangle(const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace tetrapage
