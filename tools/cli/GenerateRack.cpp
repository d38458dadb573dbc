// `tetrapage generate rack`: a benchmark assembly of real STEP parts on boards in card cages
// (RackGenerator.h), written as manifests; the insertion flight of a connector beside it.

#include <chrono>
#include <cstdio>

#include "Commands.h"
#include "tetrapage/formats/base/ByteSize.h"
#include "tetrapage/formats/base/MemoryUsage.h"
#include "tetrapage/tools/RackGenerator.h"

namespace tetrapage::cli {
namespace {

// The longest length a layout option takes: a kilometre, far beyond any rack.
constexpr double kLongestMillimetres = 1e6;

const std::filesystem::path kKicadParts = "/usr/share/kicad/3dmodels";
const std::filesystem::path kHeader =
    "Connector_PinHeader_2.54mm.3dshapes/PinHeader_2x05_P2.54mm_Vertical.step";
const std::filesystem::path kSocket =
    "Connector_PinSocket_2.54mm.3dshapes/PinSocket_2x05_P2.54mm_Vertical.step";

struct RackArguments {
  RackOptions options;
  std::filesystem::path output, report;
  std::string max_file_size = "400K";
  bool no_connector = false;
};

/// The KiCad header and socket under the parts folder, when neither is given and both exist.
void default_connector(RackArguments& args) {
  RackOptions& o = args.options;
  if (args.no_connector) {
    o.connector.clear();
    o.plug.clear();
    return;
  }
  const auto header = o.parts.folder / kHeader, socket = o.parts.folder / kSocket;
  if (o.connector.empty() && o.plug.empty() && std::filesystem::is_regular_file(header) &&
      std::filesystem::is_regular_file(socket)) {
    o.connector = header;
    o.plug = socket;
  }
}

nlohmann::json summary_json(const RackArguments& args, const RackSummary& summary) {
  const RackOptions& o = args.options;
  nlohmann::json types = nlohmann::json::array();
  for (const BoardLayout& layout : summary.types)
    types.push_back({{"parts", layout.parts.size()}, {"triangles", layout.triangles}});
  nlohmann::json parts = nlohmann::json::array();
  for (const RackPart& part : summary.library.parts)
    parts.push_back({{"file", part.file.string()}, {"triangles", part.triangles}});
  return {{"command", "generate rack"},
          {"output", args.output.string()},
          {"seed", o.parts.seed},
          {"target_triangles", o.triangles},
          {"triangles", summary.triangles},
          {"boards", summary.boards},
          {"board_types", types},
          {"parts", parts},
          {"parts_folder", o.parts.folder.string()},
          {"candidate_files", summary.library.candidates},
          {"skipped_files", summary.library.skipped},
          {"bounds", {{"lo", summary.bounds.lo}, {"hi", summary.bounds.hi}}},
          {"connector", o.connector.string()},
          {"plug", o.plug.string()},
          {"plug_triangles", summary.plug_triangles},
          {"insertion_poses", summary.insertion_poses.string()},
          {"flat", o.flat}};
}

void run_generate_rack(RackArguments& args) {
  const auto start = std::chrono::steady_clock::now();
  args.options.parts.max_file_bytes = parse_byte_size(args.max_file_size);
  default_connector(args);
  check_outputs_writable({args.output, args.report}, {});
  Progress progress("reading STEP parts", args.options.parts.count);
  const RackSummary summary = generate_rack(args.options, args.output, progress);
  progress.finish();
  for (const auto& reason : summary.library.skipped)
    std::fprintf(stderr, "tetrapage: note: passed over %s\n", reason.c_str());
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const auto& lo = summary.bounds.lo;
  const auto& hi = summary.bounds.hi;
  std::printf(
      "rack: %llu triangles, %zu boards of %zu types, %zu distinct parts (%zu files passed over), "
      "bounds [%.1f %.1f %.1f]-[%.1f %.1f %.1f] mm, %.2f s, peak RSS %.1f MB, wrote %s\n",
      static_cast<unsigned long long>(summary.triangles), summary.boards, summary.types.size(),
      summary.library.parts.size(), summary.library.skipped.size(), lo[0], lo[1], lo[2], hi[0],
      hi[1], hi[2], seconds, double(peak_resident_bytes()) / 1e6, args.output.c_str());
  if (!summary.insertion_poses.empty())
    std::printf("insertion flight: %zu poses of %s into board %zu's %s, wrote %s\n",
                args.options.insert_steps, args.options.plug.filename().c_str(),
                insertion_board(args.options, summary.boards),
                args.options.connector.filename().c_str(), summary.insertion_poses.c_str());
  if (args.report.empty()) return;
  nlohmann::json report = summary_json(args, summary);
  report["seconds"] = seconds;
  report["peak_rss_bytes"] = peak_resident_bytes();
  write_report(args.report, report);
}

void add_layout_options(CLI::App& command, RackOptions& o) {
  command.add_option("--board-types", o.board_types, "Distinct boards laid out, used in turn")
      ->capture_default_str()
      ->check(whole_number_check(1, 64));
  command.add_option("--board-length", o.board.length, "Plate length (mm)")
      ->capture_default_str()
      ->check(positive_number_check(kLongestMillimetres));
  command.add_option("--board-width", o.board.width, "Plate width (mm)")
      ->capture_default_str()
      ->check(positive_number_check(kLongestMillimetres));
  command.add_option("--board-thickness", o.board.thickness, "Plate thickness (mm)")
      ->capture_default_str()
      ->check(positive_number_check(kLongestMillimetres));
  command
      .add_option("--gap", o.board.gap,
                  "Free space between footprints and from the plate's edges (mm)")
      ->capture_default_str()
      ->check(number_check(0, kLongestMillimetres));
  command.add_option("--pitch", o.pitch, "Distance between neighbouring boards in a cage (mm)")
      ->capture_default_str()
      ->check(positive_number_check(kLongestMillimetres));
  command.add_option("--slots", o.slots, "Boards per card cage")
      ->capture_default_str()
      ->check(whole_number_check(1, 10000));
  command
      .add_option("--cages", o.cages, "Cages stacked in one rack (more boards: racks side by side)")
      ->capture_default_str()
      ->check(whole_number_check(1, 10000));
  command.add_flag(
      "--flat", o.flat,
      "Write one manifest of mesh entries (each placement composed) instead of the rack "
      "naming one manifest per board type");
}

void add_parts_options(CLI::App& command, RackArguments& args) {
  RackOptions& o = args.options;
  o.parts.folder = kKicadParts;
  command
      .add_option("--parts-folder", o.parts.folder,
                  "Folder searched (recursively) for .step/.stp parts")
      ->capture_default_str()
      ->check(CLI::ExistingDirectory);
  command.add_option("--parts", o.parts.count, "Distinct parts drawn from the folder")
      ->capture_default_str()
      ->check(whole_number_check(1, 100000));
  command
      .add_option("--max-file-size", args.max_file_size,
                  "Files larger than this are passed over (bytes; K, M, G)")
      ->capture_default_str()
      ->check(byte_size_check());
  command.add_option("--max-height", o.parts.max_height, "Taller parts are passed over (mm)")
      ->capture_default_str()
      ->check(positive_number_check(kLongestMillimetres));
  command
      .add_option("--max-side", o.parts.max_side,
                  "Parts whose footprint has a longer side are passed over (mm)")
      ->capture_default_str()
      ->check(positive_number_check(kLongestMillimetres));
  command
      .add_option("--connector", o.connector,
                  "A STEP header put first on every board type (default: KiCad's " +
                      kHeader.filename().string() +
                      " under the parts folder, with --plug its socket)")
      ->check(existing_file_check());
  command
      .add_option("--plug", o.plug,
                  "The STEP part inserted into a board's connector (the flying object)")
      ->check(existing_file_check());
  command.add_flag("--no-connector", args.no_connector, "No connector and no insertion flight");
  command.add_option("--insert-steps", o.insert_steps, "Poses of the insertion flight")
      ->capture_default_str()
      ->check(whole_number_check(2, 1ll << 24));
  command
      .add_option("--insert-depth", o.insert_depth,
                  "How far the plug's face travels past the header's top (mm)")
      ->capture_default_str()
      ->check(number_check(0, kLongestMillimetres));
}

}  // namespace

void add_generate_rack_command(CLI::App& generate) {
  auto args = std::make_shared<RackArguments>();
  auto* command = generate.add_subcommand(
      "rack",
      "A benchmark assembly of real CAD parts: STEP files drawn (seeded) from --parts-folder,\n"
      "each tessellated once (read_cad's defaults, as preprocess reads them) to learn its box;\n"
      "--board-types boards laid out by shelf packing (parts turned by multiples of 90 degrees\n"
      "about z, standing on the plate, never overlapping); boards instanced in turn, upright in\n"
      "card cages, until the rack holds --triangles. Writes the rack manifest (-o, millimetres),\n"
      "its board manifests and plate in OUTPUT_STEM-boards/, and with a connector the insertion\n"
      "flight OUTPUT_STEM-insert.csv (poses of --plug moving into the header of the last\nboard of "
      "the first cage). The same\n"
      "options and parts give the same bytes.");
  command
      ->add_option("--triangles", args->options.triangles,
                   "Boards are added until the rack holds this many triangles")
      ->capture_default_str()
      ->check(whole_number_check(1, 1ll << 40));
  command->add_option("--seed", args->options.parts.seed, "Random seed (parts drawn, layouts)")
      ->capture_default_str()
      ->check(seed_check());
  command->add_option("-o,--output", args->output, "Rack manifest to write (.json)")->required();
  command->add_option("--report", args->report, "Also write the figures as JSON to this file");
  add_parts_options(*command, *args);
  add_layout_options(*command, args->options);
  command->callback([args] { run_generate_rack(*args); });
}

}  // namespace tetrapage::cli
