// read_mesh: picks the reader by extension, times it and fills the report; the degenerate
// filter every reader shares (SoupBuilder::finish).

#include "tetrapage/formats/mesh/MeshReader.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <chrono>

#include "CadModule.h"
#include "GltfDocument.h"
#include "PathSupport.h"
#include "ReaderSupport.h"
#include "tetrapage/formats/base/DeterminantFilter.h"
#include "tetrapage/formats/mesh/FileChecks.h"
#include "tetrapage/formats/mesh/Manifest.h"
#include "tetrapage/formats/mesh/TessellatedFile.h"

namespace tetrapage {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;

}  // namespace

MeshFormat mesh_format_from_path(const std::filesystem::path& path) {
  const std::string extension = detail::lower_extension(path);
  if (extension == ".obj") return MeshFormat::obj;
  if (extension == ".stl") return MeshFormat::stl;
  if (extension == ".ply") return MeshFormat::ply;
  if (extension == ".off") return MeshFormat::off;
  if (extension == ".gltf") return MeshFormat::gltf;
  if (extension == ".glb") return MeshFormat::glb;
  // Before Assimp, whose IFC importer claims .stp and refuses every other STEP schema.
  if (extension == ".iges" || extension == ".igs") return MeshFormat::iges;
  if (is_cad_path(path)) return MeshFormat::step;
  if (extension.size() > 1 && detail::cad_module(path).assimp_imports(extension))
    return MeshFormat::assimp_other;
  throw InputError("'" + path.string() + "': no mesh reader for the extension '" + extension +
                   "' (readable: .obj, .stl, .ply, .off, .gltf, .glb, STEP (.step, .stp), IGES "
                   "(.iges, .igs) and the formats Assimp imports)");
}

bool is_degenerate_triangle(const Vec3& a, const Vec3& b, const Vec3& c) {
  // Not collinear when one projection of (b - a) x (c - a) is certainly nonzero: orient2d's
  // filter, a few nanoseconds. CGAL's own (interval arithmetic, which switches the rounding
  // mode) was a fiftieth of the preprocess's CPU; it now decides only the close calls.
  for (int axis = 0; axis < 3; ++axis) {
    const int i = axis == 2 ? 0 : axis + 1, j = axis == 0 ? 2 : axis - 1;
    const double ux = b[i] - a[i], uy = b[j] - a[j], vx = c[i] - a[i], vy = c[j] - a[j];
    const double left = ux * vy, right = uy * vx;
    if (detail::filter_accepts(std::fabs(left - right), detail::kOrient2dRelativeBound,
                               std::fabs(left) + std::fabs(right), 2))
      return false;
  }
  return CGAL::collinear(Kernel::Point_3(a[0], a[1], a[2]), Kernel::Point_3(b[0], b[1], b[2]),
                         Kernel::Point_3(c[0], c[1], c[2]));
}

namespace detail {

bool SoupBuilder::drop_if_degenerate(std::size_t t, std::uint64_t position) {
  const auto& tri = soup_.triangles[t];
  const bool repeated = tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2];
  if (!repeated && !is_degenerate_triangle(vertex(tri[0]), vertex(tri[1]), vertex(tri[2])))
    return false;
  ++report_.degenerate_dropped;
  if (chunks_ == nullptr || chunks_->keep_dropped_positions)
    report_.dropped_positions.push_back(position);
  return true;
}

void SoupBuilder::throw_no_triangle_left() const {
  if (report_.triangles_read == 0) throw InputError(file_name_ + ": the mesh has no triangle");
  throw InputError(file_name_ + ": no triangle left after dropping " +
                   std::to_string(report_.degenerate_dropped) + " degenerate triangles");
}

void SoupBuilder::hand_over_chunk() {
  // The chunk's vertices numbered as its kept triangles first use them: an open-addressing map
  // from the file's vertex to the chunk's, at most half full (a table of the file's vertices
  // would hold 4 B each whatever the budget).
  constexpr std::uint32_t kEmpty = 0xffffffffu;
  std::size_t slots = 16;
  while (slots < 6 * soup_.triangles.size()) slots *= 2;
  chunk_map_.assign(slots, {kEmpty, 0});
  TriangleSoup chunk;
  chunk.triangles.reserve(soup_.triangles.size());
  chunk.part_of.reserve(soup_.triangles.size());
  for (std::size_t t = 0; t < soup_.triangles.size(); ++t) {
    if (drop_if_degenerate(t, triangles_before_ + t)) continue;
    TriangleIndices local{};
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = soup_.triangles[t][k];
      std::size_t slot = (std::uint64_t(v) * 0x9e3779b97f4a7c15ULL >> 20) & (slots - 1);
      while (chunk_map_[slot].first != kEmpty && chunk_map_[slot].first != v) slot = (slot + 1) & (slots - 1);
      if (chunk_map_[slot].first == kEmpty) {
        chunk_map_[slot] = {v, std::uint32_t(chunk.vertices.size())};
        chunk.vertices.push_back(vertex(v));
      }
      local[k] = chunk_map_[slot].second;
    }
    chunk.triangles.push_back(local);
    chunk.part_of.push_back(soup_.part_of[t]);
  }
  triangles_before_ += soup_.triangles.size();
  kept_before_ += chunk.triangles.size();
  soup_.triangles.clear();
  soup_.part_of.clear();
  if (vertices_unshared_) {
    vertex_base_ += table_.size();
    table_.clear();
  }
  if (!chunk.triangles.empty()) chunks_->take(std::move(chunk));
}

TriangleSoup SoupBuilder::finish() {
  if (chunks_ != nullptr) {
    hand_over_chunk();
    if (kept_before_ == 0) throw_no_triangle_left();
    TriangleSoup parts;
    parts.part_names = std::move(soup_.part_names);
    parts.part_paths = std::move(soup_.part_paths);
    return parts;
  }
  auto& triangles = soup_.triangles;
  auto& part_of = soup_.part_of;
  std::size_t kept = 0;
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    if (drop_if_degenerate(t, t)) continue;
    triangles[kept] = triangles[t];
    part_of[kept] = part_of[t];
    ++kept;
  }
  triangles.resize(kept);
  part_of.resize(kept);
  if (kept == 0) throw_no_triangle_left();
  triangles.shrink_to_fit();
  part_of.shrink_to_fit();
  soup_.vertices.shrink_to_fit();
  return std::move(soup_);
}

}  // namespace detail

std::uint64_t triangle_position(const ReadReport& report, std::uint64_t id) {
  // Ascending positions: each one at or before the candidate pushes it one further.
  std::uint64_t position = id;
  for (const std::uint64_t dropped : report.dropped_positions) {
    if (dropped > position) break;
    ++position;
  }
  return position;
}

namespace {

using OwnReader = TriangleSoup (*)(detail::InputFile&, ReadReport&, const SoupChunks*);

TriangleSoup read_with(OwnReader reader, const std::filesystem::path& path, const char* format,
                       ReadReport& report, const SoupChunks* chunks = nullptr) {
  detail::InputFile file(path);
  report.bytes = file.size();
  report.format = format;
  return reader(file, report, chunks);
}

std::uint64_t file_size_or_zero(const std::filesystem::path& path) {
  std::error_code error;
  const auto size = std::filesystem::file_size(path, error);
  return error ? 0 : size;
}

}  // namespace

namespace {

// The block a reader reads through (InputFile) and the heap's slack around it.
constexpr std::uint64_t kReadBlockBytes = std::uint64_t(8) << 20;

// Formats whose size is all that is cheap to know: the fewest file bytes a triangle took in the
// files measured, and the vertex entries a triangle brings. OBJ: 28 B (a 20k-triangle terrain
// of ours took 33, a 1M one 52); ASCII STL: 100 B a facet (6 significant digits took 124);
// glTF: float vertices shared by two triangles and uint32 indices, 18 B (base64 in a .gltf, 24).
struct SizeRule {
  std::uint64_t bytes_per_triangle;
  std::uint64_t vertices_per_two_triangles;
};
SizeRule size_rule(MeshFormat format) {
  switch (format) {
    case MeshFormat::obj:
      return {28, 1};
    case MeshFormat::stl:
      return {100, 6};
    case MeshFormat::gltf:
      return {24, 1};
    default:
      return {18, 1};
  }
}

// The counts a header states; false when the format has none or the header cannot be read.
bool header_counts(const std::filesystem::path& path, MeshFormat format, MeshReadEstimate& out) {
  try {
    detail::InputFile file(path, std::size_t(64) << 10);
    detail::MeshCounts counts;
    if (format == MeshFormat::ply) {
      counts = detail::read_ply_counts(file);
    } else if (format == MeshFormat::off) {
      counts = detail::read_off_counts(file);
    } else if (format == MeshFormat::stl) {
      const std::optional<std::uint64_t> triangles = detail::binary_stl_count(file);
      if (!triangles) return false;  // ASCII: estimated from its size
      counts.triangles = counts.faces = *triangles;
      counts.vertices = 3 * counts.triangles;
    } else {
      return false;
    }
    out.vertices = counts.vertices;
    out.triangles = counts.triangles;
    // Arrays reserved from the counts; polygons grow the triangles' (old and new while
    // growing), else the degenerate filter's shrink copies them.
    out.reading_bytes = out.soup_bytes() + (counts.triangles > counts.faces ? 16 : 12) * counts.triangles;
    out.counted = true;
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

// A glTF our reader reads: its placed counts from the JSON. It holds the JSON's text and its
// document while parsing it (GltfDocument::parse_bytes, told by the text's shape), the walk's
// stack and placed nodes (272 B a node), with its tables and decoded data URIs, which stay, and
// a block of the buffer beside the soup, or, in chunks, beside the vertex table and a chunk. A JSON whose
// document alone would pass kLargestParsed is not parsed here: estimated by its size, its parse
// bytes say what reading it needs. False when Assimp reads the file or the JSON cannot be read
// (its read says why).
constexpr std::uint64_t kLargestParsed = std::uint64_t(1) << 30;
bool gltf_counts(const std::filesystem::path& path, MeshReadEstimate& out) {
  try {
    if (detail::gltf_parse_bytes(path) > kLargestParsed) return false;
    const detail::GltfDocument document = detail::read_gltf_document(path, false);
    if (!document.needs_assimp.empty()) return false;
    const detail::GltfCounts counts = detail::count_placed(document);
    out.vertices = counts.vertices;
    out.triangles = counts.triangles;
    out.counted = true;
    const std::uint64_t parse = document.parse_bytes + 272 * document.node_count;
    const std::uint64_t held = parse + detail::held_bytes(document) + counts.embedded_bytes + kReadBlockBytes;
    // Reserved from the counts up to a third (vertices) and a quarter (triangles) of the bytes
    // stored (counts may lie); more (a mesh placed many times) grows, old and new arrays
    // together; the degenerate filter's shrink copies the triangles (16 B each with parts).
    const bool grows = counts.vertices > counts.stored_bytes / 3 || counts.triangles > counts.stored_bytes / 4;
    const std::uint64_t growth = grows ? 2 : 1;
    out.reading_bytes = growth * out.soup_bytes() + 16 * counts.triangles + held;
    out.chunked = true;
    out.chunked_bytes = held;
    out.vertex_table_bytes = growth * 24 * counts.vertices;
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace

MeshReadEstimate estimate_mesh_read(const std::filesystem::path& path) noexcept {
  MeshReadEstimate out;
  MeshFormat format{};
  try {
    format = mesh_format_from_path(path);
  } catch (const Error&) {
    return out;
  }
  if (format == MeshFormat::step || format == MeshFormat::iges) {
    out.cad = true;
    return out;
  }
  const std::uint64_t bytes = file_size_or_zero(path);
  const bool gltf = format == MeshFormat::gltf || format == MeshFormat::glb;
  if (gltf && gltf_counts(path, out)) return out;
  if (!header_counts(path, format, out)) {
    const SizeRule rule = size_rule(format);
    out.triangles = bytes / rule.bytes_per_triangle + 1;
    out.vertices = (out.triangles * rule.vertices_per_two_triangles + 1) / 2;
    // Arrays grown as the file is read: each at twice its size while it grows.
    out.reading_bytes = 2 * out.soup_bytes();
  }
  out.reading_bytes += kReadBlockBytes;
  if (format == MeshFormat::obj || format == MeshFormat::stl || format == MeshFormat::ply ||
      format == MeshFormat::off) {
    out.chunked = true;
    // The vertex table (an STL's: a chunk's), reserved from a header's count, else grown.
    const std::uint64_t table = format == MeshFormat::stl ? 0 : 24 * out.vertices;
    out.chunked_bytes = kReadBlockBytes;
    out.vertex_table_bytes = out.counted ? table : 2 * table;
  }
  const bool assimp = format == MeshFormat::gltf || format == MeshFormat::glb ||
                      format == MeshFormat::assimp_other;
  // Assimp's scene beside the soup: float vertices, faces and their index arrays, the file's
  // buffers (a 1M-triangle GLB peaked 73 MiB with its components).
  if (assimp) out.reading_bytes += 12 * out.vertices + 32 * out.triangles + bytes;
  // A glTF's JSON parsed (by our reader or Assimp's: at least nlohmann's document).
  if (gltf) out.reading_bytes += detail::gltf_parse_bytes(path);
  return out;
}

namespace {

// The reader for the file's format, timed into the report. With `chunks`, our own readers hand
// their triangles over and return the parts alone; the others return the whole soup.
TriangleSoup read_mesh_file(const std::filesystem::path& path, ReadReport* report,
                            const TessellationOptions& tessellation, const SoupChunks* chunks) {
  const auto start = std::chrono::steady_clock::now();
  ReadReport local;
  ReadReport& out = report != nullptr ? *report : local;
  out = ReadReport{};
  out.path = path.string();
  TriangleSoup soup;
  switch (mesh_format_from_path(path)) {
    case MeshFormat::obj:
      soup = read_with(detail::read_obj, path, "obj", out, chunks);
      break;
    case MeshFormat::stl:
      soup = read_with(detail::read_stl, path, "stl", out, chunks);
      break;
    case MeshFormat::ply:
      soup = read_with(detail::read_ply, path, "ply", out, chunks);
      break;
    case MeshFormat::off:
      soup = read_with(detail::read_off, path, "off", out, chunks);
      break;
    case MeshFormat::gltf:
    case MeshFormat::glb:
      out.bytes = file_size_or_zero(path);
      if (std::optional<TriangleSoup> own = detail::read_gltf(path, out, chunks)) {
        soup = std::move(*own);
      } else {
        soup = read_mesh_with_assimp(path, &out);
      }
      break;
    case MeshFormat::assimp_other:
      soup = read_mesh_with_assimp(path, &out);
      break;
    case MeshFormat::step:
    case MeshFormat::iges:
      if (chunks == nullptr) return read_cad(path, tessellation, &out);
      soup = TessellatedFile(path, tessellation, out).place_in_chunks(*chunks, out);
      break;
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return soup;
}

}  // namespace

TriangleSoup read_mesh(const std::filesystem::path& path, ReadReport* report,
                       const TessellationOptions& tessellation) {
  return read_mesh_file(path, report, tessellation, nullptr);
}

TriangleSoup read_mesh_in_chunks(const std::filesystem::path& path, ReadReport* report,
                                 const SoupChunks& chunks, const TessellationOptions& tessellation) {
  TriangleSoup soup = read_mesh_file(path, report, tessellation, &chunks);
  // Read whole (the formats of other libraries): handed over as one chunk.
  if (soup.triangle_count() > 0) return detail::hand_over_whole(std::move(soup), chunks);
  return soup;
}

void load_readers_for(std::span<const std::filesystem::path> inputs) {
  for (const std::filesystem::path& input : inputs) {
    std::vector<std::filesystem::path> files;
    try {
      files = files_read_from(input);
    } catch (const Error&) {
      continue;  // the read names what is wrong with it
    }
    for (const std::filesystem::path& file : files) {
      if (is_manifest_path(file)) continue;
      MeshFormat format{};
      try {
        format = mesh_format_from_path(file);
      } catch (const InputError&) {
        continue;
      }
      if (format != MeshFormat::obj && format != MeshFormat::stl && format != MeshFormat::ply &&
          format != MeshFormat::off)
        detail::cad_module(file);
    }
  }
}

TriangleSoup read_mesh_with_assimp(const std::filesystem::path& path, ReadReport* report) {
  const auto start = std::chrono::steady_clock::now();
  ReadReport local;
  ReadReport& out = report != nullptr ? *report : local;
  out = ReadReport{};
  out.path = path.string();
  const std::string extension = detail::lower_extension(path);
  out.format = "assimp:" + (extension.empty() ? std::string() : extension.substr(1));
  out.bytes = file_size_or_zero(path);
  TriangleSoup soup = detail::read_assimp(path, out);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return soup;
}

}  // namespace tetrapage
