// Streaming mesh writers. Text numbers are printed in the shortest form that reads back as
// the same double (std::to_chars), so OBJ/PLY/OFF round trips are exact; nothing depends on
// the clock or the locale, so the same parts give the same bytes.

#include "tetrapage/formats/mesh/MeshWriter.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "PathSupport.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/TextNumbers.h"
#include "tetrapage/formats/mesh/Manifest.h"
#include "tetrapage/formats/mesh/OutputFile.h"

namespace tetrapage {

class MeshWriter::Impl {
 public:
  explicit Impl(const std::filesystem::path& path) : path_(path), output_(path) {}
  virtual ~Impl() = default;
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  /// What a part is called; `continues`: the triangles go to the part added last.
  struct Label {
    std::string_view name;  ///< empty only for an unnamed first part
    std::string_view path;  ///< empty: the name
    bool continues = false;
  };
  virtual void add_part(std::span<const Vec3> vertices, std::span<const TriangleIndices> triangles,
                        const Label& label) = 0;
  /// Writes what is left (headers, counts, buffered data) into output_.
  virtual void finish() = 0;

  void commit() {
    if (committed_) return;
    if (failed_) {
      throw IoError("cannot commit '" + path_.string() + "': an earlier commit failed");
    }
    try {
      finish();
      output_.rename_to(path_);
    } catch (...) {
      failed_ = true;  // the temporary is half finished: never finish it twice
      throw;
    }
    committed_ = true;
  }
  bool committed() const { return committed_; }

  const std::filesystem::path& path() const { return path_; }

  std::uint64_t triangles = 0;
  std::uint64_t vertices = 0;
  std::uint64_t parts = 0;

 protected:
  // A temporary beside the output's own ("OUTPUT.faces.tmp-PID"), swept like it after a kill.
  static std::filesystem::path side_file(const std::filesystem::path& path, const char* suffix) {
    const std::filesystem::path side(path.string() + suffix);
    remove_stale_temporaries(side);
    return temporary_path(side);
  }

  std::filesystem::path path_;
  OutputFile output_;
  bool committed_ = false;
  bool failed_ = false;
};

namespace {

void check_part(const std::filesystem::path& path, std::span<const Vec3> vertices,
                std::span<const TriangleIndices> triangles) {
  for (std::size_t v = 0; v < vertices.size(); ++v) {
    const Vec3& p = vertices[v];
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
      throw InputError("writing '" + path.string() + "': vertex " + std::to_string(v) +
                       " of the part is not finite");
    }
  }
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    for (const auto index : triangles[t]) {
      if (index >= vertices.size()) {
        throw InputError("writing '" + path.string() + "': triangle " + std::to_string(t) +
                         " uses vertex " + std::to_string(index) + " but the part has " +
                         std::to_string(vertices.size()) + " vertices");
      }
    }
  }
}

/// Formats "<prefix>a b c\n" for three doubles.
char* format_vertex(char* out, const char* prefix, const Vec3& p) {
  while (*prefix != '\0') *out++ = *prefix++;
  for (int axis = 0; axis < 3; ++axis) {
    out = detail::write_double(out, p[axis]);
    *out++ = axis < 2 ? ' ' : '\n';
  }
  return out;
}

char* format_face(char* out, const char* prefix, std::uint64_t a, std::uint64_t b,
                  std::uint64_t c) {
  while (*prefix != '\0') *out++ = *prefix++;
  const std::uint64_t corners[3] = {a, b, c};
  for (int k = 0; k < 3; ++k) {
    out = std::to_chars(out, out + 24, corners[k]).ptr;
    *out++ = k < 2 ? ' ' : '\n';
  }
  return out;
}

constexpr std::size_t line_room = 4 * detail::max_double_chars + 16;

class ObjWriter final : public MeshWriter::Impl {
 public:
  explicit ObjWriter(const std::filesystem::path& path) : Impl(path) {
    output_.write("# written by tetrapage\n");
  }

  void add_part(std::span<const Vec3> part_vertices,
                std::span<const TriangleIndices> part_triangles, const Label& label) override {
    if (!label.continues) write_label(label);
    // OBJ indices are global and 1-based: shift by the vertices of the earlier parts.
    const std::uint64_t base = vertices + 1;
    for (const auto& p : part_vertices) {
      char* line = output_.reserve(line_room);
      output_.advance(static_cast<std::size_t>(format_vertex(line, "v ", p) - line));
    }
    for (const auto& t : part_triangles) {
      char* line = output_.reserve(line_room);
      output_.advance(static_cast<std::size_t>(
          format_face(line, "f ", base + t[0], base + t[1], base + t[2]) - line));
    }
  }
  void finish() override {}

 private:
  // What ObjReader reads back as this name and path: `o PATH` for a part whose path is its
  // name, `o OBJECT` and `g NAME` for "OBJECT/NAME", else `o PATH` and `g NAME`.
  void write_label(const Label& label) {
    if (label.name.empty()) return;  // an unnamed first part: the reader names it by the stem
    const std::string_view name = label.name, path = label.path.empty() ? name : label.path;
    std::string object(path), group;
    if (path != name) {
      const bool nested = path.size() > name.size() + 1 && path.ends_with(name) &&
                          path[path.size() - name.size() - 1] == '/';
      if (nested) object = path.substr(0, path.size() - name.size() - 1);
      group = name;
    }
    // Two parts the reader would merge (paths "a" named "b" and "a/b" named "b") stay apart.
    std::string& renamed = group.empty() ? object : group;
    const std::string original = renamed;
    for (int k = 2; !written_.insert(object + '\n' + group).second; ++k)
      renamed = original + "#" + std::to_string(k);
    output_.write("o " + one_line(object) + "\n");
    if (!group.empty()) output_.write("g " + one_line(group) + "\n");
  }
  // A name is the rest of its line: line breaks inside it become spaces.
  static std::string one_line(std::string text) {
    std::replace_if(
        text.begin(), text.end(), [](char c) { return c == '\n' || c == '\r'; }, ' ');
    return text;
  }

  std::set<std::string> written_;
};

class StlWriter final : public MeshWriter::Impl {
 public:
  explicit StlWriter(const std::filesystem::path& path) : Impl(path) {
    // 80 bytes that must not start with "solid" (which would suggest ASCII STL), then the
    // triangle count, patched by finish().
    char header[84] = {};
    const std::string_view text = "binary STL written by tetrapage";
    std::memcpy(header, text.data(), text.size());
    output_.write(header, sizeof header);
  }

  void add_part(std::span<const Vec3> part_vertices,
                std::span<const TriangleIndices> part_triangles, const Label&) override {
    if (triangles + part_triangles.size() > std::numeric_limits<std::uint32_t>::max()) {
      throw InputError("writing '" + path_.string() +
                       "': binary STL holds at most 2^32-1 triangles");
    }
    for (const auto& t : part_triangles) {
      const Vec3& a = part_vertices[t[0]];
      const Vec3& b = part_vertices[t[1]];
      const Vec3& c = part_vertices[t[2]];
      const Vec3 u{b[0] - a[0], b[1] - a[1], b[2] - a[2]};
      const Vec3 v{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
      Vec3 n{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
      const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      if (length > 0 && std::isfinite(length)) {
        for (double& component : n) component /= length;
      } else {
        n = {0, 0, 0};
      }
      float record[12];
      for (int k = 0; k < 3; ++k) {
        record[k] = static_cast<float>(n[k]);
        record[3 + k] = static_cast<float>(a[k]);
        record[6 + k] = static_cast<float>(b[k]);
        record[9 + k] = static_cast<float>(c[k]);
      }
      static_assert(std::endian::native == std::endian::little, "STL is little-endian");
      const std::uint16_t attributes = 0;
      output_.write(record, sizeof record);
      output_.write(&attributes, sizeof attributes);
    }
  }

  void finish() override {
    const auto count = static_cast<std::uint32_t>(triangles);
    output_.write_at(80, &count, sizeof count);
  }
};

/// PLY and OFF need the counts in the header: vertices and faces stream into two side files,
/// assembled behind the header by finish().
class CountedHeaderWriter : public MeshWriter::Impl {
 public:
  explicit CountedHeaderWriter(const std::filesystem::path& path)
      : Impl(path),
        vertex_file_(side_file(path, ".vertices"), path),
        face_file_(side_file(path, ".faces"), path) {}

  void finish() override {
    output_.write(header());
    output_.append_file(vertex_file_);
    output_.append_file(face_file_);
    output_.write(trailer());
  }

 protected:
  virtual std::string header() const = 0;
  /// Bytes after the faces.
  virtual std::string trailer() const { return {}; }

  OutputFile vertex_file_;
  OutputFile face_file_;
};

// Parts go into a `part` element after `face` (Assimp 5.2 fails on an element before it): per
// part its face count (the parts' faces are consecutive in `face`), name and path (empty: the
// name) as lists of bytes. A file of one unnamed part has none. PLY readers skip the elements
// they do not know.
class PlyWriter final : public CountedHeaderWriter {
 public:
  using CountedHeaderWriter::CountedHeaderWriter;

  void add_part(std::span<const Vec3> part_vertices,
                std::span<const TriangleIndices> part_triangles, const Label& label) override {
    if (vertices + part_vertices.size() > std::numeric_limits<std::uint32_t>::max()) {
      throw InputError("writing '" + path_.string() + "': more than 2^32-1 vertices");
    }
    if (!label.continues || parts_.empty())
      parts_.push_back({std::string(label.name), std::string(label.path), 0});
    if (parts_.back().faces + part_triangles.size() > std::numeric_limits<std::uint32_t>::max())
      throw InputError("writing '" + path_.string() + "': part '" + parts_.back().name +
                       "' has more than 2^32-1 triangles, more than a PLY part table counts");
    parts_.back().faces += part_triangles.size();
    static_assert(std::endian::native == std::endian::little, "written as little-endian");
    for (const auto& p : part_vertices) vertex_file_.write(p.data(), sizeof(double) * 3);
    const auto base = static_cast<std::uint32_t>(vertices);
    for (const auto& t : part_triangles) {
      char record[13];
      record[0] = 3;
      const std::uint32_t corners[3] = {base + t[0], base + t[1], base + t[2]};
      std::memcpy(record + 1, corners, sizeof corners);
      face_file_.write(record, sizeof record);
    }
  }

 private:
  std::string header() const override {
    std::string text = "ply\nformat binary_little_endian 1.0\ncomment written by tetrapage\n";
    text += "element vertex " + std::to_string(vertices) +
            "\nproperty double x\nproperty double y\nproperty double z\n";
    text +=
        "element face " + std::to_string(triangles) + "\nproperty list uchar uint vertex_indices\n";
    if (has_part_table()) {
      text +=
          "element part " + std::to_string(parts_.size()) +
          "\nproperty uint faces\nproperty list uint uchar name\nproperty list uint uchar path\n";
    }
    return text + "end_header\n";
  }

  std::string trailer() const override {
    std::string bytes;
    if (!has_part_table()) return bytes;
    const auto put = [&bytes](std::uint32_t value) {
      bytes.append(reinterpret_cast<const char*>(&value), sizeof value);
    };
    for (const auto& part : parts_) {
      put(static_cast<std::uint32_t>(part.faces));
      for (const std::string* text : {&part.name, &part.path}) {
        put(static_cast<std::uint32_t>(text->size()));
        bytes += *text;
      }
    }
    return bytes;
  }

  bool has_part_table() const {
    return parts_.size() > 1 || (parts_.size() == 1 && !parts_[0].name.empty());
  }

  struct Part {
    std::string name, path;
    std::uint64_t faces = 0;
  };
  std::vector<Part> parts_;
};

class OffWriter final : public CountedHeaderWriter {
 public:
  using CountedHeaderWriter::CountedHeaderWriter;

  void add_part(std::span<const Vec3> part_vertices,
                std::span<const TriangleIndices> part_triangles, const Label&) override {
    for (const auto& p : part_vertices) {
      char* line = vertex_file_.reserve(line_room);
      vertex_file_.advance(static_cast<std::size_t>(format_vertex(line, "", p) - line));
    }
    const std::uint64_t base = vertices;
    for (const auto& t : part_triangles) {
      char* line = face_file_.reserve(line_room);
      face_file_.advance(static_cast<std::size_t>(
          format_face(line, "3 ", base + t[0], base + t[1], base + t[2]) - line));
    }
  }

 private:
  std::string header() const override {
    return "OFF\n" + std::to_string(vertices) + " " + std::to_string(triangles) + " 0\n";
  }
};

std::string base64(const std::vector<unsigned char>& bytes) {
  static constexpr char alphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string text;
  text.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const std::uint32_t group =
        (std::uint32_t{bytes[i]} << 16) | (std::uint32_t{bytes[i + 1]} << 8) | bytes[i + 2];
    for (int shift = 18; shift >= 0; shift -= 6) text.push_back(alphabet[(group >> shift) & 63]);
  }
  if (i < bytes.size()) {
    const bool two = i + 1 < bytes.size();
    const std::uint32_t group =
        (std::uint32_t{bytes[i]} << 16) | (two ? std::uint32_t{bytes[i + 1]} << 8 : 0);
    text.push_back(alphabet[(group >> 18) & 63]);
    text.push_back(alphabet[(group >> 12) & 63]);
    text.push_back(two ? alphabet[(group >> 6) & 63] : '=');
    text.push_back('=');
  }
  return text;
}

/// glTF 2.0 (.gltf with the buffer embedded as a base64 data URI, or .glb). One mesh and one
/// node per part, float positions, uint32 indices. Buffered in memory until commit().
class GltfWriter final : public MeshWriter::Impl {
 public:
  GltfWriter(const std::filesystem::path& path, bool binary) : Impl(path), binary_(binary) {}

  void add_part(std::span<const Vec3> part_vertices,
                std::span<const TriangleIndices> part_triangles, const Label& label) override {
    if (!label.continues) {
      name_ = label.name.empty() ? "part" + std::to_string(parts) : std::string(label.name);
      mesh_ = none;
    }
    if (part_triangles.empty()) return;  // glTF accessors cannot be empty
    // A part is a mesh (made at its first triangles), each add_part of it a primitive.
    if (mesh_ == none) {
      mesh_ = mesh_names_.size();
      mesh_names_.push_back(name_);
    }
    Part part;
    part.mesh = mesh_;
    part.vertex_offset = buffer_.size();
    part.vertex_count = part_vertices.size();
    for (const auto& p : part_vertices) {
      for (int axis = 0; axis < 3; ++axis) {
        const float value = static_cast<float>(p[axis]);
        part.lo[axis] = std::min(part.lo[axis], value);
        part.hi[axis] = std::max(part.hi[axis], value);
        append(&value, sizeof value);
      }
    }
    part.index_offset = buffer_.size();
    part.index_count = 3 * part_triangles.size();
    for (const auto& t : part_triangles) append(t.data(), sizeof(std::uint32_t) * 3);
    parts_.push_back(part);
  }

  void finish() override {
    using nlohmann::json;
    json document;
    document["asset"] = {{"version", "2.0"}, {"generator", "tetrapage"}};
    document["scene"] = 0;
    json scene;
    scene["nodes"] = json::array();
    json nodes = json::array();
    json meshes = json::array();
    json accessors = json::array();
    json buffer_views = json::array();
    for (std::size_t k = 0; k < parts_.size(); ++k) {
      const Part& part = parts_[k];
      json positions_view;
      positions_view["buffer"] = 0;
      positions_view["byteOffset"] = part.vertex_offset;
      positions_view["byteLength"] = part.index_offset - part.vertex_offset;
      positions_view["target"] = 34962;  // ARRAY_BUFFER
      json indices_view;
      indices_view["buffer"] = 0;
      indices_view["byteOffset"] = part.index_offset;
      indices_view["byteLength"] = 4 * part.index_count;
      indices_view["target"] = 34963;  // ELEMENT_ARRAY_BUFFER
      buffer_views.push_back(positions_view);
      buffer_views.push_back(indices_view);

      json positions;
      positions["bufferView"] = 2 * k;
      positions["componentType"] = 5126;  // FLOAT
      positions["count"] = part.vertex_count;
      positions["type"] = "VEC3";
      positions["min"] = json::array({part.lo[0], part.lo[1], part.lo[2]});
      positions["max"] = json::array({part.hi[0], part.hi[1], part.hi[2]});
      json indices;
      indices["bufferView"] = 2 * k + 1;
      indices["componentType"] = 5125;  // UNSIGNED_INT
      indices["count"] = part.index_count;
      indices["type"] = "SCALAR";
      accessors.push_back(positions);
      accessors.push_back(indices);

      json primitive;
      primitive["attributes"]["POSITION"] = 2 * k;
      primitive["indices"] = 2 * k + 1;
      primitive["mode"] = 4;  // TRIANGLES
      if (part.mesh == meshes.size()) meshes.push_back({{"primitives", json::array()}});
      meshes[part.mesh]["primitives"].push_back(primitive);
    }
    for (std::size_t m = 0; m < mesh_names_.size(); ++m) {
      nodes.push_back({{"mesh", m}, {"name", mesh_names_[m]}});
      scene["nodes"].push_back(m);
    }
    if (parts_.empty()) {
      // A file with no geometry is still valid glTF: one empty scene, no node, mesh or buffer
      // (the schema forbids empty top-level arrays).
      document["scenes"] = json::array({json::object()});
    } else {
      document["scenes"] = json::array({scene});
      document["nodes"] = nodes;
      document["meshes"] = meshes;
      document["accessors"] = accessors;
      document["bufferViews"] = buffer_views;
      json buffer;
      buffer["byteLength"] = buffer_.size();
      if (!binary_) buffer["uri"] = "data:application/octet-stream;base64," + base64(buffer_);
      document["buffers"] = json::array({buffer});
    }
    std::string text = document.dump();
    if (!binary_) {
      output_.write(text);
      output_.write("\n");
      return;
    }
    while (text.size() % 4 != 0) text.push_back(' ');
    while (buffer_.size() % 4 != 0) buffer_.push_back(0);
    const bool has_binary = !buffer_.empty();
    const std::uint64_t total = 12 + 8 + text.size() + (has_binary ? 8 + buffer_.size() : 0);
    if (total > std::numeric_limits<std::uint32_t>::max()) {
      throw InputError("writing '" + path_.string() + "': " + std::to_string(total) +
                       " bytes are more than a GLB file can hold (4 GiB)");
    }
    const std::uint32_t header[3] = {0x46546C67u, 2u,
                                     static_cast<std::uint32_t>(total)};  // "glTF", v2
    output_.write(header, sizeof header);
    const std::uint32_t json_chunk[2] = {static_cast<std::uint32_t>(text.size()), 0x4E4F534Au};
    output_.write(json_chunk, sizeof json_chunk);
    output_.write(text);
    if (has_binary) {
      const std::uint32_t binary_chunk[2] = {static_cast<std::uint32_t>(buffer_.size()),
                                             0x004E4942u};
      output_.write(binary_chunk, sizeof binary_chunk);
      output_.write(buffer_.data(), buffer_.size());
    }
  }

 private:
  // One primitive: a call of add_part with triangles.
  struct Part {
    std::size_t mesh = 0;
    std::size_t vertex_offset = 0;
    std::size_t vertex_count = 0;
    std::size_t index_offset = 0;
    std::size_t index_count = 0;
    std::array<float, 3> lo{std::numeric_limits<float>::max(), std::numeric_limits<float>::max(),
                            std::numeric_limits<float>::max()};
    std::array<float, 3> hi{std::numeric_limits<float>::lowest(),
                            std::numeric_limits<float>::lowest(),
                            std::numeric_limits<float>::lowest()};
  };

  void append(const void* data, std::size_t size) {
    const auto* bytes = static_cast<const unsigned char*>(data);
    buffer_.insert(buffer_.end(), bytes, bytes + size);
  }

  static constexpr std::size_t none = std::numeric_limits<std::size_t>::max();

  bool binary_;
  std::vector<unsigned char> buffer_;
  std::vector<Part> parts_;
  std::vector<std::string> mesh_names_;  ///< one node per mesh, named by its part
  std::string name_;                     ///< the part being added
  std::size_t mesh_ = none;              ///< its mesh, once it has triangles
};

// An assembly: each part in its own binary PLY in "<stem>.parts/", listed by a JSON manifest
// (formats/Manifest.h) that preprocess reads one part at a time. The part files go to a
// temporary folder that commit() renames before it renames the manifest.
class ManifestWriter final : public MeshWriter::Impl {
 public:
  ManifestWriter(const std::filesystem::path& path, std::string length_unit)
      : Impl(path),
        length_unit_(length_unit.empty() ? "m" : std::move(length_unit)),
        folder_name_(path.stem().string() + ".parts"),
        final_folder_(path.parent_path() / folder_name_),
        temporary_folder_(temporary_path(final_folder_)) {
    metres_per_unit(length_unit_);  // an unknown unit is an InputError naming it
    // Impl's OutputFile checked the part folder (check_outputs): it holds part files alone.
    std::error_code error;
    std::filesystem::remove_all(temporary_folder_, error);
    if (!std::filesystem::create_directories(temporary_folder_, error) && error)
      throw IoError("cannot create the part folder '" + temporary_folder_.string() + "': " + error.message());
  }
  ~ManifestWriter() override {
    std::error_code ignored;
    current_.reset();  // its temporaries first
    if (!committed()) std::filesystem::remove_all(temporary_folder_, ignored);
  }

  void add_part(std::span<const Vec3> part_vertices,
                std::span<const TriangleIndices> part_triangles, const Label& label) override {
    if (!label.continues || !current_) {
      if (current_) current_->commit();
      char file[32];
      std::snprintf(file, sizeof file, "part-%06zu.ply", files_.size());
      current_ = std::make_unique<MeshWriter>(temporary_folder_ / file);
      files_.push_back(file);
      names_.push_back(manifest_name(label, std::filesystem::path(file).stem().string()));
    }
    if (current_->parts_written() == 0) {
      current_->add_part(part_vertices, part_triangles);
    } else {
      current_->extend_part(part_vertices, part_triangles);
    }
  }

  void finish() override {
    if (current_) current_->commit();
    current_.reset();  // removes its side files before the folder moves
    nlohmann::ordered_json manifest;
    manifest["units"] = length_unit_;
    auto& list = manifest["parts"] = nlohmann::ordered_json::array();
    for (std::size_t k = 0; k < files_.size(); ++k)
      list.push_back({{"name", names_[k]}, {"file", folder_name_ + "/" + files_[k]}});
    output_.write(manifest.dump(1) + "\n");
    std::error_code error;
    std::filesystem::remove_all(final_folder_, error);
    std::filesystem::rename(temporary_folder_, final_folder_, error);
    if (error)
      throw IoError("cannot rename '" + temporary_folder_.string() + "' to '" + final_folder_.string() +
                    "': " + error.message());
  }

 private:
  // The part's path (unique in a soup; a manifest's names must be), else its name, else its
  // file's; "#2", "#3", ... where one repeats.
  std::string manifest_name(const Label& label, std::string fallback) {
    std::string name = !label.path.empty()   ? std::string(label.path)
                       : !label.name.empty() ? std::string(label.name)
                                             : std::move(fallback);
    const std::string original = name;
    for (int k = 2; !used_names_.insert(name).second; ++k)
      name = original + "#" + std::to_string(k);
    return name;
  }

  std::string length_unit_;
  std::string folder_name_;
  std::filesystem::path final_folder_, temporary_folder_;
  std::unique_ptr<MeshWriter> current_;  ///< the part file being written
  std::vector<std::string> files_, names_;
  std::set<std::string> used_names_;
};

}  // namespace

bool can_write_mesh(const std::filesystem::path& path) {
  const std::string extension = detail::lower_extension(path);
  for (const char* writable : {".obj", ".stl", ".ply", ".off", ".gltf", ".glb", ".json"}) {
    if (extension == writable) return true;
  }
  return false;
}

MeshWriter::MeshWriter(const std::filesystem::path& path, std::string length_unit) {
  const std::string extension = detail::lower_extension(path);
  if (extension == ".obj") {
    impl_ = std::make_unique<ObjWriter>(path);
  } else if (extension == ".stl") {
    impl_ = std::make_unique<StlWriter>(path);
  } else if (extension == ".ply") {
    impl_ = std::make_unique<PlyWriter>(path);
  } else if (extension == ".off") {
    impl_ = std::make_unique<OffWriter>(path);
  } else if (extension == ".gltf" || extension == ".glb") {
    impl_ = std::make_unique<GltfWriter>(path, extension == ".glb");
  } else if (extension == ".json") {
    impl_ = std::make_unique<ManifestWriter>(path, std::move(length_unit));
  } else {
    throw InputError("'" + path.string() + "': cannot write meshes with the extension '" +
                     extension + "' (writable: .obj, .stl, .ply, .off, .gltf, .glb, and .json: a manifest of parts)");
  }
}

MeshWriter::~MeshWriter() = default;

void MeshWriter::add_part(std::span<const Vec3> vertices,
                          std::span<const TriangleIndices> triangles, std::string_view name,
                          std::string_view path) {
  if (impl_->committed()) {
    throw InputError("'" + impl_->path().string() + "': add_part after commit");
  }
  check_part(impl_->path(), vertices, triangles);
  // An unnamed part after the first needs a name, or a reader would merge it with the one
  // before (OBJ) or name both by the file's stem (PLY).
  const std::string fallback =
      name.empty() && impl_->parts > 0 ? "part" + std::to_string(impl_->parts) : std::string();
  if (!fallback.empty()) name = fallback;
  if (path == name) path = {};
  impl_->add_part(vertices, triangles, {name, path, false});
  impl_->vertices += vertices.size();
  impl_->triangles += triangles.size();
  ++impl_->parts;
}

void MeshWriter::extend_part(std::span<const Vec3> vertices,
                             std::span<const TriangleIndices> triangles) {
  if (impl_->committed() || impl_->parts == 0) {
    throw InputError("'" + impl_->path().string() + "': extend_part " +
                     (impl_->parts == 0 ? "before add_part" : "after commit"));
  }
  check_part(impl_->path(), vertices, triangles);
  impl_->add_part(vertices, triangles, {{}, {}, true});
  impl_->vertices += vertices.size();
  impl_->triangles += triangles.size();
}

void MeshWriter::commit() {
  impl_->commit();
}

std::uint64_t MeshWriter::triangles_written() const {
  return impl_->triangles;
}
std::uint64_t MeshWriter::vertices_written() const {
  return impl_->vertices;
}
std::uint64_t MeshWriter::parts_written() const {
  return impl_->parts;
}

bool mesh_format_keeps_parts(const std::filesystem::path& path) {
  const std::string extension = detail::lower_extension(path);
  return extension != ".stl" && extension != ".off";
}

namespace {

// The soup's triangles grouped by part, in order within a part (a counting sort): part p's
// are by_part[first[p] .. first[p + 1]).
struct PartOrder {
  std::vector<std::size_t> first, by_part;
};

PartOrder order_by_part(const std::filesystem::path& path, const TriangleSoup& soup) {
  if (soup.part_of.size() != soup.triangles.size()) {
    throw InputError("writing '" + path.string() + "': the soup has " +
                     std::to_string(soup.triangles.size()) + " triangles but " +
                     std::to_string(soup.part_of.size()) + " part ids");
  }
  PartOrder order;
  order.first.assign(soup.part_count() + 1, 0);
  for (const auto part : soup.part_of) {
    if (part >= soup.part_count()) {
      throw InputError("writing '" + path.string() + "': part id " + std::to_string(part) +
                       " but the soup has " + std::to_string(soup.part_count()) + " parts");
    }
    ++order.first[part + 1];
  }
  for (std::size_t p = 0; p < soup.part_count(); ++p) order.first[p + 1] += order.first[p];
  order.by_part.resize(soup.triangles.size());
  std::vector<std::size_t> next(order.first.begin(), order.first.end() - 1);
  for (std::size_t t = 0; t < soup.triangles.size(); ++t)
    order.by_part[next[soup.part_of[t]]++] = t;
  return order;
}

std::string_view path_of(const TriangleSoup& soup, std::size_t part) {
  return soup.part_paths.empty() ? std::string_view() : std::string_view(soup.part_paths[part]);
}

}  // namespace

void write_mesh(const std::filesystem::path& path, const TriangleSoup& soup,
                std::string length_unit) {
  MeshWriter writer(path, std::move(length_unit));
  if (soup.part_count() <= 1) {
    if (soup.part_count() == 1) {
      writer.add_part(soup.vertices, soup.triangles, soup.part_names[0], path_of(soup, 0));
    } else {
      writer.add_part(soup.vertices, soup.triangles);
    }
    writer.commit();
    return;
  }
  const PartOrder order = order_by_part(path, soup);
  // Each part with the vertices its triangles use, in first-use order.
  constexpr std::uint32_t unused = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> local(soup.vertices.size(), unused);
  std::vector<std::uint32_t> used;
  std::vector<Vec3> part_vertices;
  std::vector<TriangleIndices> part_triangles;
  for (std::size_t part = 0; part < soup.part_count(); ++part) {
    part_vertices.clear();
    part_triangles.clear();
    used.clear();
    for (std::size_t i = order.first[part]; i < order.first[part + 1]; ++i) {
      const std::size_t t = order.by_part[i];
      TriangleIndices triangle{};
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t global = soup.triangles[t][k];
        if (global >= soup.vertices.size()) {
          throw InputError("writing '" + path.string() + "': triangle " + std::to_string(t) +
                           " uses vertex " + std::to_string(global) + " but the soup has " +
                           std::to_string(soup.vertices.size()));
        }
        if (local[global] == unused) {
          local[global] = static_cast<std::uint32_t>(part_vertices.size());
          part_vertices.push_back(soup.vertices[global]);
          used.push_back(global);
        }
        triangle[k] = local[global];
      }
      part_triangles.push_back(triangle);
    }
    for (const auto global : used) local[global] = unused;
    writer.add_part(part_vertices, part_triangles, soup.part_names[part], path_of(soup, part));
  }
  writer.commit();
}

}  // namespace tetrapage
