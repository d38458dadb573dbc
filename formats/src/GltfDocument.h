#pragma once
// Internal: a glTF 2.0 file's scene as our reader needs it: the buffers (a GLB's BIN chunk, an
// external file, a data URI), the views and accessors its triangle primitives use, and every
// mesh node placed by its composed transform. Parsed from the JSON once, which is then let go,
// so that reading holds these tables and not the document.

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace tetrapage::detail {

/// Row-major 4x4, applied to column vectors (glTF's column-major matrices transposed).
using Transform = std::array<double, 16>;

struct GltfBuffer {
  std::uint64_t length = 0;       ///< byteLength
  std::filesystem::path file;     ///< empty: `bytes` (a data URI)
  std::uint64_t file_offset = 0;  ///< where the buffer starts in `file` (a GLB's BIN chunk)
  std::vector<char> bytes;
};

struct GltfView {
  std::uint64_t buffer = 0, offset = 0, length = 0, stride = 0;  ///< stride 0: tightly packed
};

struct GltfAccessor {
  std::uint64_t view = 0, offset = 0, count = 0;
  std::uint32_t component_type = 0;  ///< 5121 ubyte, 5123 ushort, 5125 uint, 5126 float, ...
  std::string type;                  ///< "SCALAR", "VEC3", ...
};

struct GltfPrimitive {
  std::uint32_t mode = 4;       ///< 4 triangles, 5 strip, 6 fan (others hold no triangle)
  std::uint64_t positions = 0;  ///< accessor
  std::optional<std::uint64_t> indices;
};

/// One node with a mesh, as placed in the scene: its mesh's triangle primitives.
struct GltfInstance {
  std::string name;  ///< the part's name: "stem" alone, else "stem/node"
  Transform transform{};
  std::vector<GltfPrimitive> primitives;
};

struct GltfDocument {
  bool binary = false;
  /// Set when Assimp reads the file instead (glTF 1.0, an extension that changes the geometry,
  /// a sparse accessor or one without a view): what our reader does not read.
  std::string needs_assimp;
  std::uint64_t json_bytes = 0;
  std::vector<GltfBuffer> buffers;
  std::vector<GltfView> views;
  std::vector<GltfAccessor> accessors;
  std::vector<GltfInstance> instances;  ///< depth first, in the file's order
};

/// Parses the JSON of `path` (.gltf, or a .glb's JSON chunk). Data URIs are decoded only with
/// `load_embedded` (an estimate needs the counts alone).
/// @throw IoError when a file cannot be read; FormatError for a malformed container, JSON or
///        reference (naming the file and the object).
GltfDocument read_gltf_document(const std::filesystem::path& path, bool load_embedded);

/// The vertex and triangle entries the instances place (degenerate ones included).
struct GltfCounts {
  std::uint64_t vertices = 0, triangles = 0;
  std::uint64_t embedded_bytes = 0;  ///< the data URIs' buffers, held decoded
  std::uint64_t buffer_bytes = 0;    ///< every buffer's (checked against its file when read)
};
GltfCounts count_placed(const GltfDocument& document);

/// What the document's tables hold, and what a soup's part table holds for its instances
/// (their names twice, the set that keeps their paths unique).
std::uint64_t held_bytes(const GltfDocument& document);

}  // namespace tetrapage::detail
