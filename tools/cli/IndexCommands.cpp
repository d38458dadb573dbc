// `tetrapage preprocess`, `inspect` and `validate`: build an index, show where its bytes go
// (and its mesh's stabbing number, by the walk and by Embree), and check it from end to end.

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <thread>

#include "Commands.h"
#include "TessellationArguments.h"
#include "tetrapage/formats/base/ByteSize.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/Progress.h"
#include "tetrapage/formats/index/IndexParts.h"
#include "tetrapage/formats/index/IndexReader.h"
#include "tetrapage/formats/index/IndexSchema.h"
#include "tetrapage/formats/index/IndexSummary.h"
#include "tetrapage/formats/mesh/FileChecks.h"
#include "tetrapage/formats/mesh/Manifest.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/preprocess/Preprocess.h"
#include "tetrapage/runtime/geometry/PointTetrahedron.h"
#include "tetrapage/runtime/geometry/Predicates.h"
#include "tetrapage/runtime/paging/CollisionIndex.h"
#include "tetrapage/runtime/paging/Shard.h"
#include "tetrapage/tools/EmbreeMeshFaces.h"
#include "tetrapage/tools/IndexAudit.h"
#include "tetrapage/tools/Random.h"
#include "tetrapage/tools/StabbingNumbers.h"

namespace tetrapage::cli {

namespace schema = index_schema;
namespace {

// The other format a file name's extension names ("a PNG image"), or empty: an index written
// under a picture's or a mesh's name would be opened as one by every other program.
std::string other_format_named(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  for (char& c : extension) c = char(std::tolower(static_cast<unsigned char>(c)));
  for (const char* image :
       {".png", ".jpg", ".jpeg", ".bmp", ".gif", ".tif", ".tiff", ".ppm", ".svg"})
    if (extension == image) return "an image";
  // The index's own extension: no mesh reader (nor the CAD module, which knows Assimp's
  // extensions) needs asking.
  if (extension == ".tpi") return {};
  if (extension == ".csv") return "a CSV table";
  if (extension == ".json") return "a JSON file (a manifest or a report)";
  if (extension.size() > 1) {
    try {
      mesh_format_from_path(path);
      return "a mesh";
    } catch (const Error&) {
      // no reader claims it (or the CAD module that would cannot be loaded): free for an index
    }
  }
  return {};
}

CLI::Validator index_output_check() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        const std::string format = other_format_named(text);
        if (format.empty()) return {};
        return "'" + text + "' names " + format + ", not an index (write MODEL.tpi)";
      },
      "", "index file name");
}

struct PreprocessArguments {
  std::vector<std::filesystem::path> inputs;
  std::filesystem::path output;
  std::size_t region_triangles = PreprocessOptions{}.region_triangles;
  std::string memory;  // add_memory_option sets the default
  unsigned threads = 0;
  std::string shard = "auto";
  std::string precision = "exact";
  std::string compression = "lz4";
  double query_extent = 0;
  std::string interiors = "on";
  bool accept_undecided = false;
  std::string unit;
  TessellationArguments tessellation;
  std::filesystem::path report;
};

void run_preprocess(const PreprocessArguments& args) {
  check_outputs(std::vector<std::filesystem::path>{args.output, args.report}, args.inputs);
  check_writable(args.report);
  PreprocessOptions options;
  options.region_triangles = args.region_triangles;
  options.memory_bytes = parse_byte_size(args.memory);
  options.threads = args.threads;
  options.shard = parse_shard_choice(args.shard);
  options.precision = parse_stored_precision(args.precision);
  options.compression = parse_chunk_compression(args.compression);
  options.query_extent = args.query_extent;
  options.progress = true;
  options.interiors = args.interiors == "on";
  options.accept_undecided = args.accept_undecided;
  options.length_unit = args.unit;
  options.tessellation = args.tessellation.options(true);
  const PreprocessSummary summary = preprocess(args.inputs, args.output, options);
  std::fputs(summary.to_text().c_str(), stdout);
  if (!args.report.empty()) write_report(args.report, nlohmann::json::parse(summary.to_json()));
}

struct InspectArguments {
  std::filesystem::path index;
  std::filesystem::path report;
  std::uint64_t stabbing_segments = 10'000;
  std::uint64_t stabbing_seed = 1;
  std::size_t parts_listed = 20;
};

// The model's unit, its tessellation and its parts (the first `listed`, or all for 0).
nlohmann::json part_figures(const IndexReader& reader, std::size_t listed) {
  const IndexHeader& header = reader.header();
  const std::string unit = header.length_unit.empty() ? "model units (the index records no unit)" : header.length_unit;
  std::printf("unit: %s\n", unit.c_str());
  if (header.tessellation_deflection > 0)
    std::printf("tessellation: STEP/IGES shapes within a deflection of %g %s of their surfaces\n",
                header.tessellation_deflection, unit.c_str());
  const auto component_part = reader.read_table_uint32(schema::table::component_part);
  std::size_t listed_parts = 0;
  for (const auto p : component_part) listed_parts = std::max<std::size_t>(listed_parts, std::size_t(p) + 1);
  const IndexParts parts = IndexParts::read(reader, listed_parts);
  std::printf("parts: %zu%s\n", parts.count(), parts.named() ? "" : " (unnamed: the index predates part names)");
  const std::size_t shown = listed == 0 ? parts.count() : std::min(listed, parts.count());
  nlohmann::json list = nlohmann::json::array();
  for (std::uint32_t p = 0; p < shown; ++p) {
    if (parts.named())
      std::printf("  part %u: %s (%s), %llu triangles\n", p, parts.path(p).c_str(), parts.name(p).c_str(),
                  (unsigned long long)parts.triangles(p));
    else
      std::printf("  part %u: %s (triangles not recorded)\n", p, parts.path(p).c_str());
    list.push_back({{"part", p}, {"path", parts.path(p)}, {"name", parts.name(p)}, {"triangles", parts.named() ? nlohmann::json(parts.triangles(p)) : nlohmann::json(nullptr)}});
  }
  if (shown < parts.count()) std::printf("  ... %zu more (--parts 0 lists every part)\n", parts.count() - shown);
  return {{"length_unit", header.length_unit},
          {"tessellation_deflection", header.tessellation_deflection},
          {"parts", parts.count()},
          {"part_list", list}};
}

struct InteriorFigures {
  std::string text;
  nlohmann::json json;
};

// The connected components (their part and closedness) and what the interiors tables hold
// (preprocess --interiors): tets inside a closed component, undecided tets.
InteriorFigures component_figures(const IndexReader& reader, const IndexSummary& summary) {
  char line[512];
  std::snprintf(line, sizeof line, "components: %llu in %llu parts (%llu closed, %llu open)",
                (unsigned long long)summary.components, (unsigned long long)summary.parts,
                (unsigned long long)summary.closed_components,
                (unsigned long long)(summary.components - summary.closed_components));
  std::string text = line;
  nlohmann::json json = nlohmann::json::object();
  if (!summary.interiors)
    return {text + "\ninteriors: not stored (objects inside obstacles go unseen)", json};
  const auto offsets = reader.read_table_uint64(schema::table::interior_offsets);
  const auto inside_of = reader.read_table_uint32(schema::table::interior_components);
  std::uint64_t inside = 0, undecided = 0;
  for (std::size_t t = 0; t + 1 < offsets.size() && t < summary.tets; ++t) {
    if (offsets[t + 1] == offsets[t]) continue;
    if (offsets[t + 1] - offsets[t] == 1 && offsets[t] < inside_of.size() && inside_of[offsets[t]] == 0xffffffffu) ++undecided;
    else ++inside;
  }
  std::snprintf(line, sizeof line, "\ninteriors: %llu tets with their reference point inside a closed component, %llu undecided",
                (unsigned long long)inside, (unsigned long long)undecided);
  json = {{"interior_tets_inside", inside}, {"interior_tets_undecided", undecided}};
  return {text + line, json};
}

void run_inspect(const InspectArguments& args) {
  check_outputs_writable({args.report}, {args.index});
  const IndexReader reader(args.index);
  const IndexSummary summary = IndexSummary::of(reader);
  const TetMesh mesh = reader.read_mesh();
  const double triangles = double(std::max<std::uint64_t>(1, summary.triangles));
  std::printf("index %s: format version %u, %s coordinates, %s on disk\n", args.index.c_str(),
              summary.version, summary.precision.c_str(),
              format_byte_size(summary.file_bytes).c_str());
  std::printf("model: %llu triangles, bounds [%g %g %g]-[%g %g %g]\n",
              (unsigned long long)summary.triangles, summary.bounds.lo[0], summary.bounds.lo[1],
              summary.bounds.lo[2], summary.bounds.hi[0], summary.bounds.hi[1],
              summary.bounds.hi[2]);
  std::printf("%s\n", summary.storage.c_str());
  std::printf("coarse mesh: %zu vertices, %llu tets (%llu empty)\n", mesh.vertices.size(),
              (unsigned long long)summary.tets,
              (unsigned long long)(summary.tets - summary.shards));
  std::printf(
      "shards: %llu (grid %llu, rtree %llu), %llu stored triangles (duplication %.3f), largest %s "
      "(%u triangles max)\n",
      (unsigned long long)summary.shards, (unsigned long long)summary.grid_shards,
      (unsigned long long)summary.rtree_shards, (unsigned long long)summary.stored_triangles,
      double(summary.stored_triangles) / triangles,
      format_byte_size(summary.largest_shard_bytes).c_str(), summary.largest_shard_triangles);
  std::printf(
      "bytes: shards on disk %s (%.1f B/triangle; grid %s, rtree %s), decoded %s (%.1f "
      "B/triangle)\n",
      format_byte_size(summary.shard_stored_bytes).c_str(),
      double(summary.shard_stored_bytes) / triangles,
      format_byte_size(summary.grid_stored_bytes).c_str(),
      format_byte_size(summary.rtree_stored_bytes).c_str(),
      format_byte_size(summary.shard_decoded_bytes).c_str(),
      double(summary.shard_decoded_bytes) / triangles);
  const nlohmann::json part_json = part_figures(reader, args.parts_listed);
  const InteriorFigures interiors = component_figures(reader, summary);
  std::printf("%s\n", interiors.text.c_str());
  std::optional<StabbingNumbers> stabbing;
  if (args.stabbing_segments > 0) {
    // The study's section 4.2.1 "unit cube" is the model's own box.
    const EmbreeMeshFaces faces(mesh);
    StabbingOptions options;
    options.segments = args.stabbing_segments;
    options.seed = args.stabbing_seed;
    stabbing = measure_stabbing_numbers(faces, summary.bounds, options);
    std::printf("stabbing number (study 4.2.1: %llu random segments in the model box, tets met per unit length): "
                "walk %.3f, Embree %.3f; %.2f tets per segment of mean length %.4g; %llu segments differ (%.2f s)\n",
                (unsigned long long)stabbing->segments, stabbing->walk, stabbing->embree,
                stabbing->walk_tets_per_segment, stabbing->mean_length,
                (unsigned long long)stabbing->differing, stabbing->seconds);
    for (const StabbingDifference& d : stabbing->differences)
      std::printf("stabbing difference: (%.17g, %.17g, %.17g) -> (%.17g, %.17g, %.17g): walk %llu tets, Embree %llu\n",
                  d.a[0], d.a[1], d.a[2], d.b[0], d.b[1], d.b[2], (unsigned long long)d.walk_tets,
                  (unsigned long long)d.embree_tets);
    if (stabbing->incomplete_walks > 0)
      std::printf("stabbing: %llu segments left the mesh\n", (unsigned long long)stabbing->incomplete_walks);
  }
  if (!args.report.empty()) {
    nlohmann::json report = nlohmann::json::parse(summary.to_json());
    report.update(interiors.json);
    report["part_list"] = part_json.at("part_list");
    if (stabbing) {
      report["stabbing_segments"] = stabbing->segments;
      report["stabbing_number_walk"] = stabbing->walk;
      report["stabbing_number_embree"] = stabbing->embree;
      report["stabbing_segments_differing"] = stabbing->differing;
      report["stabbing_tets_per_segment"] = stabbing->walk_tets_per_segment;
      report["stabbing_mean_length"] = stabbing->mean_length;
      report["stabbing_seconds"] = stabbing->seconds;
    }
    write_report(args.report, report);
  }
}

// Everything an index promises, checked; returns the problems found.
std::vector<std::string> validate_index(const IndexReader& reader) {
  // Every shard decoded as the reader checks its chunks (one read and decompression of the data);
  // what the tables must agree with is kept.
  struct Decoded {
    std::uint32_t triangles = 0;
    BoundingBox bounds;
    std::string problem;  ///< the decoder's, if it failed
  };
  std::vector<Decoded> decoded(reader.shard_count());
  std::vector<std::string> problems = reader.validate([&](std::uint32_t s, std::span<const std::byte> payload) {
    try {
      const Shard shard = Shard::decode(payload);
      decoded[s].triangles = shard.triangle_count();
      decoded[s].bounds = shard.bounds();
    } catch (const Error& error) {
      decoded[s].problem = error.what();
    }
  });
  if (!problems.empty()) return problems;
  const TetMesh mesh = reader.read_mesh();  // checks every vertex and neighbour index
  auto problem = [&](std::string text) {
    if (problems.size() < 100) problems.push_back(std::move(text));
  };
  for (std::size_t t = 0; t < mesh.tet_count(); ++t) {
    const auto c = mesh.corners(t);
    if (geometry::orient3d(c[0], c[1], c[2], c[3]) != geometry::Sign::positive)
      problem("tet " + std::to_string(t) + " is not positively oriented");
    for (int i = 0; i < 4; ++i) {
      const std::uint32_t n = mesh.neighbours[t][i];
      if (n == TetMesh::no_neighbour) continue;
      bool back = false;
      for (int j = 0; j < 4; ++j) back |= mesh.neighbours[n][j] == t;
      if (!back) problem("tets " + std::to_string(t) + " and " + std::to_string(n) + " are not mutual neighbours");
    }
  }
  const auto tet_shard = reader.read_table_uint32(schema::table::tet_shard);
  const auto shard_tet = reader.read_table_uint32(schema::table::shard_tet);
  const auto shard_triangles = reader.read_table_uint32(schema::table::shard_triangles);
  const auto shard_bounds = reader.read_table_double(schema::table::shard_bounds);
  if (tet_shard.size() != mesh.tet_count()) problem("tet_shard has " + std::to_string(tet_shard.size()) + " entries");
  if (shard_tet.size() != reader.shard_count() || shard_triangles.size() != reader.shard_count() ||
      shard_bounds.size() != 6 * std::size_t(reader.shard_count()))
    problem("shard tables do not have one entry per shard");
  if (!problems.empty()) return problems;
  for (std::uint32_t s = 0; s < reader.shard_count(); ++s) {
    if (shard_tet[s] >= tet_shard.size() || tet_shard[shard_tet[s]] != s)
      problem("shard " + std::to_string(s) + " and tet " + std::to_string(shard_tet[s]) + " do not name each other");
    const Decoded& shard = decoded[s];
    if (!shard.problem.empty()) {
      problem("shard " + std::to_string(s) + ": " + shard.problem);
      continue;
    }
    if (shard.triangles != shard_triangles[s])
      problem("shard " + std::to_string(s) + " holds " + std::to_string(shard.triangles) +
              " triangles, the table says " + std::to_string(shard_triangles[s]));
    // The runtime skips a shard by these bounds without reading it: they must hold it.
    for (int a = 0; a < 3; ++a)
      if (shard.triangles > 0 &&
          (shard.bounds.lo[a] < shard_bounds[6 * s + a] || shard.bounds.hi[a] > shard_bounds[6 * s + 3 + a]))
        problem("shard " + std::to_string(s) + " reaches beyond its /tables/shard_bounds on axis " +
                std::to_string(a));
  }
  // Interiors: the runtime's checks at open (all four tables, consistent), and every reference
  // point strictly inside its tet (the crossings are counted within the tet).
  const auto names = reader.table_names();
  if (std::find(names.begin(), names.end(), schema::table::interior_offsets) != names.end()) {
    const auto points = reader.read_table_double(schema::table::reference_points);
    for (std::size_t t = 0; t < mesh.tet_count() && 3 * t + 2 < points.size(); ++t) {
      const geometry::Point p{points[3 * t], points[3 * t + 1], points[3 * t + 2]};
      if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) continue;  // undecided
      if (geometry::locate_in_tetrahedron(p, mesh.corners(t)).position != geometry::TetrahedronPosition::inside)
        problem("the reference point of tet " + std::to_string(t) + " is not strictly inside it");
    }
    try {
      CollisionIndex opened(reader.path(), {});
    } catch (const Error& error) {
      problem(std::string("interiors: ") + error.what());
    }
  }
  return problems;
}

struct ValidateArguments {
  std::filesystem::path index;
  std::vector<std::filesystem::path> inputs;
  bool full = false;
  std::uint32_t sample = 256;
  std::uint32_t boxes = 16;
  std::uint64_t seed = 1;
};

// `count` distinct values below `n` (all of them when count >= n or `all`), sorted.
std::vector<std::uint32_t> sample_below(std::uint32_t n, std::uint32_t count, bool all, std::uint64_t seed) {
  Random random(seed);
  std::vector<std::uint32_t> chosen = random_subset(n, all ? n : std::min(count, n), random);
  std::sort(chosen.begin(), chosen.end());
  return chosen;
}

void run_validate(const ValidateArguments& args) {
  const IndexReader reader(args.index);
  auto problems = validate_index(reader);
  for (const auto& p : problems) std::printf("problem: %s\n", p.c_str());
  if (!problems.empty())
    throw FormatError(args.index.string() + ": invalid index (" + std::to_string(problems.size()) + " problems)");
  // Against brute force: a sample of tets against the model, a sample of shards against random
  // boxes (everything with --full).
  const auto tet_count = std::uint32_t(reader.header().region_count);
  AuditFindings findings;
  {
    const auto shards = sample_below(reader.shard_count(), args.sample, args.full, args.seed + 1);
    Progress progress("checking shard queries", shards.size(), true);
    audit_shard_queries(reader, shards, args.boxes, args.seed, findings, progress);
    progress.finish();
  }
  std::vector<std::filesystem::path> inputs = args.inputs.empty() ? source_inputs(reader.header(), args.index) : args.inputs;
  std::string missing;
  for (const auto& input : inputs)
    if (!std::filesystem::exists(input)) missing = input.string();
  const bool check_model = missing.empty() || !args.inputs.empty() || args.full;
  if (check_model) {
    const auto tets = sample_below(tet_count, args.sample, args.full, args.seed);
    const std::vector<InputPiece> model = input_pieces(inputs);
    Progress progress("checking tets against the model", model.size(), true);
    audit_binning(reader, model, tets, findings, progress);
    progress.finish();
  }
  for (const auto& p : findings.problems) std::printf("problem: %s\n", p.c_str());
  std::printf("shard queries: %llu shards x %u random boxes against brute force (CGAL exact), %llu mismatches\n",
              (unsigned long long)findings.shards_checked, args.boxes, (unsigned long long)findings.mismatches);
  if (check_model)
    std::printf("binning: %llu tets against the model's %llu triangles (CGAL exact), %s\n",
                (unsigned long long)findings.tets_checked, (unsigned long long)findings.triangles_read,
                findings.mismatches == 0 ? "all equal" : "see the problems above");
  else
    std::printf("binning: not checked, input '%s' not found (give the inputs after the index)\n", missing.c_str());
  if (findings.mismatches > 0)
    throw FormatError(args.index.string() + ": invalid index (" + std::to_string(findings.mismatches) +
                      " mismatches against brute force)");
  std::printf("%s: valid (%u shards, %llu triangles)\n", args.index.c_str(), reader.shard_count(),
              (unsigned long long)reader.header().input_triangles);
}

}  // namespace

void add_index_commands(CLI::App& app) {
  auto pre = std::make_shared<PreprocessArguments>();
  auto* command = app.add_subcommand(
      "preprocess",
      "Cut an assembly into a coarse tetrahedral mesh of regions, each with a grid or R-tree\n"
      "shard of the triangles it meets (exact test), and write one HDF5 index.\n"
      "The index is written under a temporary name and renamed only when complete.");
  command
      ->add_option("inputs", pre->inputs,
                   "Mesh files (obj, stl, ply, off, gltf, glb, ...), STEP or IGES files, or "
                   "manifests (.json)")
      ->required()
      ->check(existing_file_check());
  command
      ->add_option("-o,--output", pre->output,
                   "The index file to write (model.tpi; not a mesh's, a picture's, a CSV or a JSON "
                   "file's name)")
      ->required()
      ->check(index_output_check());
  command->add_option("--region-triangles", pre->region_triangles,
                      "Target triangles per region; 0 (the default): 4096, or the model's triangles / 12,000 "
                      "when larger, so that the coarse mesh stays near 100k tets")
      ->capture_default_str()
      ->check(whole_number_check(0, 1ll << 30));
  add_memory_option(
      command, pre->memory,
      "Working-memory budget of the stages' data, at least 16M: larger models spill to disk\n"
      "next to the output. Peak RSS stays within it + what the process held before any work\n"
      "(libraries, about 48 MiB) + 64 MiB for the files being read (a file placed many times\n"
      "is placed in batches; one file's own soup is held whole while it is read: a file too\n"
      "large for that is refused before it is read, naming the --memory it needs); the\n"
      "summary states the three and the peak",
      kLeastPreprocessMemory);
  command->add_option("--threads", pre->threads, "Worker threads (0: all cores)")
      ->capture_default_str()
      ->check(whole_number_check(0, kMostThreads));
  command->add_option("--shard", pre->shard, "Shard kind: auto (measured cost model), grid or rtree")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "grid", "rtree"}));
  command->add_option("--precision", pre->precision,
                      "Stored coordinates: exact (each shard decodes to the coordinates read: 4-byte floats\n"
                      "where that is lossless, as for float input, else doubles), double (8 bytes always),\n"
                      "or float (rounded to compact floats, by up to the reported max rounding distance:\n"
                      "answers are then exact for the rounded model, not the input)")
      ->capture_default_str()
      ->check(CLI::IsMember({"exact", "float", "double"}));
  command->add_option("--compression", pre->compression,
                      "Shard chunks: lz4 (shuffled and compressed: the smaller file) or none (stored as they\n"
                      "are: about a third larger, but a page-in read from the page cache skips the\n"
                      "decompression, a third of its time)")
      ->capture_default_str()
      ->check(CLI::IsMember({"lz4", "none"}));
  command
      ->add_option("--query-extent", pre->query_extent,
                   "Side of the query boxes the cost model plans for (0: 5% of the model's size)")
      ->capture_default_str()
      ->check(number_check(0, kLongestLength));
  command->add_option("--interiors", pre->interiors,
                      "Classify each region's reference point against the closed components (connected\n"
                      "surfaces whose every edge is used an even number of times; exact ray parity, one pass\n"
                      "over the triangles) so that the runtime reports an object inside an obstacle")
      ->capture_default_str()
      ->check(CLI::IsMember({"on", "off"}));
  command->add_flag("--accept-undecided", pre->accept_undecided,
                   "Store a region whose inside cannot be decided (every reference point tried lies on a\n"
                   "closed surface) as undecided, where containment is then unknown, instead of failing");
  command
      ->add_option(
          "--unit", pre->unit,
          "Length unit of inputs that state none (plain meshes): m, cm, mm, um, in or ft; STEP "
          "and IGES are read in mm and a manifest states its units; recorded in the index")
      ->check(parsed_by([](const std::string& unit) { metres_per_unit(unit); }, "UNIT"));
  pre->tessellation.add_to(command);
  command->add_option("--report", pre->report, "Write the summary as JSON");
  command->callback([pre] { run_preprocess(*pre); });

  auto inspect = std::make_shared<InspectArguments>();
  auto* inspect_command = app.add_subcommand("inspect", "Show what an index holds and where its bytes go");
  inspect_command->add_option("index", inspect->index, "Index file (.tpi)")
      ->required()
      ->check(existing_file_check());
  inspect_command->add_option("--report", inspect->report, "Write the figures as JSON");
  inspect_command->add_option("--parts", inspect->parts_listed, "Parts listed (0: every part)")
      ->capture_default_str()
      ->check(whole_number_check(0, 1'000'000'000));
  inspect_command
      ->add_option(
          "--stabbing-segments", inspect->stabbing_segments,
          "Random segments for the stabbing number, counted by the walk and by Embree (0: skip)")
      ->capture_default_str()
      ->check(whole_number_check(0, kMostPoints));
  inspect_command->add_option("--stabbing-seed", inspect->stabbing_seed, "Seed of those segments")
      ->capture_default_str()
      ->check(seed_check());
  inspect_command->callback([inspect] { run_inspect(*inspect); });

  auto valid = std::make_shared<ValidateArguments>();
  auto* validate = app.add_subcommand(
      "validate",
      "Check an index from end to end: checksums, extents, mesh orientation and adjacency, shard\n"
      "tables, every shard decoded; then against brute force (CGAL's exact kernel): a sample of tets\n"
      "hold exactly the model's triangles that meet them, and a sample of shards answer random boxes\n"
      "with exactly the stored triangles that meet them (--full: every tet and shard). The model is\n"
      "read from the files the index names, or from the INPUTs given. Exit 0 only when valid.");
  validate->add_option("index", valid->index, "Index file (.tpi)")
      ->required()
      ->check(existing_file_check());
  validate
      ->add_option(
          "inputs", valid->inputs,
          "The model's files, in preprocess's order (default: those the index names; when they\n"
          "are missing, the binning check is skipped and said so, unless --full)")
      ->check(existing_file_check());
  validate->add_flag("--full", valid->full, "Check every tet and every shard, not a sample");
  validate->add_option("--sample", valid->sample, "Tets and shards checked without --full")
      ->capture_default_str()
      ->check(whole_number_check(0, 1'000'000'000));
  validate->add_option("--boxes", valid->boxes, "Random query boxes per shard checked")
      ->capture_default_str()
      ->check(whole_number_check(0, 1'000'000));
  validate->add_option("--seed", valid->seed, "Seed of the samples and boxes")
      ->capture_default_str()
      ->check(seed_check());
  validate->callback([valid] { run_validate(*valid); });
}

}  // namespace tetrapage::cli
