// `tetrapage render`: a PNG of an index, regions coloured by shard kind, region or page-ins
// of a flight, with the flight's path drawn.

#include <algorithm>
#include <cctype>
#include <cstdio>

#include "Commands.h"
#include "tetrapage/formats/base/ByteSize.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/Progress.h"
#include "tetrapage/formats/mesh/Manifest.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/runtime/query/FlyingObject.h"
#include "tetrapage/tools/ModelRenderer.h"

namespace tetrapage::cli {
namespace {

// The image formats render writes, by the output's extension (any case).
struct ImageFormat {
  const char* extension;
  const char* name;
  void (*write)(const std::filesystem::path&, const RgbImage&);
};
constexpr ImageFormat kImageFormats[] = {{".png", "PNG", write_png}};

// "PNG (.png)", for the help and the refusal.
std::string written_formats() {
  std::string list;
  for (const ImageFormat& format : kImageFormats)
    list += std::string(list.empty() ? "" : ", ") + format.name + " (" + format.extension + ")";
  return list;
}

// The format `output` names, or an InputError naming the path and the formats render writes:
// a picture is written in the format its name promises, never in another under that name.
const ImageFormat& image_format(const std::filesystem::path& output) {
  std::string extension = output.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  for (const ImageFormat& format : kImageFormats)
    if (extension == format.extension) return format;
  throw InputError("render: cannot write '" + output.string() + "': " +
                   (extension.empty() ? std::string("it has no extension")
                                      : "unknown extension '" + extension + "'") +
                   "; render writes " + written_formats());
}

struct RenderArguments {
  std::filesystem::path index, output, path, object, report;
  std::string colour = "kind";
  std::string size = "1200x800";
  std::string memory;  // add_memory_option sets the default
  double azimuth = 35, elevation = 30, zoom = 1;
  std::uint64_t max_triangles = 20'000'000;
};

void run_render(const RenderArguments& args) {
  // Before the work: a picture that cannot be written is known now, not after the render.
  const ImageFormat& format = image_format(args.output);
  check_outputs_writable({args.output, args.report}, {args.index, args.path, args.object});
  RenderOptions options;
  if (std::sscanf(args.size.c_str(), "%zux%zu", &options.width, &options.height) != 2)
    throw InputError("--size '" + args.size + "': expected WIDTHxHEIGHT, e.g. 1200x800");
  options.azimuth_degrees = args.azimuth;
  options.elevation_degrees = args.elevation;
  options.zoom = args.zoom;
  options.max_triangles = args.max_triangles;
  options.colouring = args.colour == "kind"      ? RenderColouring::shard_kind
                      : args.colour == "regions" ? RenderColouring::regions
                                                 : RenderColouring::page_ins;
  std::vector<Pose> poses;
  if (!args.path.empty()) {
    poses = read_poses(args.path);
    for (const auto& pose : poses) options.path.push_back(pose.translation);
  }
  // One index for the replay and the picture: rendering reads every shard once through the
  // cache, which any budget holding the largest shard allows.
  const bool replay = options.colouring == RenderColouring::page_ins;
  if (replay && (poses.empty() || args.object.empty()))
    throw InputError("--color page-ins needs the flight (--path) and the object (--object) to replay");
  CollisionIndexOptions index_options;
  index_options.memory_budget_bytes = parse_byte_size(args.memory);
  index_options.prefetch = replay;  // as `fly` runs the flight
  const auto index = std::make_shared<const CollisionIndex>(args.index, index_options);
  nlohmann::json flight;  // the replay's figures (--color page-ins)
  if (replay) {
    FlyingObject object(index, load_inputs({args.object}));
    Progress progress("replaying the flight", poses.size());
    std::uint64_t collisions = 0;
    for (const auto& pose : poses) {
      collisions += object.query(pose).collides ? 1 : 0;
      progress.advance();
    }
    progress.finish();
    index->cache().wait_prefetch_idle();
    options.page_ins = index->cache().page_ins_per_shard();
    const auto counters = index->cache().counters();
    std::uint64_t touched = 0;
    for (const auto n : options.page_ins) touched += n > 0;
    flight = {{"poses", poses.size()},
              {"collisions", collisions},
              {"budget", args.memory},
              {"budget_bytes", index_options.memory_budget_bytes},
              {"page_ins", counters.page_ins},
              {"shards_paged_in", touched},
              {"bytes_read", counters.bytes_loaded}};
    std::fprintf(stderr, "flight: %zu poses, %llu page-ins of %llu shards under %s\n", poses.size(),
                 (unsigned long long)counters.page_ins, (unsigned long long)touched, args.memory.c_str());
  }
  RenderSummary summary;
  const RgbImage image = render_model(*index, options, summary);
  format.write(args.output, image);
  std::printf("%s: %zux%zu, %llu triangles drawn%s from %llu shards, %.1f %% of pixels on the model, %.2f s\n",
              args.output.string().c_str(), image.width, image.height, (unsigned long long)summary.triangles_drawn,
              summary.stride > 1 ? (" (every " + std::to_string(summary.stride) + "th)").c_str() : "",
              (unsigned long long)summary.shards, 100.0 * double(summary.pixels_hit) / double(image.width * image.height),
              summary.seconds);
  if (!args.report.empty()) {
    nlohmann::json report{{"command", "render"},
                          {"index", args.index.string()},
                          {"output", args.output.string()},
                          {"colour", args.colour},
                          {"width", image.width},
                          {"height", image.height},
                          {"shards", summary.shards},
                          {"triangles_drawn", summary.triangles_drawn},
                          {"stride", summary.stride},
                          {"pixels_hit", summary.pixels_hit},
                          {"seconds", summary.seconds}};
    if (replay) report["flight"] = flight;
    write_report(args.report, report);
  }
}

}  // namespace

void add_render_command(CLI::App& app) {
  auto args = std::make_shared<RenderArguments>();
  auto* command = app.add_subcommand(
      "render",
      "Ray-trace an index with Embree into a PNG: each region's triangles coloured by its shard\n"
      "kind (grid blue, R-tree orange), by region, or by how often a flight paged it in\n"
      "(--color page-ins replays --path with --object under --memory; grey: never), with the\n"
      "flight's path drawn in magenta (faint where hidden; start green, end red).");
  command->add_option("index", args->index, "Index file (.tpi)")
      ->required()
      ->check(existing_file_check());
  command
      ->add_option("-o,--output", args->output,
                   "Image to write, in the format its extension names: " + written_formats())
      ->required();
  command
      ->add_option("--path", args->path, "Pose file of a flight to draw (CSV tx,ty,tz,qw,qx,qy,qz)")
      ->check(existing_file_check());
  command->add_option("--color", args->colour, "kind, regions or page-ins")
      ->check(CLI::IsMember({"kind", "regions", "page-ins"}))
      ->capture_default_str();
  command->add_option("--object", args->object, "Flying object for --color page-ins: a mesh, a STEP or IGES file, or a manifest (.json)")
      ->check(existing_file_check());
  add_memory_option(
      command, args->memory,
      "Budget of the decoded shards (the replay's for --color page-ins: a smaller one pages more)");
  command->add_option("--size", args->size, "Image size WIDTHxHEIGHT (each side 1 to 16384 pixels)")
      ->capture_default_str()
      ->check(image_size_check());
  command->add_option("--azimuth", args->azimuth, "Camera direction around +z, degrees from +x")
      ->capture_default_str()
      ->check(number_check(-360, 360));
  command
      ->add_option("--elevation", args->elevation, "Camera direction above the xy plane, degrees")
      ->capture_default_str()
      ->check(number_check(-90, 90));
  command->add_option("--zoom", args->zoom, "Move the camera closer (> 1) or away (< 1)")
      ->check(number_check(1e-3, 1e3))
      ->capture_default_str();
  command
      ->add_option("--max-triangles", args->max_triangles,
                   "Draw every k-th triangle above this many (Embree's scene memory)")
      ->check(whole_number_check(1, 1'000'000'000))
      ->capture_default_str();
  command->add_option("--report", args->report, "Write figures as JSON");
  command->callback([args] { run_render(*args); });
}

}  // namespace tetrapage::cli
