// The glTF 2.0 document (GltfDocument.h): the GLB container, the JSON's tables, the scene's
// node tree walked without recursion, and data URIs decoded.

#include "GltfDocument.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <map>
#include <set>
#include <string_view>

#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>

#include "PathSupport.h"
#include "ReaderSupport.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/QuotedInput.h"
#include "tetrapage/formats/mesh/FileChecks.h"

namespace tetrapage::detail {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

// A JSON chunk or .gltf larger than this is refused: no scene description needs it (a file's
// geometry belongs in its buffers) and the document is held while it is parsed.
constexpr std::uint64_t kLargestJson = std::uint64_t(1) << 30;

std::uint32_t little_u32(const char* bytes) {
  const auto* b = reinterpret_cast<const unsigned char*>(bytes);
  return std::uint32_t(b[0]) | std::uint32_t(b[1]) << 8 | std::uint32_t(b[2]) << 16 |
         std::uint32_t(b[3]) << 24;
}

struct Container {
  std::string json;
  std::uint64_t file_bytes = 0;
  std::uint64_t bin_offset = 0, bin_length = 0;
  bool has_bin = false;
  bool version_one = false;  // a glTF 1.0 GLB
};

// A .glb: a 12-byte header (magic, version, length), the JSON chunk, then chunks of which the
// first BIN one is the buffer; others are skipped unread (a reader must ignore them).
Container read_glb(const ReadOnlyFile& file, const std::string& name) {
  Container out;
  out.file_bytes = file.size();
  char header[12];
  if (file.size() < 12)
    throw FormatError(name + ": not a GLB file (shorter than its 12-byte header)");
  file.read_at(0, 12, header);
  if (std::memcmp(header, "glTF", 4) != 0)
    throw FormatError(name + ": not a GLB file (no 'glTF' magic in its first 4 bytes)");
  const std::uint32_t version = little_u32(header + 4);
  if (version == 1) {
    out.version_one = true;
    return out;
  }
  if (version != 2)
    throw FormatError(name + ": GLB version " + std::to_string(version) + " (readable: 1 and 2)");
  const std::uint64_t length = little_u32(header + 8);
  if (length > file.size())
    throw FormatError(name + ": the GLB header states " + std::to_string(length) +
                      " bytes, the file has " + std::to_string(file.size()));
  std::uint64_t at = 12;
  for (int chunk = 0; at + 8 <= length; ++chunk) {
    char chunk_header[8];
    file.read_at(at, 8, chunk_header);
    const std::uint64_t chunk_length = little_u32(chunk_header);
    const std::string_view type(chunk_header + 4, 4);
    at += 8;
    if (chunk_length > length - at)
      throw FormatError(name + ": GLB chunk " + std::to_string(chunk) + " states " +
                        std::to_string(chunk_length) + " bytes past the file's end");
    if (chunk == 0) {
      if (type != std::string_view("JSON", 4))
        throw FormatError(name + ": the GLB's first chunk is not its JSON");
      if (chunk_length > kLargestJson)
        throw FormatError(name + ": the GLB's JSON chunk is larger than 1 GiB");
      out.json.resize(static_cast<std::size_t>(chunk_length));
      file.read_at(at, out.json.size(), out.json.data());
    } else if (type == std::string_view("BIN\0", 4)) {
      out.has_bin = true;
      out.bin_offset = at;
      out.bin_length = chunk_length;
      break;  // read through its own block when an accessor needs it
    }
    at += chunk_length;
  }
  if (out.json.empty()) throw FormatError(name + ": the GLB has no JSON chunk");
  return out;
}

Container read_container(const fs::path& path, bool binary) {
  const ReadOnlyFile file(path);
  if (binary) return read_glb(file, path.string());
  if (file.size() > kLargestJson)
    throw FormatError(path.string() + ": a .gltf larger than 1 GiB (its JSON is held whole)");
  Container out;
  out.file_bytes = file.size();
  out.json.resize(static_cast<std::size_t>(file.size()));
  file.read_at(0, out.json.size(), out.json.data());
  return out;
}

// What nlohmann's document of a JSON text holds, from the text's shape alone (a linear scan, no
// allocation): a value is 16 B in its array's or object's storage (up to 48 while an array
// grows: old and new), an object's map 64 B and each member's tree node with its key 96 B, an
// array's vector 32 B, a string 48 B beside its characters past 15; and the text itself, held
// while parsed.
std::uint64_t document_bytes(std::string_view text) {
  std::uint64_t objects = 0, arrays = 0, strings = 0, scalars = 0, members = 0, long_strings = 0;
  bool in_string = false, escaped = false, in_scalar = false;
  std::uint64_t string_length = 0;
  for (const char c : text) {
    if (in_string) {
      if (escaped) {
        escaped = false;
      } else if (c == '\\') {
        escaped = true;
      } else if (c == '"') {
        in_string = false;
        if (string_length > 15) long_strings += string_length + 1;
      }
      ++string_length;
      continue;
    }
    const bool scalar =
        std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '-' || c == '+' || c == '.';
    if (scalar && !in_scalar) ++scalars;
    in_scalar = scalar;
    if (scalar) continue;
    if (c == '{') ++objects;
    if (c == '[') ++arrays;
    if (c == ':') ++members;
    if (c == '"') {
      in_string = true;
      string_length = 0;
      ++strings;
    }
  }
  const std::uint64_t value_strings = strings > members ? strings - members : 0;
  const std::uint64_t values = objects + arrays + scalars + value_strings;
  return text.size() + 48 * values + 64 * objects + 96 * members + 32 * arrays +
         48 * value_strings + long_strings;
}

// A document that would hold more than this is refused before it is parsed.
constexpr std::uint64_t kLargestDocument = std::uint64_t(4) << 30;

// Field access that names the object at fault.
class Fields {
 public:
  Fields(const std::string& file, const Json& object, std::string where)
      : file_(file), object_(object), where_(std::move(where)) {}

  bool has(const char* key) const { return object_.is_object() && object_.contains(key); }
  const Json* find(const char* key) const {
    if (!object_.is_object()) return nullptr;
    const auto it = object_.find(key);
    return it == object_.end() ? nullptr : &*it;
  }
  std::uint64_t required_unsigned(const char* key) const {
    if (!has(key)) fail(std::string("has no ") + key);
    return unsigned_or(key, 0);
  }
  std::uint64_t unsigned_or(const char* key, std::uint64_t fallback) const {
    const Json* value = find(key);
    if (value == nullptr) return fallback;
    if (!value->is_number_unsigned()) fail(std::string(key) + " is not a non-negative integer");
    return value->get<std::uint64_t>();
  }
  std::uint64_t index(const char* key, std::size_t size) const {
    const Json* value = find(key);
    if (value == nullptr) fail(std::string("has no ") + key);
    return checked_index(*value, size, key);
  }
  std::uint64_t checked_index(const Json& value, std::size_t size, const std::string& what) const {
    if (!value.is_number_unsigned()) fail(what + " is not a non-negative integer");
    const auto i = value.get<std::uint64_t>();
    if (i >= size)
      fail(what + " " + std::to_string(i) + " out of range (" + std::to_string(size) + ")");
    return i;
  }
  std::string string_or(const char* key, std::string fallback) const {
    const Json* value = find(key);
    if (value == nullptr) return fallback;
    if (!value->is_string()) fail(std::string(key) + " is not a string");
    return value->get<std::string>();
  }
  /// The array at `key`, or an empty one.
  const Json& array(const char* key) const {
    static const Json empty = Json::array();
    const Json* value = find(key);
    if (value == nullptr) return empty;
    if (!value->is_array()) fail(std::string(key) + " is not an array");
    return *value;
  }
  /// `count` finite numbers at `key`, or `fallback`.
  template <std::size_t N>
  std::array<double, N> numbers_or(const char* key, const std::array<double, N>& fallback) const {
    const Json* value = find(key);
    if (value == nullptr) return fallback;
    if (!value->is_array() || value->size() != N)
      fail(std::string(key) + " is not an array of " + std::to_string(N) + " numbers");
    std::array<double, N> out{};
    for (std::size_t i = 0; i < N; ++i) {
      if (!(*value)[i].is_number()) fail(std::string(key) + " holds a value that is not a number");
      out[i] = (*value)[i].get<double>();
    }
    return out;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw FormatError(file_ + ": " + where_ + ": " + what);
  }

 private:
  const std::string& file_;
  const Json& object_;
  std::string where_;
};

Transform multiply(const Transform& a, const Transform& b) {
  Transform product{};
  for (int row = 0; row < 4; ++row)
    for (int column = 0; column < 4; ++column) {
      double sum = 0;
      for (int k = 0; k < 4; ++k) sum += a[4 * row + k] * b[4 * k + column];
      product[4 * row + column] = sum;
    }
  return product;
}

constexpr Transform kIdentity{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};

// A node's local transform: its matrix (column-major), else T * R * S.
Transform local_transform(const Fields& node) {
  if (node.has("matrix")) {
    const auto m = node.numbers_or<16>("matrix", {});
    Transform out{};
    for (int row = 0; row < 4; ++row)
      for (int column = 0; column < 4; ++column) out[4 * row + column] = m[4 * column + row];
    return out;
  }
  const auto t = node.numbers_or<3>("translation", {0, 0, 0});
  auto q = node.numbers_or<4>("rotation", {0, 0, 0, 1});  // x, y, z, w
  const auto s = node.numbers_or<3>("scale", {1, 1, 1});
  // Unit by the format; normalised, so that a rounded or careless one still only rotates.
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (!(norm > 0) || !std::isfinite(norm))
    node.fail("its rotation is not a quaternion of finite, non-zero length");
  for (double& c : q) c /= norm;
  const double x = q[0], y = q[1], z = q[2], w = q[3];
  const double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - z * w),     2 * (x * z + y * w),
                       2 * (x * y + z * w),     1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
                       2 * (x * z - y * w),     2 * (y * z + x * w),     1 - 2 * (x * x + y * y)};
  Transform out{};
  for (int row = 0; row < 3; ++row) {
    for (int column = 0; column < 3; ++column)
      out[4 * row + column] = r[3 * row + column] * s[column];
    out[4 * row + 3] = t[row];
  }
  out[15] = 1;
  return out;
}

// Extensions that change only how a model looks, never its positions, indices or placement:
// a file requiring only these is read by our reader.
bool changes_no_geometry(const std::string& extension) {
  for (const char* prefix :
       {"KHR_materials_", "KHR_texture_", "EXT_texture_", "KHR_lights_", "MSFT_texture_"})
    if (extension.rfind(prefix, 0) == 0) return true;
  return false;
}

int base64_value(char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+' || c == '-') return 62;
  if (c == '/' || c == '_') return 63;
  return -1;
}

std::vector<char> decode_base64(std::string_view text, const Fields& where) {
  std::vector<char> out;
  out.reserve(text.size() / 4 * 3 + 3);
  std::uint32_t bits = 0;
  int held = 0;
  for (const char c : text) {
    if (c == '=') break;
    const int value = base64_value(c);
    if (value < 0) where.fail("its data URI holds a character that is not base64");
    bits = bits << 6 | std::uint32_t(value);
    held += 6;
    if (held >= 8) {
      held -= 8;
      out.push_back(static_cast<char>((bits >> held) & 0xff));
    }
  }
  return out;
}

class DocumentParser {
 public:
  DocumentParser(const fs::path& path, bool load_embedded)
      : path_(path), name_(path.string()), load_embedded_(load_embedded) {}

  GltfDocument parse() {
    out_.binary = lower_extension(path_) == ".glb";
    Container container = read_container(path_, out_.binary);
    if (container.version_one) return needing_assimp("a glTF 1.0 GLB");
    out_.stored_bytes = container.file_bytes;
    out_.json_bytes = container.json.size();
    out_.parse_bytes = document_bytes(container.json);
    if (out_.parse_bytes > kLargestDocument)
      throw FormatError(name_ + ": its JSON (" + std::to_string(out_.json_bytes) +
                        " bytes) would take about " + std::to_string(out_.parse_bytes >> 20) +
                        " MiB as a document, above 4 GiB");
    // No parser callback: nlohmann's parser keeps its own stack (a file may nest deeply), and
    // its callback parser rescans a container after every value (quadratic time).
    const Json root = Json::parse(container.json, nullptr, false);
    container.json = std::string();
    if (root.is_discarded() || !root.is_object())
      throw FormatError(name_ + ": its JSON cannot be parsed (not a glTF)");
    const Fields top(name_, root, "the document");
    const Json* asset = top.find("asset");
    const std::string version =
        asset != nullptr ? Fields(name_, *asset, "asset").string_or("version", "") : "";
    if (version.rfind("2.", 0) != 0) return needing_assimp("glTF version " + quoted_input(version));
    for (const Json& extension : top.array("extensionsRequired"))
      if (!extension.is_string() || !changes_no_geometry(extension.get_ref<const std::string&>()))
        return needing_assimp("the required extension " +
                              (extension.is_string()
                                   ? quoted_input(extension.get_ref<const std::string&>())
                                   : std::string("?")));
    read_buffers(top, container);
    read_views(top);
    read_accessors(top);
    read_instances(top);
    if (!out_.needs_assimp.empty()) return needing_assimp(out_.needs_assimp);
    return std::move(out_);
  }

 private:
  GltfDocument needing_assimp(std::string why) {
    GltfDocument out;
    out.binary = out_.binary;
    out.needs_assimp = std::move(why);
    return out;
  }

  void read_buffers(const Fields& top, const Container& container) {
    const Json& buffers = top.array("buffers");
    for (std::size_t b = 0; b < buffers.size(); ++b) {
      const Fields buffer(name_, buffers[b], "buffer " + std::to_string(b));
      GltfBuffer out;
      out.length = buffer.required_unsigned("byteLength");
      const Json* uri = buffer.find("uri");
      if (uri == nullptr) {
        if (!out_.binary || b != 0 || !container.has_bin)
          buffer.fail("has no uri (and is not a GLB's BIN chunk)");
        if (container.bin_length < out.length)
          buffer.fail("states " + std::to_string(out.length) + " bytes, the BIN chunk holds " +
                      std::to_string(container.bin_length));
        out.file = path_;
        out.file_offset = container.bin_offset;
      } else if (!uri->is_string()) {
        buffer.fail("its uri is not a string");
      } else {
        locate(uri->get_ref<const std::string&>(), buffer, out);
      }
      out_.buffers.push_back(std::move(out));
    }
  }

  // A buffer's URI: a base64 data URI, else a file beside the glTF (a relative path: one
  // beginning with '/' would read any file the process may read as geometry).
  void locate(const std::string& uri, const Fields& buffer, GltfBuffer& out) {
    if (uri.rfind("data:", 0) == 0) {
      const std::size_t comma = uri.find(',');
      if (comma == std::string::npos || uri.rfind(";base64", comma) == std::string::npos)
        buffer.fail("its data URI is not base64");
      // Four characters carry three bytes: the URI's length bounds the buffer before decoding.
      const std::uint64_t most = (uri.size() - comma - 1) / 4 * 3 + 2;
      if (most < out.length)
        buffer.fail("states " + std::to_string(out.length) + " bytes, its data URI holds at most " +
                    std::to_string(most));
      out_.stored_bytes += out.length;
      if (!load_embedded_) return;
      out.bytes = decode_base64(std::string_view(uri).substr(comma + 1), buffer);
      if (out.bytes.size() < out.length)
        buffer.fail("states " + std::to_string(out.length) + " bytes, its data URI holds " +
                    std::to_string(out.bytes.size()));
      return;
    }
    if (uri.find("://") != std::string::npos)
      buffer.fail("names " + quoted_input(uri) + ", which is not a file");
    const std::string decoded = decoded_uri(uri);
    if (uri.front() == '/' || decoded.front() == '/')
      buffer.fail("names " + quoted_input(uri) +
                  ", an absolute path (a buffer's URI is relative to the glTF)");
    fs::path file = path_.parent_path() / decoded;
    std::error_code error;
    if (!fs::exists(file, error)) file = path_.parent_path() / uri;  // as Assimp opens it
    require_regular_file(file);
    const std::uint64_t size = fs::file_size(file, error);
    if (error)
      throw IoError("cannot read '" + file.string() + "' (buffer of " + name_ +
                    "): " + error.message());
    if (size < out.length)
      buffer.fail("states " + std::to_string(out.length) + " bytes, '" + file.string() +
                  "' holds " + std::to_string(size));
    if (files_.insert(fs::weakly_canonical(file, error)).second) out_.stored_bytes += size;
    out.file = std::move(file);
  }

  void read_views(const Fields& top) {
    const Json& views = top.array("bufferViews");
    for (std::size_t v = 0; v < views.size(); ++v) {
      const Fields view(name_, views[v], "bufferView " + std::to_string(v));
      GltfView out;
      out.buffer = view.index("buffer", out_.buffers.size());
      out.offset = view.unsigned_or("byteOffset", 0);
      out.length = view.required_unsigned("byteLength");
      out.stride = view.unsigned_or("byteStride", 0);
      if (out.stride > 255) view.fail("byteStride " + std::to_string(out.stride) + " above 255");
      const std::uint64_t buffer_length = out_.buffers[out.buffer].length;
      if (out.offset > buffer_length || out.length > buffer_length - out.offset)
        view.fail("bytes " + std::to_string(out.offset) + " + " + std::to_string(out.length) +
                  " past its buffer's " + std::to_string(buffer_length));
      out_.views.push_back(out);
    }
  }

  // Every accessor as the file states it; those a placed primitive uses are checked there.
  void read_accessors(const Fields& top) {
    const Json& accessors = top.array("accessors");
    for (std::size_t a = 0; a < accessors.size(); ++a) {
      const Fields accessor(name_, accessors[a], "accessor " + std::to_string(a));
      GltfAccessor out;
      out.has_view = accessor.has("bufferView") && !accessor.has("sparse");
      if (out.has_view) out.view = accessor.index("bufferView", out_.views.size());
      out.offset = accessor.unsigned_or("byteOffset", 0);
      out.count = accessor.unsigned_or("count", 0);
      out.component_type = static_cast<std::uint32_t>(
          std::min<std::uint64_t>(accessor.unsigned_or("componentType", 0), 1u << 16));
      out.type = accessor.string_or("type", "");
      out_.accessors.push_back(std::move(out));
    }
  }

  // The scene's nodes depth first (an explicit stack: a file may nest deeply). A node is marked
  // when it is pushed, so that a node reached twice (no tree: it could place itself forever) is
  // refused before the stack grows past the node count.
  void read_instances(const Fields& top) {
    const Json& nodes = top.array("nodes");
    out_.node_count = nodes.size();
    std::vector<bool> met(nodes.size(), false);
    struct Pending {
      std::uint64_t node;
      Transform parent;
    };
    std::vector<Pending> pending;
    const auto push = [&](const Fields& from, std::uint64_t node, const Transform& parent) {
      if (met[node])
        from.fail("node " + std::to_string(node) +
                  " is reached twice in the scene (its nodes make no tree)");
      met[node] = true;
      pending.push_back({node, parent});
    };
    const std::vector<std::uint64_t> roots = scene_roots(top, nodes);
    for (auto r = roots.rbegin(); r != roots.rend(); ++r) push(top, *r, kIdentity);
    std::vector<std::pair<std::uint64_t, Transform>> placed;
    while (!pending.empty()) {
      const Pending next = pending.back();
      pending.pop_back();
      const Fields node(name_, nodes[next.node], "node " + std::to_string(next.node));
      const Transform transform = multiply(next.parent, local_transform(node));
      if (node.has("mesh")) placed.emplace_back(next.node, transform);
      const Json& children = node.array("children");
      for (std::size_t c = children.size(); c-- > 0;)
        push(node, node.checked_index(children[c], nodes.size(), "child"), transform);
    }
    place(top, nodes, placed);
  }

  // The root nodes of the scene `scene` names, else of the first; a file without scenes places
  // every node no other node lists as a child.
  std::vector<std::uint64_t> scene_roots(const Fields& top, const Json& nodes) {
    const Json& scenes = top.array("scenes");
    const std::uint64_t s = top.has("scene") ? top.index("scene", scenes.size()) : 0;
    std::vector<std::uint64_t> roots;
    if (!scenes.empty()) {
      const Fields scene(name_, scenes[s], "scene " + std::to_string(s));
      for (const Json& root : scene.array("nodes"))
        roots.push_back(scene.checked_index(root, nodes.size(), "node"));
      return roots;
    }
    std::vector<bool> child(nodes.size(), false);
    for (std::size_t n = 0; n < nodes.size(); ++n) {
      const Fields node(name_, nodes[n], "node " + std::to_string(n));
      for (const Json& c : node.array("children"))
        child[node.checked_index(c, nodes.size(), "child")] = true;
    }
    for (std::size_t n = 0; n < nodes.size(); ++n)
      if (!child[n]) roots.push_back(n);
    return roots;
  }

  // The placed mesh nodes as instances, each mesh's primitives read once (a mesh no node
  // places is not read), and the placed vertices counted against what a soup indexes.
  void place(const Fields& top, const Json& nodes,
             const std::vector<std::pair<std::uint64_t, Transform>>& placed) {
    const Json& meshes = top.array("meshes");
    out_.meshes.resize(meshes.size());
    std::vector<bool> read(meshes.size(), false);
    const std::string stem = path_.stem().string();
    std::uint64_t vertices = 0;
    for (std::size_t i = 0; i < placed.size(); ++i) {
      const Fields node(name_, nodes[placed[i].first], "node " + std::to_string(placed[i].first));
      GltfInstance instance;
      instance.mesh = node.index("mesh", meshes.size());
      if (!read[instance.mesh]) {
        read[instance.mesh] = true;
        read_primitives(
            Fields(name_, meshes[instance.mesh], "mesh " + std::to_string(instance.mesh)),
            out_.meshes[instance.mesh]);
        if (!out_.needs_assimp.empty()) return;
      }
      const std::vector<GltfPrimitive>& primitives = out_.meshes[instance.mesh].primitives;
      if (primitives.empty()) continue;
      for (const GltfPrimitive& primitive : primitives)
        vertices += out_.accessors[primitive.positions].count;
      if (vertices > max_vertices)
        throw InputError(name_ + ": its scene places more than " + std::to_string(max_vertices) +
                         " vertices, more than a soup can index");
      const std::string node_name = node.string_or("name", "");
      instance.name =
          placed.size() == 1
              ? stem
              : stem + "/" + (node_name.empty() ? "node" + std::to_string(i) : node_name);
      instance.transform = placed[i].second;
      out_.instances.push_back(std::move(instance));
    }
  }

  void read_primitives(const Fields& mesh, GltfMesh& out) {
    const Json& primitives = mesh.array("primitives");
    for (std::size_t p = 0; p < primitives.size(); ++p) {
      const Fields primitive(name_, primitives[p], "primitive " + std::to_string(p));
      GltfPrimitive read;
      const std::uint64_t mode = primitive.unsigned_or("mode", 4);
      if (mode < 4) continue;  // points and lines bound no surface
      if (mode > 6) primitive.fail("mode " + std::to_string(mode) + " (glTF's are 0 to 6)");
      read.mode = static_cast<std::uint32_t>(mode);
      if (const Json* extensions = primitive.find("extensions");
          extensions != nullptr && extensions->is_object())
        for (const auto& [name, value] : extensions->items())
          if (!changes_no_geometry(name)) {
            out_.needs_assimp = "the primitive extension " + quoted_input(name);
            return;
          }
      const Json* attributes = primitive.find("attributes");
      if (attributes == nullptr || !attributes->is_object() || !attributes->contains("POSITION"))
        continue;
      read.positions = Fields(name_, *attributes, "primitive " + std::to_string(p) + " attributes")
                           .index("POSITION", out_.accessors.size());
      if (primitive.has("indices"))
        read.indices = primitive.index("indices", out_.accessors.size());
      if (!out_.accessors[read.positions].has_view ||
          (read.indices && !out_.accessors[*read.indices].has_view)) {
        out_.needs_assimp = "a sparse accessor or one without a bufferView";
        return;
      }
      check_positions(read.positions);
      if (read.indices) check_indices(*read.indices);
      if (out_.accessors[read.positions].count > 0) out.primitives.push_back(read);
    }
  }

  void check_positions(std::uint64_t a) {
    const GltfAccessor& accessor = out_.accessors[a];
    if (accessor.type != "VEC3" || accessor.component_type != 5126)
      throw FormatError(name_ + ": accessor " + std::to_string(a) +
                        ": POSITION is not VEC3 of floats (componentType 5126)");
    check_range(a, 12);
  }
  void check_indices(std::uint64_t a) {
    const GltfAccessor& accessor = out_.accessors[a];
    const std::uint32_t type = accessor.component_type;
    if (accessor.type != "SCALAR" || (type != 5121 && type != 5123 && type != 5125))
      throw FormatError(
          name_ + ": accessor " + std::to_string(a) +
          ": indices are not SCALAR unsigned integers (componentType 5121, 5123 or 5125)");
    check_range(a, index_bytes(type));
  }
  // The accessor's elements lie within its view (count * stride may not fit 64 bits: compared
  // by division), so that every count the document holds is backed by bytes of a buffer.
  void check_range(std::uint64_t a, std::uint64_t element_bytes) {
    GltfAccessor& accessor = out_.accessors[a];
    const GltfView& view = out_.views[accessor.view];
    const std::uint64_t stride = view.stride != 0 ? view.stride : element_bytes;
    const std::string where = name_ + ": accessor " + std::to_string(a);
    if (stride < element_bytes)
      throw FormatError(where + ": byteStride " + std::to_string(stride) + " below its element's " +
                        std::to_string(element_bytes) + " bytes");
    const std::uint64_t room = view.length >= accessor.offset ? view.length - accessor.offset : 0;
    if (accessor.count > 0 &&
        (room < element_bytes || (accessor.count - 1) > (room - element_bytes) / stride))
      throw FormatError(where + ": " + std::to_string(accessor.count) + " elements of " +
                        std::to_string(element_bytes) + " bytes (stride " + std::to_string(stride) +
                        ") from byte " + std::to_string(accessor.offset) +
                        " pass the end of its bufferView (" + std::to_string(view.length) +
                        " bytes)");
    accessor.stride = stride;
  }

  const fs::path& path_;
  const std::string name_;
  const bool load_embedded_;
  GltfDocument out_;
  std::set<fs::path> files_;  // the external buffers' files, each counted once
};

}  // namespace

ReadOnlyFile::ReadOnlyFile(const fs::path& path) : path_(path) {
  // Non-blocking: opening a FIFO would otherwise wait for a writer forever.
  descriptor_ = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (descriptor_ < 0)
    throw IoError("cannot open '" + path.string() + "': " + std::strerror(errno));
  struct stat status {};
  if (::fstat(descriptor_, &status) != 0 || !S_ISREG(status.st_mode)) {
    ::close(descriptor_);
    descriptor_ = -1;
    require_regular_file(path);  // throws, naming what it is
    throw IoError("cannot read '" + path.string() + "': not a regular file");
  }
  size_ = static_cast<std::uint64_t>(status.st_size);
}

ReadOnlyFile::~ReadOnlyFile() {
  if (descriptor_ >= 0) ::close(descriptor_);
}

void ReadOnlyFile::read_at(std::uint64_t offset, std::size_t count, char* out) const {
  std::size_t got = 0;
  while (got < count) {
    const ssize_t n =
        ::pread(descriptor_, out + got, count - got, static_cast<off_t>(offset + got));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw IoError("cannot read '" + path_.string() + "': " + std::strerror(errno));
    if (n == 0)
      throw FormatError(path_.string() + ": ends before byte " + std::to_string(offset + count) +
                        " (changed while read?)");
    got += static_cast<std::size_t>(n);
  }
}

// A URI's percent escapes decoded ("a%20b.bin" -> "a b.bin").
std::string decoded_uri(const std::string& uri) {
  std::string path;
  for (std::size_t i = 0; i < uri.size(); ++i) {
    const auto hex = [&](std::size_t k) {
      return std::isxdigit(static_cast<unsigned char>(uri[k])) != 0;
    };
    if (uri[i] == '%' && i + 2 < uri.size() && hex(i + 1) && hex(i + 2)) {
      path += char(std::stoi(uri.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      path += uri[i];
    }
  }
  return path;
}

std::string read_gltf_json(const fs::path& path) {
  return read_container(path, lower_extension(path) == ".glb").json;
}

GltfDocument read_gltf_document(const fs::path& path, bool load_embedded) {
  return DocumentParser(path, load_embedded).parse();
}

std::uint64_t gltf_parse_bytes(const fs::path& path) noexcept {
  try {
    return document_bytes(read_gltf_json(path));
  } catch (const std::exception&) {
    return 0;
  }
}

GltfCounts count_placed(const GltfDocument& document) {
  GltfCounts counts;
  counts.stored_bytes = document.stored_bytes;
  for (const GltfBuffer& buffer : document.buffers)
    if (buffer.file.empty()) counts.embedded_bytes += buffer.length;
  // Each count is backed by its view's bytes and the placed vertices fit 32 bits (checked by
  // the parse): no sum below wraps.
  for (const GltfInstance& instance : document.instances) {
    for (const GltfPrimitive& primitive : document.meshes[instance.mesh].primitives) {
      const std::uint64_t vertices = document.accessors[primitive.positions].count;
      const std::uint64_t corners =
          primitive.indices ? document.accessors[*primitive.indices].count : vertices;
      counts.vertices += vertices;
      counts.triangles += primitive.mode == 4 ? corners / 3 : (corners >= 3 ? corners - 2 : 0);
    }
  }
  return counts;
}

std::uint64_t held_bytes(const GltfDocument& document) {
  std::uint64_t bytes =
      document.buffers.size() * sizeof(GltfBuffer) + document.views.size() * sizeof(GltfView) +
      document.accessors.size() * sizeof(GltfAccessor) + document.meshes.size() * sizeof(GltfMesh);
  for (const GltfBuffer& buffer : document.buffers) bytes += buffer.file.native().capacity();
  for (const GltfMesh& mesh : document.meshes)
    bytes += mesh.primitives.capacity() * sizeof(GltfPrimitive);
  // A part's name in the instance, the soup's names and paths and the builder's set and
  // suffix table (tree nodes of 64 B beside their strings).
  constexpr std::uint64_t kPartBytes = 4 * sizeof(std::string) + 128;
  for (const GltfInstance& instance : document.instances)
    bytes += sizeof(GltfInstance) + kPartBytes + 5 * instance.name.capacity();
  return bytes;
}

}  // namespace tetrapage::detail
