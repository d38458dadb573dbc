#pragma once
// Internal: a glTF 2.0 file's scene as our reader needs it: the buffers (a GLB's BIN chunk, an
// external file, a data URI), the views and accessors its triangle primitives use (checked to
// lie within their views and buffers), its meshes, and every mesh node placed by its composed
// transform. Parsed from the JSON once, which is then let go, so that reading holds these
// tables and not the document.

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace tetrapage::detail {

/// Row-major 4x4, applied to column vectors (glTF's column-major matrices transposed).
using Transform = std::array<double, 16>;

/// A regular file read at offsets (pread); closed with the object.
class ReadOnlyFile {
 public:
  /// @throw IoError when it cannot be opened or is not a regular file (a FIFO is not waited on).
  explicit ReadOnlyFile(const std::filesystem::path& path);
  ReadOnlyFile(const ReadOnlyFile&) = delete;
  ReadOnlyFile& operator=(const ReadOnlyFile&) = delete;
  ~ReadOnlyFile();
  std::uint64_t size() const { return size_; }
  /// Exactly `count` bytes at `offset`. @throw FormatError when the file ends before them.
  void read_at(std::uint64_t offset, std::size_t count, char* out) const;

 private:
  std::filesystem::path path_;
  int descriptor_ = -1;
  std::uint64_t size_ = 0;
};

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
  bool has_view = false;             ///< false: sparse, or zeros (Assimp reads those)
  std::uint64_t stride = 0;          ///< set once a primitive's use has checked it
};

struct GltfPrimitive {
  std::uint32_t mode = 4;       ///< 4 triangles, 5 strip, 6 fan (others hold no triangle)
  std::uint64_t positions = 0;  ///< accessor
  std::optional<std::uint64_t> indices;
};

/// A mesh's triangle primitives that hold at least one vertex.
struct GltfMesh {
  std::vector<GltfPrimitive> primitives;
};

/// One node with a mesh, as placed in the scene.
struct GltfInstance {
  std::string name;  ///< the part's name: "stem" alone, else "stem/node"
  Transform transform{};
  std::uint64_t mesh = 0;
};

struct GltfDocument {
  bool binary = false;
  /// Set when Assimp reads the file instead (glTF 1.0, an extension that changes the geometry,
  /// a sparse accessor or one without a view): what our reader does not read.
  std::string needs_assimp;
  std::uint64_t json_bytes = 0;
  /// What parsing the JSON held at most (its text and nlohmann's document), by its shape.
  std::uint64_t parse_bytes = 0;
  std::uint64_t node_count = 0;
  /// The bytes the file and its buffers hold, each file once.
  std::uint64_t stored_bytes = 0;
  std::vector<GltfBuffer> buffers;
  std::vector<GltfView> views;
  std::vector<GltfAccessor> accessors;
  std::vector<GltfMesh> meshes;
  std::vector<GltfInstance> instances;  ///< depth first, in the file's order
};

/// Parses the JSON of `path` (.gltf, or a .glb's JSON chunk). Data URIs are decoded only with
/// `load_embedded` (an estimate needs the counts alone).
/// @throw IoError when a file cannot be read; FormatError for a malformed container, JSON or
///        reference (naming the file and the object), or a JSON whose document would take more
///        than 4 GiB; InputError when the scene places more vertices than a soup can index.
GltfDocument read_gltf_document(const std::filesystem::path& path, bool load_embedded);

/// What parsing the JSON of `path` would hold (its text and document), told from a scan of its
/// text without parsing it; for a GLB the JSON chunk's. 0 when the file cannot be read.
std::uint64_t gltf_parse_bytes(const std::filesystem::path& path) noexcept;

/// The JSON text of a .gltf, or of a .glb's JSON chunk (a glTF 1.0 GLB: empty).
/// @throw IoError, FormatError as read_gltf_document for the container.
std::string read_gltf_json(const std::filesystem::path& path);

/// A URI's percent escapes decoded ("a%20b.bin" -> "a b.bin").
std::string decoded_uri(const std::string& uri);

/// The bytes of an index of componentType 5121, 5123 or 5125.
inline std::size_t index_bytes(std::uint32_t component_type) {
  return component_type == 5121 ? 1 : component_type == 5123 ? 2 : 4;
}

/// The vertex and triangle entries the instances place (degenerate ones included).
struct GltfCounts {
  std::uint64_t vertices = 0, triangles = 0;
  std::uint64_t embedded_bytes = 0;  ///< the data URIs' buffers, held decoded
  /// The bytes the buffers hold, each file once: what bounds the soup's reservation.
  std::uint64_t stored_bytes = 0;
};
GltfCounts count_placed(const GltfDocument& document);

/// What the document's tables hold, and what a soup's part table holds for its instances
/// (their names twice, the set that keeps their paths unique).
std::uint64_t held_bytes(const GltfDocument& document);

}  // namespace tetrapage::detail
