// STEP and IGES: the file is checked and pre-scanned here, read and tessellated by the CAD
// module's OpenCASCADE half (in a child process unless told otherwise), and every instance is
// then placed in double by our own arithmetic (the placement a manifest uses), so that
// identical prototypes give bit-identical instances.

#include "tetrapage/formats/CadReader.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>

#include "CadIsolation.h"
#include "CadModule.h"
#include "PathSupport.h"
#include "StepPrescan.h"
#include "tetrapage/formats/Error.h"
#include "tetrapage/formats/FileChecks.h"
#include "tetrapage/formats/Manifest.h"
#include "tetrapage/formats/MeshReader.h"

namespace tetrapage {
namespace {

using detail::CadContent;
using detail::ShapeInstance;
using detail::TessellatedShape;

// Every instance placed: a part each (instances of a shape that failed are skipped or fail).
// Refuses, before any is placed, instances whose triangles together exceed the limit.
void check_placed_triangles(const CadContent& content, const TessellationOptions& options,
                            const std::string& file) {
  std::uint64_t total = 0, vertices = 0;
  for (const ShapeInstance& instance : content.instances) {
    total += content.shapes[instance.shape].triangles.size();
    vertices += content.shapes[instance.shape].vertices.size();
  }
  if (options.before_placing) options.before_placing(vertices, total);
  if (options.max_triangles != 0 && total > options.max_triangles)
    throw InputError(file + ": its " + std::to_string(content.instances.size()) +
                     " placed shapes make " + std::to_string(total) +
                     " triangles, more than the limit of " + std::to_string(options.max_triangles) +
                     " (a larger --deflection makes fewer; --max-cad-triangles raises the limit)");
}

TriangleSoup place_instances(const CadContent& content, const TessellationOptions& options,
                             const std::string& file, ReadReport& report) {
  check_placed_triangles(content, options, file);
  TriangleSoup soup;
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
    if (soup.vertices.size() + prototype.vertices.size() >
        std::numeric_limits<std::uint32_t>::max())
      throw InputError(file + ": more vertices than a soup can index at part '" + instance.path +
                       "'");
    const std::uint32_t part = soup.add_part(prototype.name, instance.path);
    const auto base = static_cast<std::uint32_t>(soup.vertices.size());
    for (const Vec3& p : prototype.vertices)
      soup.vertices.push_back(apply_transform(instance.placement, p));
    report.tessellation_deflection = std::max(
        report.tessellation_deflection, prototype.deflection * largest_stretch(instance.placement));
    for (const TriangleIndices& t : prototype.triangles) {
      ++report.triangles_read;
      const TriangleIndices placed{t[0] + base, t[1] + base, t[2] + base};
      if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] ||
          is_degenerate_triangle(soup.vertices[placed[0]], soup.vertices[placed[1]],
                                 soup.vertices[placed[2]])) {
        ++report.degenerate_dropped;
        continue;
      }
      soup.triangles.push_back(placed);
      soup.part_of.push_back(part);
    }
  }
  return soup;
}

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

}  // namespace

namespace detail {

bool is_iges_path(const std::filesystem::path& path) {
  const std::string extension = lower_extension(path);
  return extension == ".iges" || extension == ".igs";
}

}  // namespace detail

void set_deflection(TessellationOptions& options, const std::string& text, std::string_view what) {
  std::string number = text;
  const bool relative = !number.empty() && number.back() == '%';
  if (relative) number.pop_back();
  std::size_t used = 0;
  double value = 0;
  try {
    value = std::stod(number, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != number.size() || number.empty() || !(value > 0) || !std::isfinite(value))
    throw InputError(std::string(what) + " '" + text +
                     "': expected a positive length (0.01) or percentage (0.1%)");
  options.relative_deflection = relative;
  options.deflection = relative ? value / 100 : value;
}

bool is_cad_path(const std::filesystem::path& path) {
  const std::string extension = detail::lower_extension(path);
  return extension == ".step" || extension == ".stp" || extension == ".p21" || detail::is_iges_path(path);
}

TriangleSoup read_cad(const std::filesystem::path& path, const TessellationOptions& options,
                      ReadReport* report) {
  const auto start = std::chrono::steady_clock::now();
  ReadReport local;
  ReadReport& out = report != nullptr ? *report : local;
  out = ReadReport{};
  out.path = path.string();
  out.format = detail::is_iges_path(path) ? "iges" : "step";
  const std::string file = path.string();
  check_options(file, options);
  out.bytes = checked_file_size(path);
  if (!detail::is_iges_path(path))
    detail::check_step_structure(path, detail::scan_step_structure(path), options.max_occurrences);
  const CadContent content =
      options.isolate ? read_isolated(path, options)
                      : detail::cad_module(path).read_occt_content(path, options, 0);
  out.length_unit = "mm";
  TriangleSoup soup = place_instances(content, options, file, out);
  if (soup.triangles.empty())
    throw InputError(file + ": no triangle (no shape with faces was tessellated)");
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return soup;
}

}  // namespace tetrapage