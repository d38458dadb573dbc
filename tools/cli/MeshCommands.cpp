// `tetrapage mesh info|convert`: look at mesh files and convert between formats.

#include <cctype>
#include <chrono>
#include <cstdio>
#include <memory>
#include <vector>

#include "Commands.h"
#include "TessellationArguments.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/MemoryUsage.h"
#include "tetrapage/formats/mesh/FileChecks.h"
#include "tetrapage/formats/mesh/Manifest.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/MeshWriter.h"

namespace tetrapage::cli {
namespace {

struct InfoArguments {
  std::vector<std::filesystem::path> files;
  std::filesystem::path report;
  TessellationArguments tessellation;
};

struct ConvertArguments {
  std::filesystem::path input;
  std::filesystem::path output;
  std::filesystem::path report;
  TessellationArguments tessellation;
};

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

double megabytes_per_second(std::uint64_t bytes, double seconds) {
  return seconds > 0 ? double(bytes) / 1e6 / seconds : 0.0;
}

nlohmann::json bounds_json(const BoundingBox& box) {
  if (box.empty()) return nullptr;
  return {{"lo", box.lo}, {"hi", box.hi}};
}

nlohmann::json report_json(const ReadReport& report) {
  return {{"path", report.path},
          {"format", report.format},
          {"encoding", report.encoding},
          {"bytes", report.bytes},
          {"triangles_read", report.triangles_read},
          {"degenerate_dropped", report.degenerate_dropped},
          {"polygons_triangulated", report.polygons_triangulated},
          {"length_unit", report.length_unit},
          {"tessellation_deflection", report.tessellation_deflection},
          {"skipped_parts", report.skipped_parts},
          {"seconds", report.seconds},
          {"megabytes_per_second", megabytes_per_second(report.bytes, report.seconds)}};
}

void print_bounds(const BoundingBox& box) {
  if (box.empty()) return;
  std::printf("  bounds [%.9g, %.9g, %.9g] .. [%.9g, %.9g, %.9g]\n", box.lo[0], box.lo[1],
              box.lo[2], box.hi[0], box.hi[1], box.hi[2]);
}

// The first parts by name and instance path, one a line: a long assembly is summed up after.
void print_parts(const TriangleSoup& soup) {
  constexpr std::size_t kListed = 20;
  for (std::size_t part = 0; part < soup.part_count() && part < kListed; ++part) {
    const std::string& name = soup.part_names[part];
    const std::string& path = soup.part_path(part);
    std::printf("  part %zu: %s%s%s\n", part, name.empty() ? "(unnamed)" : name.c_str(),
                path == name ? "" : "  at ", path == name ? "" : path.c_str());
  }
  if (soup.part_count() > kListed)
    std::printf("  ... and %zu more parts\n", soup.part_count() - kListed);
}

void run_info(const InfoArguments& args) {
  check_outputs(std::span<const std::filesystem::path>(&args.report, 1), args.files);
  nlohmann::json files = nlohmann::json::array();
  for (const auto& path : args.files) {
    std::vector<ReadReport> reports;
    const auto start = std::chrono::steady_clock::now();
    const bool is_manifest = path.extension() == ".json" || path.extension() == ".JSON";
    const TriangleSoup soup = load_inputs({path}, &reports, Progress::silent(), args.tessellation.options(true));
    const double seconds = seconds_since(start);
    std::uint64_t bytes = 0, degenerate = 0, polygons = 0;
    for (const auto& report : reports) {
      bytes += report.bytes;
      degenerate += report.degenerate_dropped;
      polygons += report.polygons_triangulated;
    }
    const BoundingBox box = soup.bounds();
    const std::string format =
        is_manifest
            ? "manifest"
            : reports.front().format +
                  (reports.front().encoding.empty() ? "" : " (" + reports.front().encoding + ")");
    std::printf(
        "%s: %s, %zu triangles, %zu vertices, %zu parts, %llu degenerate dropped, "
        "%llu polygons triangulated\n",
        path.c_str(), format.c_str(), soup.triangle_count(), soup.vertices.size(),
        soup.part_count(), static_cast<unsigned long long>(degenerate),
        static_cast<unsigned long long>(polygons));
    print_bounds(box);
    print_parts(soup);
    for (const auto& report : reports) {
      if (!report.length_unit.empty()) std::printf("  %s: unit %s", report.path.c_str(), report.length_unit.c_str());
      if (report.tessellation_deflection > 0)
        std::printf(", tessellated within %g %s", report.tessellation_deflection, report.length_unit.c_str());
      if (!report.length_unit.empty()) std::printf("\n");
      for (const auto& skipped : report.skipped_parts) std::printf("  skipped part %s\n", skipped.c_str());
    }
    std::printf("  read %.3f s, %.1f MB/s (%llu bytes%s)\n", seconds,
                megabytes_per_second(bytes, seconds), static_cast<unsigned long long>(bytes),
                is_manifest ? (", " + std::to_string(reports.size()) + " files").c_str() : "");
    nlohmann::json entry = {
        {"path", path.string()},
        {"format", is_manifest ? "manifest" : reports.front().format},
        {"encoding", is_manifest ? "" : reports.front().encoding},
        {"triangles", soup.triangle_count()},
        {"vertices", soup.vertices.size()},
        {"parts", soup.part_count()},
        {"degenerate_dropped", degenerate},
        {"polygons_triangulated", polygons},
        {"bounds", bounds_json(box)},
        {"bytes", bytes},
        {"read_seconds", seconds},
        {"megabytes_per_second", megabytes_per_second(bytes, seconds)},
        {"triangles_per_second", seconds > 0 ? double(soup.triangle_count()) / seconds : 0.0}};
    if (is_manifest) {
      entry["files"] = nlohmann::json::array();
      for (const auto& report : reports) entry["files"].push_back(report_json(report));
    }
    files.push_back(std::move(entry));
  }
  if (!args.report.empty()) {
    write_report(
        args.report,
        {{"command", "mesh info"}, {"files", files}, {"peak_rss_bytes", peak_resident_bytes()}});
  }
}

// The unit of the coordinates load_inputs gave for one input: a manifest's own, else the one
// its file states (STEP and IGES: mm), else none.
std::string unit_of_input(const std::filesystem::path& input,
                          const std::vector<ReadReport>& reports) {
  if (is_manifest_path(input)) return read_manifest(input).units;
  return reports.empty() ? std::string() : reports.front().length_unit;
}

void run_convert(const ConvertArguments& args) {
  check_outputs_writable({args.output, args.report}, {args.input});
  if (!can_write_mesh(args.output)) {
    throw InputError("'" + args.output.string() + "': cannot write meshes with the extension '" +
                     args.output.extension().string() +
                     "' (writable: .obj, .stl, .ply, .off, .gltf, .glb, .json)");
  }
  const auto start = std::chrono::steady_clock::now();
  std::vector<ReadReport> reports;
  Progress reading("reading", 0);
  const TriangleSoup soup = load_inputs({args.input}, &reports, reading, args.tessellation.options(true));
  reading.finish();
  const double read_seconds = seconds_since(start);
  const auto write_start = std::chrono::steady_clock::now();
  write_mesh(args.output, soup, unit_of_input(args.input, reports));
  const double write_seconds = seconds_since(write_start);
  std::uint64_t degenerate = 0;
  for (const auto& report : reports) degenerate += report.degenerate_dropped;
  const std::size_t parts = parts_in_file(args.output, soup.part_count());
  std::printf(
      "wrote %s: %zu triangles, %zu vertices, %zu parts (%llu degenerate dropped); "
      "read %.3f s, write %.3f s\n",
      args.output.c_str(), soup.triangle_count(), soup.vertices.size(), parts,
      static_cast<unsigned long long>(degenerate), read_seconds, write_seconds);
  if (!args.report.empty()) {
    nlohmann::json inputs = nlohmann::json::array();
    for (const auto& report : reports) inputs.push_back(report_json(report));
    std::error_code error;
    const auto output_bytes = std::filesystem::file_size(args.output, error);
    write_report(args.report, {{"command", "mesh convert"},
                               {"input", args.input.string()},
                               {"output", args.output.string()},
                               {"triangles", soup.triangle_count()},
                               {"vertices", soup.vertices.size()},
                               {"parts", parts},
                               {"input_parts", soup.part_count()},
                               {"degenerate_dropped", degenerate},
                               {"read_seconds", read_seconds},
                               {"write_seconds", write_seconds},
                               {"output_bytes", error ? 0 : output_bytes},
                               {"files", inputs},
                               {"peak_rss_bytes", peak_resident_bytes()}});
  }
}

}  // namespace

std::size_t parts_in_file(const std::filesystem::path& output, std::size_t parts) {
  if (parts <= 1 || mesh_format_keeps_parts(output)) return parts;
  std::string format = output.extension().string().substr(1);
  for (char& c : format) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  std::printf("%s: %s holds no parts: the %zu parts were merged into one\n", output.c_str(),
              format.c_str(), parts);
  return 1;
}

void add_mesh_commands(CLI::App& app) {
  auto* mesh = app.add_subcommand("mesh", "Inspect and convert mesh files and assembly manifests");
  mesh->require_subcommand(1);

  auto info_args = std::make_shared<InfoArguments>();
  auto* info = mesh->add_subcommand(
      "info",
      "Read mesh files and print, per file: format, triangles, vertices, parts, degenerate\n"
      "triangles dropped, polygons triangulated, bounds, read time and throughput (MB/s).\n"
      "Readable: .obj, .stl (ASCII or binary), .ply (ASCII or binary), .off (our own readers,\n"
      "double precision), .gltf, .glb and the other formats Assimp imports (single precision),\n"
      "and assembly manifests (.json).");
  info->add_option("files", info_args->files,
                   "Mesh files, STEP or IGES files, or manifests (.json)")
      ->required()
      ->check(existing_file_check());
  info->add_option("--report", info_args->report, "Also write the figures as JSON");
  info_args->tessellation.add_to(info);
  info->callback([info_args] { run_info(*info_args); });

  auto convert_args = std::make_shared<ConvertArguments>();
  auto* convert = mesh->add_subcommand(
      "convert",
      "Read a mesh file (or an assembly manifest, .json) and write it in the format named by\n"
      "the output's extension: .obj, .ply (binary, double), .off (exact doubles), .stl\n"
      "(binary, float), .gltf/.glb (float), .json (a manifest, a PLY per part). Parts keep\n"
      "their names in OBJ (`o`/`g`), PLY (a part table), glTF (a node each) and manifests;\n"
      "STL and OFF hold none: a line says so when parts are merged. Triangles go part by\n"
      "part. The output appears only when complete.");
  convert
      ->add_option("input", convert_args->input,
                   "Mesh file, STEP or IGES file, or manifest (.json)")
      ->required()
      ->check(existing_file_check());
  convert->add_option("-o,--output", convert_args->output, "Mesh file to write")->required();
  convert->add_option("--report", convert_args->report, "Also write the figures as JSON");
  convert_args->tessellation.add_to(convert);
  convert->callback([convert_args] { run_convert(*convert_args); });
}

}  // namespace tetrapage::cli
