// `tetrapage generate scene|tetras|terrain|object`: the study's environments and flying
// objects (section 4.1), streamed to a mesh file whose format is chosen by its extension.

#include <chrono>
#include <cstdio>
#include <memory>
#include <optional>

#include "Commands.h"
#include "tetrapage/formats/base/MemoryUsage.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/tools/MeshLibrary.h"
#include "tetrapage/tools/ObjectGenerator.h"
#include "tetrapage/tools/SceneGenerator.h"
#include "tetrapage/tools/TerrainGenerator.h"
#include "tetrapage/tools/TetrasGenerator.h"

namespace tetrapage::cli {
namespace {

constexpr const char* formats_help =
    "Mesh file to write; the format follows the extension: .ply (binary, double), .obj, .off, "
    ".stl (binary), .gltf, .glb, .json (a manifest, a PLY per part); STL and OFF hold no parts";

struct Common {
  std::filesystem::path output, report, meshes;
  std::uint64_t seed = 1;
};

// What every generator reports, printed as one line and optionally as JSON.
struct Outcome {
  std::string command;
  std::uint64_t triangles = 0, vertices = 0, parts = 0;
  BoundingBox bounds;
  std::string note;  ///< appended to the summary line
  nlohmann::json details = nlohmann::json::object();
};

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

MeshLibrary load_library(const std::filesystem::path& folder) {
  Progress progress("loading meshes", 0);
  MeshLibrary library = folder.empty() ? MeshLibrary::load_default(progress)
                                       : MeshLibrary::load_folder(folder, progress);
  progress.finish();
  for (const auto& reason : library.skipped())
    std::fprintf(stderr, "tetrapage: warning: skipped mesh %s\n", reason.c_str());
  return library;
}

void finish(const Common& common, const Outcome& outcome, const nlohmann::json& seed,
            std::chrono::steady_clock::time_point start) {
  const double seconds = seconds_since(start);
  const std::uint64_t rss = peak_resident_bytes();
  const auto& lo = outcome.bounds.lo;
  const auto& hi = outcome.bounds.hi;
  const std::size_t parts = parts_in_file(common.output, outcome.parts);  // as a reader sees them
  std::printf(
      "%s: %llu triangles, %llu vertices, %llu parts%s, bounds [%.4g %.4g %.4g]-[%.4g %.4g %.4g], "
      "%.2f s, peak RSS %.1f MB, wrote %s\n",
      outcome.command.c_str(), static_cast<unsigned long long>(outcome.triangles),
      static_cast<unsigned long long>(outcome.vertices), static_cast<unsigned long long>(parts),
      outcome.note.c_str(), lo[0], lo[1], lo[2], hi[0], hi[1], hi[2], seconds, double(rss) / 1e6,
      common.output.c_str());
  if (common.report.empty()) return;
  nlohmann::json report = {{"command", "generate " + outcome.command},
                           {"output", common.output.string()},
                           {"seed", seed},
                           {"triangles", outcome.triangles},
                           {"vertices", outcome.vertices},
                           {"parts", parts},
                           {"bounds", {{"lo", lo}, {"hi", hi}}},
                           {"seconds", seconds},
                           {"peak_rss_bytes", rss}};
  report.update(outcome.details);
  write_report(common.report, report);
}

void add_common_options(CLI::App& command, Common& common, bool with_seed) {
  command.add_option("-o,--output", common.output, formats_help)->required();
  if (with_seed)
    command.add_option("--seed", common.seed, "Random seed (a whole number)")
        ->capture_default_str()
        ->check(seed_check());
  command.add_option("--report", common.report, "Also write the figures as JSON to this file");
}

void add_meshes_option(CLI::App& command, Common& common) {
  command
      .add_option("--meshes", common.meshes,
                  "Folder of real meshes: every .off/.ply/.obj/.stl file in it is used. Default: "
                  "the curated CGAL models in $TETRAPAGE_MESH_DIR or in the folder the build "
                  "unpacked (" +
                      MeshLibrary::default_folder().string() + ")")
      ->check(CLI::ExistingDirectory);
}

void add_scene(CLI::App& generate) {
  auto common = std::make_shared<Common>();
  auto options = std::make_shared<SceneOptions>();
  auto* command = generate.add_subcommand(
      "scene",
      "The study's \"scenes\": a random BSP tree cuts the unit cube [0,1]^3 (model units) into\n"
      "boxes (2 per copy; no side shorter than alpha = 0.4 (1/leaves)^(1/3)); a random half of\n"
      "the boxes each get one randomly rotated copy of a real mesh, scaled to fill 90% of its\n"
      "box along the tightest axis and centred. Meshes are drawn until the total is about\n"
      "--triangles. As in real CAD exports, closed solids and open shells share the file: a\n"
      "fraction of the copies (--open-fraction) lose their triangles above a random plane,\n"
      "leaving one connected shell with a hole; the others stay closed.\n"
      "Each copy is streamed to the file as its own part (\"<mesh>#<n>\"; STL and OFF hold no\n"
      "parts): memory stays small for any size.\n"
      "The same seed and meshes give the same file.");
  command->add_option("--triangles", options->triangles, "Target number of triangles (a count)")
      ->capture_default_str()
      ->check(whole_number_check(1, max_scene_triangles));
  options->open_fraction = default_scene_open_fraction;
  command
      ->add_option("--open-fraction", options->open_fraction,
                   "Fraction of the copies opened, in [0, 1]: the triangles whose corners all lie "
                   "above a plane at a random 60-90% of the copy's extent along a random direction "
                   "are dropped (of what remains, the largest connected piece is kept). The "
                   "triangle target counts the kept triangles. 0: every copy closed")
      ->capture_default_str()
      ->check(number_check(0, 1));
  add_common_options(*command, *common, true);
  add_meshes_option(*command, *common);
  command->callback([common, options] {
    const auto start = std::chrono::steady_clock::now();
    options->seed = common->seed;
    check_scene_options(*options);      // first: a bad option or output name fails before
    MeshWriter writer(common->output);  // any work
    const MeshLibrary library = load_library(common->meshes);
    Progress progress("generating scene (triangles)", 0);  // the plan decides the total
    const SceneSummary summary = generate_scene(library, *options, writer, progress);
    writer.commit();
    progress.finish();
    Outcome outcome{"scene",
                    summary.triangles,
                    summary.vertices,
                    summary.copies.size(),
                    summary.bounds,
                    " (copies of real meshes in " + std::to_string(summary.copies.size()) + " of " +
                        std::to_string(summary.leaves) +
                        " BSP leaves: " + std::to_string(summary.open_copies) + " open, " +
                        std::to_string(summary.closed_copies) + " closed)",
                    {}};
    nlohmann::json used = nlohmann::json::object();
    for (const auto& copy : summary.copies) {
      auto& count = used[library[copy.mesh].name];
      count = count.is_null() ? 1 : count.get<int>() + 1;
    }
    outcome.details = {{"target_triangles", options->triangles},
                       {"copies", summary.copies.size()},
                       {"open_fraction", options->open_fraction},
                       {"open_copies", summary.open_copies},
                       {"closed_copies", summary.closed_copies},
                       {"leaves", summary.leaves},
                       {"alpha", summary.alpha},
                       {"meshes_folder", library.folder().string()},
                       {"copies_per_mesh", used}};
    finish(*common, outcome, options->seed, start);
  });
}

void add_tetras(CLI::App& generate) {
  auto common = std::make_shared<Common>();
  auto options = std::make_shared<TetrasOptions>();
  auto* command = generate.add_subcommand(
      "tetras",
      "The study's \"tetras\": a random BSP tree cuts the unit cube [0,1]^3 (model units) into\n"
      "2 boxes per tetrahedron; a random half of the boxes each get one tetrahedron with\n"
      "random corners (redrawn while its volume is below 0.5% of its box), outward oriented:\n"
      "each is a closed 4-triangle part (\"tetra#<k>\"). --triangles/4 tetrahedra (the study:\n"
      "100 to 16,000 triangles).");
  command
      ->add_option("--triangles", options->triangles,
                   "Number of triangles (a count, 4 per tetrahedron)")
      ->capture_default_str()
      ->check(whole_number_check(1, max_tetras_triangles));
  add_common_options(*command, *common, true);
  command->callback([common, options] {
    const auto start = std::chrono::steady_clock::now();
    options->seed = common->seed;
    MeshWriter writer(common->output);
    Progress progress("generating tetras (triangles)", (options->triangles + 2) / 4 * 4);
    const TetrasSummary summary = generate_tetras(*options, writer, progress);
    writer.commit();
    progress.finish();
    Outcome outcome{"tetras",
                    summary.triangles,
                    summary.vertices,
                    summary.tetras,
                    summary.bounds,
                    " (tetrahedra in " + std::to_string(summary.tetras) + " of " +
                        std::to_string(summary.leaves) + " BSP leaves)",
                    {}};
    outcome.details = {{"target_triangles", options->triangles},
                       {"tetras", summary.tetras},
                       {"leaves", summary.leaves},
                       {"alpha", summary.alpha},
                       {"redraws", summary.redraws}};
    finish(*common, outcome, options->seed, start);
  });
}

void add_terrain(CLI::App& generate) {
  auto common = std::make_shared<Common>();
  auto options = std::make_shared<TerrainOptions>();
  auto* command = generate.add_subcommand(
      "terrain",
      "The study's \"terrains\": a fractal heightfield (diamond-square, cropped to the study's\n"
      "1201 x 1201 DEM grid) sampled to s x s points with 2 (s-1)^2 close to --triangles\n"
      "(default: the study's 120 x 120; 2880000 gives the full 1201 x 1201), over [0,1]^2 with\n"
      "heights in [0.05, 0.45] (model units); each grid cell split into two triangles. One open\n"
      "surface, one part.");
  command->add_option("--triangles", options->triangles, "Target number of triangles (a count)")
      ->capture_default_str()
      ->check(whole_number_check(1, max_terrain_triangles));
  command
      ->add_option(
          "--roughness", options->roughness,
          "Fractal roughness H, no unit: amplitude ratio 2^-H between levels (1 smooth, 0 noise)")
      ->capture_default_str()
      ->check(number_check(0, 4));
  add_common_options(*command, *common, true);
  command->callback([common, options] {
    const auto start = std::chrono::steady_clock::now();
    options->seed = common->seed;
    MeshWriter writer(common->output);
    const std::uint64_t cells = terrain_samples_per_side(options->triangles) - 1;
    Progress progress("generating terrain (triangles)", 2 * cells * cells);
    const TerrainSummary summary = generate_terrain(*options, writer, progress);
    writer.commit();
    progress.finish();
    Outcome outcome{"terrain",
                    summary.triangles,
                    summary.vertices,
                    1,
                    summary.bounds,
                    " (" + std::to_string(summary.samples_per_side) + " x " +
                        std::to_string(summary.samples_per_side) + " samples)",
                    {}};
    outcome.details = {{"target_triangles", options->triangles},
                       {"samples_per_side", summary.samples_per_side},
                       {"bands", summary.bands},
                       {"source_side", summary.source_side},
                       {"fractal_side", summary.fractal_side},
                       {"roughness", options->roughness}};
    finish(*common, outcome, options->seed, start);
  });
}

void add_object(CLI::App& generate) {
  auto common = std::make_shared<Common>();
  auto options = std::make_shared<ObjectOptions>();
  auto seed = std::make_shared<std::optional<std::uint64_t>>();
  auto* command = generate.add_subcommand(
      "object",
      "A flying object fitted into a cube of side --size (model units; the default 0.05 is a\n"
      "twentieth of the study's unit cube), centred at the origin (its own frame):\n"
      "up to 4 triangles a tetrahedron, up to 200 a UV sphere (116: the study's sphere), above\n"
      "that a real mesh simplified by CGAL edge collapses to about --triangles (the study:\n"
      "4, 116, 496, 2094, 5152, 14643). Without --seed the mesh with the fewest triangles\n"
      "at or above the request is used; with --seed a random one of those.");
  command->add_option("--triangles", options->triangles, "Number of triangles (a count, about)")
      ->capture_default_str()
      ->check(whole_number_check(1, max_object_triangles));
  command
      ->add_option("--size", options->size,
                   "Side of the cube the object is fitted into, in model units (match the "
                   "environment's: e.g. 65 for a 1300 mm assembly)")
      ->capture_default_str()
      ->check(positive_number_check(kLongestLength));
  command->add_option("-o,--output", common->output, formats_help)->required();
  command
      ->add_option("--seed", *seed,
                   "Pick a random real mesh (large objects only; a whole number). Default: "
                   "the mesh with the fewest triangles at or above the request")
      ->check(seed_check());
  command->add_option("--report", common->report, "Also write the figures as JSON to this file");
  add_meshes_option(*command, *common);
  command->callback([common, options, seed] {
    const auto start = std::chrono::steady_clock::now();
    options->seed = *seed;
    MeshWriter writer(common->output);  // first: a bad output name fails before any work
    std::optional<MeshLibrary> library;
    if (object_needs_meshes(options->triangles)) library.emplace(load_library(common->meshes));
    const GeneratedObject object = generate_object(*options, library ? &*library : nullptr);
    for (const auto& reason : object.rejected)
      std::fprintf(stderr, "tetrapage: warning: gave up mesh %s\n", reason.c_str());
    writer.add_part(object.soup.vertices, object.soup.triangles);
    writer.commit();
    Outcome outcome{"object",
                    object.soup.triangle_count(),
                    object.soup.vertices.size(),
                    1,
                    object.soup.bounds(),
                    " (" + object.source + (object.closed ? ", closed)" : ", not closed)"),
                    {}};
    outcome.details = {{"requested_triangles", options->triangles},
                       {"source", object.source},
                       {"source_triangles", object.source_triangles},
                       {"closed", object.closed}};
    finish(*common, outcome, *seed ? nlohmann::json(**seed) : nlohmann::json(nullptr), start);
  });
}

}  // namespace

void add_generate_environment_commands(CLI::App& generate) {
  add_scene(generate);
  add_tetras(generate);
  add_terrain(generate);
  add_object(generate);
}

}  // namespace tetrapage::cli
