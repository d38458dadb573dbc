// glTF 2.0 (.gltf, .glb) read by our own reader: the scene's mesh nodes placed by their
// transforms (composed in double from the JSON's numbers), each triangle primitive's positions
// and indices read in order through a block of the buffer, so that a read in chunks holds the
// vertex table (which may spill) and a chunk, never the file. Assimp reads what this reader
// does not (GltfDocument::needs_assimp).

#include <optional>

#include "GltfDocument.h"
#include "ReaderSupport.h"
#include "tetrapage/formats/base/Error.h"

namespace tetrapage::detail {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kBlockBytes = std::size_t(1) << 20;

// A buffer's bytes, read through one block from its file (pread), or from memory.
class BufferReader {
 public:
  /// Reads from `buffer` now; bytes past `ahead_end` (within the buffer) are not read ahead.
  void select_buffer(const GltfBuffer& buffer, std::uint64_t ahead_end) {
    ahead_end_ = ahead_end;
    if (buffer_ == &buffer) return;
    buffer_ = &buffer;
    block_length_ = 0;
    file_.reset();
    if (!buffer.file.empty()) file_.emplace(buffer.file);
  }

  /// `size` bytes at `offset` of the buffer (the document checked they lie within it).
  const char* at(std::uint64_t offset, std::size_t size) {
    if (!file_) return buffer_->bytes.data() + offset;
    if (offset < block_start_ || offset + size > block_start_ + block_length_) fill(offset, size);
    return block_.data() + (offset - block_start_);
  }

 private:
  void fill(std::uint64_t offset, std::size_t size) {
    const std::uint64_t wanted =
        std::max<std::uint64_t>(size, std::min<std::uint64_t>(kBlockBytes, ahead_end_ - offset));
    block_.resize(static_cast<std::size_t>(wanted));
    file_->read_at(buffer_->file_offset + offset, block_.size(), block_.data());
    block_start_ = offset;
    block_length_ = wanted;
  }

  const GltfBuffer* buffer_ = nullptr;
  std::optional<ReadOnlyFile> file_;
  std::vector<char> block_;
  std::uint64_t block_start_ = 0, block_length_ = 0, ahead_end_ = 0;
};

// An accessor's elements in order, where each lies in its buffer (the document checked that
// they lie within its view, and set its stride).
class AccessorElements {
 public:
  AccessorElements(const GltfDocument& document, std::uint64_t accessor, std::size_t element_bytes,
                   BufferReader& reader)
      : accessor_(document.accessors[accessor]), reader_(reader), element_bytes_(element_bytes) {
    const GltfView& view = document.views[accessor_.view];
    first_ = view.offset + accessor_.offset;
    const std::uint64_t end =
        accessor_.count == 0 ? first_
                             : first_ + (accessor_.count - 1) * accessor_.stride + element_bytes;
    reader_.select_buffer(document.buffers[view.buffer], end);
  }
  std::uint64_t count() const { return accessor_.count; }
  const char* element(std::uint64_t i) {
    return reader_.at(first_ + i * accessor_.stride, element_bytes_);
  }

 private:
  const GltfAccessor& accessor_;
  BufferReader& reader_;
  std::size_t element_bytes_;
  std::uint64_t first_ = 0;
};

std::string accessor_where(const std::string& file, std::uint64_t accessor) {
  return file + ": accessor " + std::to_string(accessor);
}

// The positions of a primitive, placed, as vertices of the soup.
void add_positions(const GltfDocument& document, const GltfInstance& instance,
                   std::uint64_t accessor, BufferReader& reader, SoupBuilder& soup,
                   const std::string& file) {
  const std::string where = accessor_where(file, accessor);
  AccessorElements elements(document, accessor, 12, reader);
  const Transform& m = instance.transform;
  for (std::uint64_t v = 0; v < elements.count(); ++v) {
    const char* bytes = elements.element(v);
    const double x = load_scalar<float>(bytes, false), y = load_scalar<float>(bytes + 4, false),
                 z = load_scalar<float>(bytes + 8, false);
    const Vec3 p{m[0] * x + m[1] * y + m[2] * z + m[3], m[4] * x + m[5] * y + m[6] * z + m[7],
                 m[8] * x + m[9] * y + m[10] * z + m[11]};
    if (!is_finite(p))
      throw_not_finite(where + ": " + instance.name + " vertex " + std::to_string(v) + ": ", p);
    soup.add_vertex(p);
  }
}

// Each corner of a primitive (its indices, else 0, 1, 2, ...), range-checked, to `take`.
template <class Take>
void for_each_corner(const GltfDocument& document, const GltfPrimitive& primitive,
                     std::uint64_t vertices, BufferReader& reader, const std::string& file,
                     Take take) {
  if (!primitive.indices) {
    for (std::uint64_t v = 0; v < vertices; ++v) take(static_cast<std::uint32_t>(v));
    return;
  }
  const GltfAccessor& indices = document.accessors[*primitive.indices];
  const std::string where = accessor_where(file, *primitive.indices);
  const std::size_t size = index_bytes(indices.component_type);
  AccessorElements elements(document, *primitive.indices, size, reader);
  for (std::uint64_t i = 0; i < elements.count(); ++i) {
    const char* bytes = elements.element(i);
    const std::uint32_t index = size == 1 ? std::uint32_t(static_cast<unsigned char>(*bytes))
                                : size == 2
                                    ? std::uint32_t(load_scalar<std::uint16_t>(bytes, false))
                                    : load_scalar<std::uint32_t>(bytes, false);
    if (index >= vertices)
      throw InputError(where + ": index " + std::to_string(i) + " is " + std::to_string(index) +
                       ", out of range (" + std::to_string(vertices) + " vertices)");
    take(index);
  }
}

// The triangles of a primitive: a list, a strip (every other one turned, so that all keep the
// first's orientation) or a fan around its first corner.
void add_triangles(const GltfDocument& document, const GltfPrimitive& primitive, std::uint32_t base,
                   BufferReader& reader, SoupBuilder& soup, const std::string& file) {
  const std::uint64_t vertices = document.accessors[primitive.positions].count;
  std::uint32_t first = 0, previous = 0, last = 0;
  std::uint64_t corner = 0;
  for_each_corner(document, primitive, vertices, reader, file, [&](std::uint32_t v) {
    v += base;
    if (primitive.mode == 4) {
      if (corner % 3 == 2) soup.add_triangle(previous, last, v);
    } else if (corner >= 2) {
      if (primitive.mode == 6)
        soup.add_triangle(first, last, v);
      else if (corner % 2 == 0)
        soup.add_triangle(previous, last, v);
      else
        soup.add_triangle(last, previous, v);
    }
    if (corner == 0) first = v;
    previous = last;
    last = v;
    ++corner;
  });
}

}  // namespace

std::optional<TriangleSoup> read_gltf(const fs::path& path, ReadReport& report,
                                      const SoupChunks* chunks) {
  const GltfDocument document = read_gltf_document(path, true);
  if (!document.needs_assimp.empty()) return std::nullopt;
  report.format = document.binary ? "glb" : "gltf";
  const std::string file = path.string();
  SoupBuilder soup(file, report, chunks);
  const GltfCounts counts = count_placed(document);
  soup.reserve(counts.vertices, counts.triangles, counts.stored_bytes);
  BufferReader reader;
  for (const GltfInstance& instance : document.instances) {
    soup.begin_part(instance.name);
    for (const GltfPrimitive& primitive : document.meshes[instance.mesh].primitives) {
      const auto base = static_cast<std::uint32_t>(soup.vertex_count());
      add_positions(document, instance, primitive.positions, reader, soup, file);
      add_triangles(document, primitive, base, reader, soup, file);
    }
  }
  return soup.finish();
}

}  // namespace tetrapage::detail
