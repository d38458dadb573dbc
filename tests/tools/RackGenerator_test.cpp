// The rack generator (RackGenerator.h): parts laid out on a board never overlap, stand on the
// plate inside its outline, and the same seed writes the same manifests. Boards are checked in
// the assembly the manifests load to (the placed STEP triangles themselves), by brute force.
// Parts are the small STEP samples of occt-misc and freecad-common.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>

#include "tetrapage/formats/mesh/Manifest.h"
#include "tetrapage/tools/RackGenerator.h"

#include "TestFiles.h"

namespace tetrapage {
namespace {

const std::filesystem::path kIdf = "/usr/share/freecad/Mod/Idf/Idflibs";
const std::filesystem::path kScrew = "/usr/share/opencascade/data/step/screw.step";
const char* const kIdfParts[] = {"1210_SMD.stp", "SOD_523.stp", "EPL22_6_16.stp",
                                 "SMB_DO_214AA.stp", "RLF_12545.stp"};

std::filesystem::path test_folder(const std::string& name) {
  return test::fresh_folder("rack", name);
}

using test::file_bytes;

/// A parts folder of links to the samples (the generator searches a folder).
std::filesystem::path sample_parts() {
  const auto folder = test_folder("parts");
  for (const char* name : kIdfParts) std::filesystem::create_symlink(kIdf / name, folder / name);
  std::filesystem::create_symlink(kScrew, folder / "screw.step");
  return folder;
}

bool samples_present() {
  for (const char* name : kIdfParts)
    if (!std::filesystem::exists(kIdf / name)) return false;
  return std::filesystem::exists(kScrew);
}

RackOptions sample_options(const std::filesystem::path& parts, std::uint64_t seed) {
  RackOptions options;
  options.parts.folder = parts;
  options.parts.count = 6;
  options.parts.max_height = 1000;  // the screw is long: the test keeps every sample
  options.parts.max_side = 1000;
  options.parts.seed = seed;
  options.board.length = 120;
  options.board.width = 80;
  options.board_types = 2;
  options.triangles = 1;  // one board of each type is enough to write both
  return options;
}

// Closed boxes that share no point: some axis separates them.
bool disjoint(const BoundingBox& a, const BoundingBox& b) {
  for (int k = 0; k < 3; ++k)
    if (a.hi[k] < b.lo[k] || b.hi[k] < a.lo[k]) return true;
  return false;
}

/// Each placed instance's box, from its triangles' corners, by its path on the board (a STEP
/// file of several shapes gives "entry#k/shape" parts: one instance).
std::vector<std::pair<std::string, BoundingBox>> instance_boxes(const TriangleSoup& soup) {
  std::map<std::string, BoundingBox> boxes;
  for (std::size_t t = 0; t < soup.triangle_count(); ++t) {
    const std::string& path = soup.part_path(soup.part_of[t]);
    BoundingBox& box = boxes[path.substr(0, path.find('/'))];
    for (const Vec3& v : soup.corners(t)) box.extend(v);
  }
  return {boxes.begin(), boxes.end()};
}

void expect_board_laid_out(const std::filesystem::path& board, const BoardOptions& plate) {
  const TriangleSoup soup = load_inputs({board});
  const auto boxes = instance_boxes(soup);
  std::size_t parts = 0;
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    const auto& [name, box] = boxes[i];
    if (name == "plate") continue;
    ++parts;
    EXPECT_NEAR(box.lo[2], plate.thickness, 1e-9) << board << ": " << name << " not on the plate";
    EXPECT_GE(box.lo[0], 0.0) << name;
    EXPECT_GE(box.lo[1], 0.0) << name;
    EXPECT_LE(box.hi[0], plate.length) << name;
    EXPECT_LE(box.hi[1], plate.width) << name;
    for (std::size_t j = i + 1; j < boxes.size(); ++j) {
      if (boxes[j].first == "plate") continue;
      EXPECT_TRUE(disjoint(box, boxes[j].second))
          << board << ": " << name << " meets " << boxes[j].first;
    }
  }
  EXPECT_GE(parts, 2u) << board << ": the layout placed almost nothing";
}

TEST(RackGenerator, PartsOnABoardNeverOverlapAndStandOnThePlate) {
  if (!samples_present())
    GTEST_SKIP() << "occt-misc and freecad-common's STEP samples are not installed";
  const auto parts = sample_parts();
  const auto out = test_folder("layout");
  RackOptions options = sample_options(parts, 7);
  options.triangles = 200000;  // more than one board holds: both types in use
  const RackSummary summary = generate_rack(options, out / "rack.json");
  ASSERT_EQ(summary.types.size(), 2u);
  EXPECT_GE(summary.library.parts.size(), 3u) << "most samples should read";
  ASSERT_GE(summary.boards, 2u) << "both types in use";
  for (const char* type : {"board_a.json", "board_b.json"})
    expect_board_laid_out(out / "rack-boards" / type, options.board);
}

TEST(RackGenerator, SameSeedSameManifestBytes) {
  if (!samples_present())
    GTEST_SKIP() << "occt-misc and freecad-common's STEP samples are not installed";
  const auto parts = sample_parts();
  RackOptions options = sample_options(parts, 3);
  options.triangles = 40000;  // several boards of each type
  const auto first = test_folder("first"), second = test_folder("second");
  generate_rack(options, first / "rack.json");
  generate_rack(options, second / "rack.json");
  for (const char* file : {"rack.json", "rack-boards/board_a.json", "rack-boards/board_b.json",
                           "rack-boards/plate.ply"}) {
    const std::string bytes = file_bytes(first / file);
    EXPECT_FALSE(bytes.empty()) << file;
    EXPECT_EQ(bytes, file_bytes(second / file)) << file << " differs between two runs of seed 3";
  }
}

// The packing alone, on many seeds and synthetic footprints: pairwise at least `gap` apart.
TEST(RackGenerator, ShelfPackingKeepsTheGapOnManySeeds) {
  std::vector<RackPart> parts;
  Random sizes(11);
  for (int p = 0; p < 12; ++p) {
    RackPart part;
    part.box.extend(Vec3{-sizes.uniform(0, 9), -sizes.uniform(0, 9), -sizes.uniform(0, 3)});
    part.box.extend(Vec3{sizes.uniform(0.1, 9), sizes.uniform(0.1, 9), sizes.uniform(0.1, 5)});
    part.triangles = 100;
    parts.push_back(part);
  }
  BoardOptions board;
  for (std::uint64_t seed = 1; seed <= 50; ++seed) {
    Random random(seed);
    const BoardLayout layout = layout_board(parts, board, random);
    ASSERT_FALSE(layout.parts.empty()) << "seed " << seed;
    for (std::size_t i = 0; i < layout.parts.size(); ++i) {
      BoundingBox grown = layout.parts[i].box;  // grown by a bit less than the gap
      for (int k = 0; k < 2; ++k) grown.lo[k] -= 0.99 * board.gap, grown.hi[k] += 0.99 * board.gap;
      EXPECT_GE(grown.lo[0], 0.0) << "seed " << seed;
      EXPECT_LE(grown.hi[1], board.width) << "seed " << seed;
      for (std::size_t j = i + 1; j < layout.parts.size(); ++j)
        EXPECT_TRUE(disjoint(grown, layout.parts[j].box))
            << "seed " << seed << ", parts " << i << ", " << j;
    }
  }
}

// The plug starts clear of the header, 5 mm away along the board's normal, and ends inside it.
TEST(RackGenerator, InsertionFlightMovesAlongTheBoardNormalIntoTheHeader) {
  RackOptions options;
  options.insert_steps = 11;
  RackPart plug;
  plug.box.extend(Vec3{-1, -12, 0});
  plug.box.extend(Vec3{4, 1, 8.5});
  BoundingBox header;  // board frame
  header.extend(Vec3{20, 30, 1.6});
  header.extend(Vec3{25, 43, 10});
  const std::size_t board_index = insertion_board(options, 40);
  EXPECT_EQ(board_index, options.slots - 1) << "the last board of the first cage";
  const auto poses = insertion_flight(options, board_index, header, plug);
  ASSERT_EQ(poses.size(), 11u);
  const Transform board = board_placement(options, board_index);
  const BoundingBox placed_header = placed_box(header, board);
  const auto placed_plug = [&](const Pose& pose) {
    BoundingBox box;
    for (int c = 0; c < 8; ++c)
      box.extend(apply_pose(pose, {(c & 1) ? plug.box.hi[0] : plug.box.lo[0],
                                   (c & 2) ? plug.box.hi[1] : plug.box.lo[1],
                                   (c & 4) ? plug.box.hi[2] : plug.box.lo[2]}));
    return box;
  };
  const BoundingBox first = placed_plug(poses.front()), last = placed_plug(poses.back());
  // The board's normal is the rack's x: the plug comes down onto the header from +x.
  EXPECT_NEAR(first.lo[0] - placed_header.hi[0], 5.0, 1e-9);
  EXPECT_NEAR(placed_header.hi[0] - last.lo[0], options.insert_depth, 1e-9);
  for (int k = 1; k < 3; ++k) {
    EXPECT_NEAR(first.center()[k], placed_header.center()[k], 1e-9);
    EXPECT_NEAR(last.center()[k], first.center()[k], 1e-9);
    EXPECT_NEAR(first.size()[k], plug.box.size()[k == 1 ? 0 : 1], 1e-9);
  }
}

}  // namespace
}  // namespace tetrapage
