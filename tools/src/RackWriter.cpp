// generate_rack: the board types laid out, the boards counted, and the manifests, the plate and
// the insertion flight written (RackGenerator.h).

#include <algorithm>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>

#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/tools/RackGenerator.h"
#include "tetrapage/tools/ReportFile.h"

namespace tetrapage {
namespace {

// board_placement's rotation (x -> y, y -> z, z -> x): 120 degrees about (1, 1, 1).
constexpr std::array<double, 4> kUprightRotation{0.5, 0.5, 0.5, 0.5};
// Half a turn about x: the plug turned over, its pins' side facing the board.
constexpr std::array<double, 4> kTurnOver{0.0, 1.0, 0.0, 0.0};
constexpr double kInsertClearance = 5.0;  // mm above the header where the plug starts
// Drawn after the parts, apart from them: the layouts do not change with the files skipped.
constexpr std::uint64_t kLayoutStream = 0x7261636b;

std::array<double, 4> hamilton(const std::array<double, 4>& a, const std::array<double, 4>& b) {
  return {a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
          a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
          a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
          a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]};
}

std::string type_name(std::size_t type) {
  return type < 26 ? std::string("board_") + char('a' + type) : "board_" + std::to_string(type);
}

void write_plate(const std::filesystem::path& path, const BoardOptions& board) {
  std::vector<Vec3> corners;
  for (int c = 0; c < 8; ++c)
    corners.push_back({(c & 1) ? board.length : 0.0, (c & 2) ? board.width : 0.0,
                       (c & 4) ? board.thickness : 0.0});
  // Two outward triangles per face.
  const std::vector<TriangleIndices> triangles{{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6},
                                               {0, 1, 4}, {1, 5, 4}, {2, 6, 3}, {3, 6, 7},
                                               {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  MeshWriter writer(path);
  writer.add_part(corners, triangles);
  writer.commit();
}

/// One mesh entry of a board: a file and its placements on the board.
struct BoardEntry {
  std::string name;
  std::filesystem::path file;
  std::vector<Transform> instances;
};

/// The plate, then one entry per distinct part in the order of first placement (the connector
/// is parts.size()).
std::vector<BoardEntry> board_entries(const BoardLayout& layout, std::span<const RackPart> parts,
                                      const RackPart* connector) {
  std::vector<BoardEntry> entries{{"plate", "plate.ply", {identity_transform()}}};
  std::map<std::size_t, std::size_t> entry_of;
  std::map<std::string, int> names;
  for (const PlacedPart& placed : layout.parts) {
    const RackPart& part = placed.part < parts.size() ? parts[placed.part] : *connector;
    auto [it, inserted] = entry_of.emplace(placed.part, entries.size());
    if (inserted) {
      // Two folders may hold one stem: entry names must be unique in a manifest.
      const int seen = names[part.name]++;
      entries.push_back(
          {seen == 0 ? part.name : part.name + "~" + std::to_string(seen + 1), part.file, {}});
    }
    entries[it->second].instances.push_back(placed.transform);
  }
  return entries;
}

nlohmann::json instances_json(const std::vector<Transform>& transforms) {
  nlohmann::json out = nlohmann::json::array();
  for (const Transform& m : transforms) out.push_back({{"matrix", m}});
  return out;
}

/// The entries as manifest parts; `prefix` before names and `folder` before relative files,
/// each placement composed after every one of `outer` (none: as they are).
nlohmann::json entries_json(const std::vector<BoardEntry>& entries, const std::string& prefix,
                            const std::filesystem::path& folder,
                            const std::vector<Transform>& outer) {
  nlohmann::json parts = nlohmann::json::array();
  for (const BoardEntry& entry : entries) {
    std::vector<Transform> placements;
    if (outer.empty()) placements = entry.instances;
    for (const Transform& o : outer)
      for (const Transform& m : entry.instances) placements.push_back(compose_transforms(o, m));
    const std::filesystem::path file = entry.file.is_absolute() ? entry.file : folder / entry.file;
    parts.push_back({{"name", prefix + entry.name},
                     {"file", file.generic_string()},
                     {"instances", instances_json(placements)}});
  }
  return parts;
}

void check_rack_options(const RackOptions& options) {
  if (options.board_types == 0 || options.slots == 0 || options.cages == 0)
    throw InputError("generate rack: --board-types, --slots and --cages must be at least 1");
  if (!(options.pitch > options.board.thickness))
    throw InputError("generate rack: --pitch " + std::to_string(options.pitch) +
                     " mm is not above the plate's thickness");
  if (options.triangles == 0) throw InputError("generate rack: --triangles must be at least 1");
  if (!options.connector.empty() && !options.plug.empty() && options.insert_steps < 2)
    throw InputError("generate rack: --insert-steps must be at least 2");
}

/// Boards (types in turn) until the target is reached; their placements and box.
void plan_boards(const RackOptions& options, RackSummary& summary) {
  std::vector<BoundingBox> type_boxes;
  for (const BoardLayout& layout : summary.types) {
    BoundingBox box;
    box.extend(Vec3{0, 0, 0});
    box.extend(Vec3{options.board.length, options.board.width, options.board.thickness});
    for (const PlacedPart& placed : layout.parts) box.extend(placed.box);
    type_boxes.push_back(box);
  }
  constexpr std::size_t kMaxBoards = 1000000;
  while (summary.triangles < options.triangles) {
    if (summary.boards == kMaxBoards)
      throw InputError("generate rack: --triangles " + std::to_string(options.triangles) +
                       " asks for more than " + std::to_string(kMaxBoards) + " boards");
    const std::size_t type = summary.boards % summary.types.size();
    const Transform placement = board_placement(options, summary.boards);
    summary.board_placements.push_back(placement);
    summary.bounds.extend(placed_box(type_boxes[type], placement));
    summary.triangles += summary.types[type].triangles;
    ++summary.boards;
  }
}

void write_rack(const RackOptions& options, const std::filesystem::path& output,
                const RackSummary& summary, const RackPart* connector) {
  const std::string boards_folder = output.stem().string() + "-boards";
  const std::filesystem::path folder = output.parent_path() / boards_folder;
  std::filesystem::create_directories(folder);
  write_plate(folder / "plate.ply", options.board);
  nlohmann::json rack_parts = nlohmann::json::array();
  for (std::size_t t = 0; t < summary.types.size(); ++t) {
    const auto entries = board_entries(summary.types[t], summary.library.parts, connector);
    std::vector<Transform> boards;
    for (std::size_t b = t; b < summary.boards; b += summary.types.size())
      boards.push_back(summary.board_placements[b]);
    if (boards.empty()) continue;
    const std::string name = type_name(t);
    if (options.flat) {
      for (auto& part : entries_json(entries, name + ".", boards_folder, boards))
        rack_parts.push_back(part);
      continue;
    }
    write_report(folder / (name + ".json"),
                 {{"units", "mm"}, {"parts", entries_json(entries, "", {}, {})}});
    rack_parts.push_back(
        {{"name", name},
         {"manifest", (std::filesystem::path(boards_folder) / (name + ".json")).generic_string()},
         {"instances", instances_json(boards)}});
  }
  write_report(output, {{"units", "mm"}, {"parts", rack_parts}});
}

}  // namespace

std::size_t insertion_board(const RackOptions& options, std::size_t boards) {
  return std::min(options.slots, boards) - 1;
}

std::vector<Pose> insertion_flight(const RackOptions& options, std::size_t board_index,
                                   const BoundingBox& header, const RackPart& plug) {
  BoundingBox turned;  // the plug's box turned over: y and z negated
  turned.extend(Vec3{plug.box.lo[0], -plug.box.hi[1], -plug.box.hi[2]});
  turned.extend(Vec3{plug.box.hi[0], -plug.box.lo[1], -plug.box.lo[2]});
  const Vec3 hc = header.center(), pc = turned.center();
  const Transform board = board_placement(options, board_index);
  const std::array<double, 4> rotation = hamilton(kUprightRotation, kTurnOver);
  const double start = header.hi[2] + kInsertClearance,
               travel = kInsertClearance + options.insert_depth;
  std::vector<Pose> poses;
  for (std::size_t s = 0; s < options.insert_steps; ++s) {
    const double bottom = start - travel * double(s) / double(options.insert_steps - 1);
    const Vec3 on_board{hc[0] - pc[0], hc[1] - pc[1], bottom - turned.lo[2]};
    poses.push_back({apply_transform(board, on_board), rotation});
  }
  return poses;
}

RackSummary generate_rack(const RackOptions& options, const std::filesystem::path& output,
                          Progress& progress) {
  check_rack_options(options);
  check_outputs_writable({output}, {});
  RackSummary summary;
  summary.library = load_rack_parts(options.parts, progress);
  std::optional<RackPart> connector, plug;
  if (!options.connector.empty())
    connector = read_rack_part(options.connector, options.parts.tessellation);
  if (connector && !options.plug.empty())
    plug = read_rack_part(options.plug, options.parts.tessellation);
  Random random(options.parts.seed ^ kLayoutStream);
  for (std::size_t t = 0; t < options.board_types; ++t)
    summary.types.push_back(layout_board(summary.library.parts, options.board, random,
                                         connector ? &*connector : nullptr));
  plan_boards(options, summary);
  write_rack(options, output, summary, connector ? &*connector : nullptr);
  if (plug) {
    summary.insertion_poses = output.parent_path() / (output.stem().string() + "-insert.csv");
    summary.plug_triangles = plug->triangles;
    const std::size_t board = insertion_board(options, summary.boards);
    write_poses(summary.insertion_poses,
                insertion_flight(options, board,
                                 summary.types[board % summary.types.size()].parts[0].box, *plug));
  }
  return summary;
}

}  // namespace tetrapage
