// STEP and IGES: the file is checked and pre-scanned here, read and tessellated by the CAD
// module's OpenCASCADE half (in a child process unless told otherwise), and every instance is
// then placed in double by our own arithmetic (the placement a manifest uses), so that
// identical prototypes give bit-identical instances, whether placed whole or in chunks.

#include "tetrapage/formats/mesh/TessellatedFile.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "CadIsolation.h"
#include "CadModule.h"
#include "StepPrescan.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/FileChecks.h"
#include "tetrapage/formats/mesh/Manifest.h"

namespace tetrapage {
namespace {

using detail::CadContent;
using detail::ShapeInstance;
using detail::TessellatedShape;

void check_options(const std::string& file, const TessellationOptions& options) {
  if (!(options.deflection > 0) || !std::isfinite(options.deflection))
    throw InputError(file + ": the deflection must be a positive number, not " +
                     std::to_string(options.deflection));
  if (!(options.angular_deflection > 0) || !(options.angular_deflection <= 3.14159265358979))
    throw InputError(file + ": the angular deflection must be in (0, pi] radians, not " +
                     std::to_string(options.angular_deflection));
}

// A FIFO or device would block OCCT's open forever, or feed it endless bytes.
std::uint64_t checked_file_size(const std::filesystem::path& path) {
  require_regular_file(path);
  std::error_code error;
  const auto bytes = std::filesystem::file_size(path, error);
  std::ifstream probe(path, std::ios::binary);
  if (error || !probe) throw IoError(path.string() + ": cannot open the file");
  return bytes;
}

// The module's read, in a child process: OCCT's crash, hang or runaway allocation ends the
// child only. The module is loaded here, before fork(), never in the child.
CadContent read_isolated(const std::filesystem::path& path, const TessellationOptions& options) {
  const detail::CadModule& module = detail::cad_module(path);
  // The child cannot use TBB's workers: it runs as many threads of its own.
  const unsigned threads = unsigned(std::max(1, tbb::this_task_arena::max_concurrency()));
  const detail::IsolationLimits limits{options.memory_limit, options.time_limit};
  return detail::read_in_child(path.string(), limits,
                               [&] { return module.read_occt_content(path, options, threads); });
}

bool flattened(const std::vector<Vec3>& placed, const TriangleIndices& t) {
  return t[0] == t[1] || t[1] == t[2] || t[0] == t[2] ||
         is_degenerate_triangle(placed[t[0]], placed[t[1]], placed[t[2]]);
}

// A chunk of placed instances being filled: each triangle's corners numbered in the chunk as
// they are first used. A prototype vertex's slot holds while its stamp is the current one; the
// stamp moves on with each instance and each chunk, so that neither clears the tables.
class ChunkFiller {
 public:
  explicit ChunkFiller(const SoupChunks& chunks) : chunks_(chunks) {}

  void begin_instance(std::size_t prototype_vertices) {
    if (stamp_of_.size() < prototype_vertices) {
      stamp_of_.resize(prototype_vertices, 0);
      slot_.resize(prototype_vertices);
    }
    ++stamp_;
  }

  void add(const std::vector<Vec3>& placed, const TriangleIndices& t, std::uint32_t part) {
    TriangleIndices corners{};
    for (int k = 0; k < 3; ++k) {
      if (stamp_of_[t[k]] != stamp_) {
        stamp_of_[t[k]] = stamp_;
        slot_[t[k]] = std::uint32_t(chunk_.vertices.size());
        chunk_.vertices.push_back(placed[t[k]]);
      }
      corners[k] = slot_[t[k]];
    }
    chunk_.triangles.push_back(corners);
    chunk_.part_of.push_back(part);
    if (chunk_.triangles.size() >= std::max<std::size_t>(chunks_.triangles, 1)) hand_over();
  }

  void hand_over() {
    if (chunk_.triangles.empty()) return;
    chunks_.take(std::move(chunk_));
    chunk_ = TriangleSoup{};
    ++stamp_;  // the instance's vertices go again with the next chunk
  }

 private:
  const SoupChunks& chunks_;
  TriangleSoup chunk_;
  std::vector<std::uint32_t> slot_;
  std::vector<std::uint64_t> stamp_of_;  // 64 bits: instances and chunks never wrap it
  std::uint64_t stamp_ = 0;
};

}  // namespace

struct TessellatedFile::Impl {
  std::string file;
  TessellationOptions options;
  CadContent content;

  // Places each instance in order that has triangles (a part each): `begin(part, placed)` with
  // its vertices placed, then `keep(part, placed, t)` for each of its triangles the placement
  // does not flatten (those are counted as dropped); instances of a shape that failed are
  // skipped (and listed in the report) or fail. Returns the triangles kept.
  template <class Begin, class Keep>
  std::uint64_t place_each(TriangleSoup& parts, ReadReport& report, Begin&& begin,
                           Keep&& keep) const {
    std::vector<Vec3> placed;
    std::uint64_t kept = 0;
    for (const ShapeInstance& instance : content.instances) {
      const TessellatedShape& prototype = content.shapes[instance.shape];
      if (prototype.refused)
        throw InputError(file + ": part '" + instance.path + "' (" + prototype.name + ") " +
                         prototype.error);
      if (!prototype.error.empty()) {
        if (!options.skip_bad_parts)
          throw InputError(file + ": part '" + instance.path + "' (" + prototype.name +
                           ") failed to tessellate: " + prototype.error +
                           " (--skip-bad-parts leaves it out)");
        report.skipped_parts.push_back(instance.path + ": " + prototype.error);
        continue;
      }
      if (prototype.triangles.empty()) continue;
      placed.resize(prototype.vertices.size());
      for (std::size_t v = 0; v < placed.size(); ++v)
        placed[v] = apply_transform(instance.placement, prototype.vertices[v]);
      report.tessellation_deflection =
          std::max(report.tessellation_deflection,
                   prototype.deflection * largest_stretch(instance.placement));
      const std::uint32_t part = parts.add_part(prototype.name, instance.path);
      begin(part, placed);
      for (const TriangleIndices& t : prototype.triangles) {
        ++report.triangles_read;
        if (flattened(placed, t)) {
          ++report.degenerate_dropped;
          continue;
        }
        keep(part, placed, t);
        ++kept;
      }
    }
    if (kept == 0) throw InputError(file + ": no triangle (no shape with faces was tessellated)");
    return kept;
  }
};
TessellatedFile::TessellatedFile(const std::filesystem::path& path,
                                 const TessellationOptions& options, ReadReport& report)
    : impl_(std::make_unique<Impl>()) {
  report = ReadReport{};
  report.path = path.string();
  report.format = detail::is_iges_path(path) ? "iges" : "step";
  impl_->file = path.string();
  impl_->options = options;
  check_options(impl_->file, options);
  report.bytes = checked_file_size(path);
  if (!detail::is_iges_path(path))
    detail::check_step_structure(path, detail::scan_step_structure(path), options.max_occurrences);
  impl_->content = options.isolate ? read_isolated(path, options)
                                   : detail::cad_module(path).read_occt_content(path, options, 0);
  report.length_unit = "mm";
  const std::uint64_t total = placed_triangles();
  if (options.max_triangles != 0 && total > options.max_triangles)
    throw InputError(impl_->file + ": its " + std::to_string(impl_->content.instances.size()) +
                     " placed shapes make " + std::to_string(total) +
                     " triangles, more than the limit of " + std::to_string(options.max_triangles) +
                     " (a larger --deflection makes fewer; --max-cad-triangles raises the limit)");
}

TessellatedFile::~TessellatedFile() = default;
TessellatedFile::TessellatedFile(TessellatedFile&&) noexcept = default;
TessellatedFile& TessellatedFile::operator=(TessellatedFile&&) noexcept = default;

std::uint64_t TessellatedFile::placed_vertices() const {
  std::uint64_t vertices = 0;
  for (const ShapeInstance& instance : impl_->content.instances)
    vertices += impl_->content.shapes[instance.shape].vertices.size();
  return vertices;
}

std::uint64_t TessellatedFile::placed_triangles() const {
  std::uint64_t triangles = 0;
  for (const ShapeInstance& instance : impl_->content.instances)
    triangles += impl_->content.shapes[instance.shape].triangles.size();
  return triangles;
}

std::uint64_t TessellatedFile::held_bytes() const {
  std::uint64_t bytes = impl_->content.instances.size() * sizeof(ShapeInstance);
  for (const TessellatedShape& shape : impl_->content.shapes)
    bytes += sizeof(TessellatedShape) + shape.vertices.size() * sizeof(Vec3) +
             shape.triangles.size() * sizeof(TriangleIndices) + shape.name.size();
  for (const ShapeInstance& instance : impl_->content.instances) bytes += instance.path.size();
  return bytes;
}

std::uint64_t TessellatedFile::largest_shape_vertices() const {
  std::uint64_t largest = 0;
  for (const TessellatedShape& shape : impl_->content.shapes)
    largest = std::max<std::uint64_t>(largest, shape.vertices.size());
  return largest;
}

TriangleSoup TessellatedFile::place(ReadReport& report) const {
  TriangleSoup soup;
  // Sized once: grown, the arrays would hold up to twice the soup.
  soup.vertices.reserve(placed_vertices());
  soup.triangles.reserve(placed_triangles());
  soup.part_of.reserve(placed_triangles());
  std::uint32_t base = 0;
  const auto begin = [&](std::uint32_t part, const std::vector<Vec3>& placed) {
    if (soup.vertices.size() + placed.size() > std::numeric_limits<std::uint32_t>::max())
      throw InputError(impl_->file + ": more vertices than a soup can index at part '" +
                       soup.part_path(part) + "'");
    base = static_cast<std::uint32_t>(soup.vertices.size());
    soup.vertices.insert(soup.vertices.end(), placed.begin(), placed.end());
  };
  const auto keep = [&](std::uint32_t part, const std::vector<Vec3>&, const TriangleIndices& t) {
    soup.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    soup.part_of.push_back(part);
  };
  impl_->place_each(soup, report, begin, keep);
  return soup;
}

TriangleSoup TessellatedFile::place_in_chunks(const SoupChunks& chunks, ReadReport& report) const {
  TriangleSoup parts;
  ChunkFiller filler(chunks);
  const auto begin = [&](std::uint32_t, const std::vector<Vec3>& placed) {
    if (chunks.on_vertex)
      for (const Vec3& vertex : placed) chunks.on_vertex(vertex);
    filler.begin_instance(placed.size());
  };
  const auto keep = [&](std::uint32_t part, const std::vector<Vec3>& placed,
                        const TriangleIndices& t) { filler.add(placed, t, part); };
  impl_->place_each(parts, report, begin, keep);
  filler.hand_over();
  return parts;
}

}  // namespace tetrapage
