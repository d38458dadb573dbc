// Damaged indexes that still pass their checksums: a stored coordinate changed by one bit must
// fail `validate --full`, naming the shard, triangle and coordinate; root attributes whose
// counts disagree with the tables they count must be refused by every command that opens the
// index.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <unistd.h>

#include <bit>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numeric>

#include "RunCli.h"
#include "TestFiles.h"
#include "tetrapage/formats/IndexReader.h"
#include "tetrapage/formats/IndexSchema.h"
#include "tetrapage/formats/IndexWriter.h"
#include "tetrapage/formats/MeshWriter.h"
#include "tetrapage/formats/Pose.h"
#include "tetrapage/preprocess/Preprocess.h"
#include "tetrapage/runtime/Shard.h"
#include "tetrapage/tools/TetrasGenerator.h"

namespace tetrapage {
namespace {

namespace fs = std::filesystem;

struct Model {
  fs::path folder, mesh, index;
};

// Random tetrahedra's faces (double coordinates), preprocessed into about 20 shards.
const Model& model() {
  static const Model built = [] {
    Model m;
    m.folder = fs::path(TETRAPAGE_TEST_TMP) / ("integrity-" + std::to_string(::getpid()));
    fs::remove_all(m.folder);
    fs::create_directories(m.folder);
    m.mesh = m.folder / "tetras.ply";
    TetrasOptions options;
    options.triangles = 800;
    options.seed = 35;
    MeshWriter writer(m.mesh);
    generate_tetras(options, writer);
    writer.commit();
    m.index = m.folder / "tetras.tpi";
    PreprocessOptions preprocess_options;
    preprocess_options.region_triangles = 60;
    preprocess(std::vector<fs::path>{m.mesh}, m.index, preprocess_options);
    return m;
  }();
  return built;
}

// Copies `good` to `path` through the writer (so every checksum is right), each shard's payload
// passed through `edit`.
void rewrite_index(const IndexReader& good, const fs::path& path,
                   const std::function<void(std::uint32_t, std::vector<std::byte>&)>& edit) {
  IndexWriter writer(path);
  writer.write_mesh(good.read_mesh());
  for (const std::string& name : good.table_names()) {
    // Each table by the one reader that accepts its type.
    try {
      writer.write_table(name, std::span<const std::uint32_t>(good.read_table_uint32(name)));
      continue;
    } catch (const FormatError&) {
    }
    try {
      writer.write_table(name, std::span<const double>(good.read_table_double(name)));
      continue;
    } catch (const FormatError&) {
    }
    try {
      writer.write_table(name, std::span<const std::uint64_t>(good.read_table_uint64(name)));
      continue;
    } catch (const FormatError&) {
    }
    writer.write_table(name, std::span<const std::uint8_t>(good.read_table_uint8(name)));
  }
  for (std::uint32_t s = 0; s < good.shard_count(); ++s) {
    std::vector<std::byte> payload = good.read_shard(s);
    edit(s, payload);
    writer.append_shard(payload);
  }
  writer.commit(good.header());
}

// A coordinate one bit away from the model's: where, and the values.
struct FlippedCoordinate {
  std::size_t byte = 0;
  std::uint64_t triangle_id = 0;
  int axis = 0;
  double before = 0, after = 0;
};

// The first byte of `payload` whose lowest bit, flipped, changes one stored coordinate (the
// same vertex wherever the shard uses it) and nothing else the decoder sees: the shard still
// decodes with every check, with the same ids and bounds.
std::optional<FlippedCoordinate> find_coordinate_bit(const std::vector<std::byte>& payload) {
  const Shard good = Shard::decode(payload);
  for (std::size_t byte = 0; byte < payload.size(); ++byte) {
    std::vector<std::byte> flipped = payload;
    flipped[byte] ^= std::byte{1};
    std::optional<Shard> shard;
    try {
      shard.emplace(Shard::decode(flipped));
    } catch (const FormatError&) {
      continue;
    }
    if (shard->triangle_count() != good.triangle_count() ||
        shard->bounds().lo != good.bounds().lo || shard->bounds().hi != good.bounds().hi)
      continue;
    std::optional<FlippedCoordinate> found;
    bool other_change = false;
    for (std::uint32_t local = 0; local < good.triangle_count() && !other_change; ++local) {
      other_change = shard->triangle_id(local) != good.triangle_id(local);
      for (int corner = 0; corner < 3; ++corner)
        for (int axis = 0; axis < 3; ++axis) {
          const double before = good.triangle(local)[corner][axis],
                       after = shard->triangle(local)[corner][axis];
          if (before == after) continue;
          if (found && (found->axis != axis || found->before != before || found->after != after))
            other_change = true;
          if (!found) found = FlippedCoordinate{byte, good.triangle_id(local), axis, before, after};
        }
    }
    if (found && !other_change) return found;
  }
  return std::nullopt;
}

TEST(IndexIntegrity, ValidateFullNamesACoordinateOneBitAwayFromTheModel) {
  const Model& m = model();
  {
    std::string out;
    ASSERT_EQ(test::run_cli("validate " + m.index.string() + " --full --boxes 2", out), 0) << out;
  }
  const IndexReader good(m.index);
  ASSERT_EQ(good.header().precision, "exact");
  ASSERT_GE(good.shard_count(), 4u);
  // Shard 2 gets the flipped bit; the others are copied as they are.
  const std::uint32_t victim = 2;
  const auto flip = find_coordinate_bit(good.read_shard(victim));
  ASSERT_TRUE(flip.has_value()) << "no byte of shard 2 holds only a coordinate";
  ASSERT_NE(std::bit_cast<std::uint64_t>(flip->before), std::bit_cast<std::uint64_t>(flip->after));
  const fs::path damaged = m.folder / "flipped.tpi";
  rewrite_index(good, damaged, [&](std::uint32_t s, std::vector<std::byte>& payload) {
    if (s == victim) payload[flip->byte] ^= std::byte{1};
  });
  // The copy opens and its checksums pass: only the comparison with the model can tell.
  const IndexReader reader(damaged);
  EXPECT_EQ(reader.validate(), std::vector<std::string>{});

  std::string out;
  EXPECT_NE(test::run_cli(
                "validate " + damaged.string() + " " + m.mesh.string() + " --full --boxes 2", out),
            0)
      << out;
  const std::string named = "shard " + std::to_string(victim);
  EXPECT_NE(out.find("problem: " + named), std::string::npos) << out;
  EXPECT_NE(out.find("triangle " + std::to_string(flip->triangle_id) + " "), std::string::npos)
      << out;
  char stored[64], read[64];
  std::snprintf(stored, sizeof stored, "stored %c is %.17g", "xyz"[flip->axis], flip -> after);
  std::snprintf(read, sizeof read, "the model's %c is %.17g", "xyz"[flip->axis], flip -> before);
  EXPECT_NE(out.find(stored), std::string::npos) << out;
  EXPECT_NE(out.find(read), std::string::npos) << out;
  EXPECT_EQ(out.find(": valid ("), std::string::npos) << out;
}

}  // namespace
}  // namespace tetrapage
