#pragma once
/// @file MeshReader.h
/// Reading meshes into a TriangleSoup. OBJ, PLY and OFF go through streaming readers of our
/// own that keep double coordinates; STL (float by definition) too; glTF/GLB and the other
/// formats Assimp knows go through Assimp, which Debian builds in single precision.

#include <filesystem>

#include "tetrapage/formats/CadReader.h"
#include "tetrapage/formats/TriangleSoup.h"

namespace tetrapage {

enum class MeshFormat { obj, stl, ply, off, gltf, glb, step, iges, assimp_other };

/// The format named by a path's extension (case-insensitive).
/// @throw InputError if no reader handles that extension.
MeshFormat mesh_format_from_path(const std::filesystem::path& path);

/// Reads one mesh file as one part (named by the file's stem; a glTF file gives one part per
/// mesh node; a STEP or IGES file one per placed shape, tessellated as `tessellation` says:
/// read_cad). Degenerate triangles (repeated indices, or exactly collinear corners) are
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

/// Reads any file through Assimp (aiProcess_Triangulate), even one of the formats that have a
/// reader of our own: the comparison path for benchmarks and tests. Walks the node hierarchy
/// applying the node transforms; one part per mesh node instance, named by the file stem when
/// there is only one, else "stem/node" ("stem/node#2", ... for repeated node names).
/// Assimp as Debian builds it is single precision.
/// polygons_triangulated stays 0 (Assimp triangulates before we see the faces).
/// @throw IoError if the file cannot be opened; FormatError if Assimp cannot import it
///        (its message is included); InputError as read_mesh.
TriangleSoup read_mesh_with_assimp(const std::filesystem::path& path, ReadReport* report = nullptr);

/// True when the three corners are exactly collinear (or coincide): an exact predicate.
bool is_degenerate_triangle(const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace tetrapage
