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
#include "tetrapage/formats/index/IndexReader.h"
#include "tetrapage/formats/index/IndexSchema.h"
#include "tetrapage/formats/index/IndexWriter.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/formats/mesh/Pose.h"
#include "tetrapage/preprocess/Preprocess.h"
#include "tetrapage/runtime/paging/Shard.h"
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

// A copy of the model's index with the root attribute `name` set to `value` by HDF5 (which keeps
// the metadata's checksums right).
fs::path with_attribute(const std::string& name, std::uint64_t value) {
  const fs::path path = model().folder / (name + "-" + std::to_string(value) + ".tpi");
  fs::copy_file(model().index, path, fs::copy_options::overwrite_existing);
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  EXPECT_GE(file, 0);
  const hid_t attribute = H5Aopen_by_name(file, "/", name.c_str(), H5P_DEFAULT, H5P_DEFAULT);
  EXPECT_GE(attribute, 0) << name;
  EXPECT_GE(H5Awrite(attribute, H5T_NATIVE_UINT64, &value), 0);
  H5Aclose(attribute);
  H5Fclose(file);
  return path;
}

void expect_one_line_refusal(const test::CliResult& run, const std::vector<std::string>& parts) {
  EXPECT_NE(run.status, 0) << run.out;
  EXPECT_NE(run.status, 124) << "timed out";
  ASSERT_FALSE(run.err.empty());
  EXPECT_EQ(run.err.find('\n'), run.err.size() - 1) << "one line: " << run.err;
  for (const std::string& part : parts)
    EXPECT_NE(run.err.find(part), std::string::npos) << part << " in " << run.err;
}

TEST(IndexIntegrity, CountsTheHeaderStatesMustMatchTheTables) {
  const Model& m = model();
  const fs::path folder = m.folder;
  ASSERT_EQ(test::run_cli_in(folder, "generate object --triangles 4 -o object.ply", 60).status, 0);
  write_poses(folder / "flight.csv", std::vector<Pose>(3));
  const IndexReader good(m.index);
  const auto shard_triangles = good.read_table_uint32("shard_triangles");
  const std::uint64_t stored =
      std::accumulate(shard_triangles.begin(), shard_triangles.end(), std::uint64_t{0});
  const auto part_triangles = good.read_table_uint64("part_triangles");
  const std::uint64_t input =
      std::accumulate(part_triangles.begin(), part_triangles.end(), std::uint64_t{0});
  const std::uint64_t tets = good.read_mesh().tet_count();
  // The oracle: the tables as an independent reader (HDF5 through the reader's plain table
  // reads) sees them, and the header of the good index agrees.
  ASSERT_EQ(good.header().region_count, tets);
  ASSERT_EQ(good.header().stored_triangles, stored);
  ASSERT_EQ(good.header().input_triangles, input);
  ASSERT_EQ(
      test::run_cli_in(folder, "fly tetras.tpi --object object.ply --path flight.csv", 60).status,
      0);

  struct Case {
    std::string attribute;
    std::uint64_t value;
    std::string table_says;
  };
  const std::vector<Case> cases{
      {"region_count", tets + 1, "'/mesh/tets' holds " + std::to_string(tets) + " tets"},
      {"region_count", tets - 1, "'/mesh/tets' holds " + std::to_string(tets) + " tets"},
      {"stored_triangles", 0, "'/tables/shard_triangles' sums to " + std::to_string(stored)},
      {"stored_triangles", stored + 1,
       "'/tables/shard_triangles' sums to " + std::to_string(stored)},
      {"input_triangles", input - 1, "'/tables/part_triangles' sums to " + std::to_string(input)},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.attribute + " = " + std::to_string(c.value));
    const fs::path damaged = with_attribute(c.attribute, c.value);
    const std::string name = damaged.filename().string();
    const std::vector<std::string> said{name, "'" + c.attribute + "' is " + std::to_string(c.value),
                                        c.table_says};
    expect_one_line_refusal(
        test::run_cli_in(folder, "fly " + name + " --object object.ply --path flight.csv", 60),
        said);
    expect_one_line_refusal(test::run_cli_in(folder, "inspect " + name, 60), said);
    expect_one_line_refusal(
        test::run_cli_in(folder, "validate " + name + " --sample 4 --boxes 1", 60), said);
  }
}

// A manifest placing one tetrahedron (1 across) once at `x` on the x axis.
void write_placed_part(const fs::path& folder, const std::string& x) {
  std::ofstream(folder / "tetra.obj")
      << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
  std::ofstream(folder / "far.json")
      << R"({"units": "m", "parts": [{"name": "bolt", "file": "tetra.obj",
      "instances": [{"translation": [0, 0, 0]}, {"translation": [)"
      << x << R"(, 0, 0]}]}]})";
}

bool has_leftovers(const fs::path& folder) {
  for (const auto& entry : fs::directory_iterator(folder))
    if (entry.path().extension() == ".tpi" ||
        entry.path().string().find(".tmp") != std::string::npos)
      return true;
  return false;
}

TEST(IndexIntegrity, PlacementsOutOfRangeAreRefusedAtTheManifestInstance) {
  const fs::path folder = test::fresh_folder("integrity", "placements");
  // Within range: the part is placed and preprocessed.
  write_placed_part(folder, "1e6");
  ASSERT_EQ(test::run_cli_in(folder, "preprocess far.json -o near.tpi", 120).status, 0);
  fs::remove(folder / "near.tpi");
  // Beyond the coordinates the model accepts (where squared distances would overflow, and
  // far beyond): once blamed on the part file.
  for (const std::string x : {"1e160", "1e308"}) {
    write_placed_part(folder, x);
    for (const std::string command : {"preprocess far.json -o far.tpi", "mesh info far.json"}) {
      SCOPED_TRACE(command + " at " + x);
      expect_one_line_refusal(
          test::run_cli_in(folder, command, 120),
          {"far.json", "part 'bolt' (tetra.obj)", "instance 'bolt#1'",
           x == "1e160" ? "x = 1e+160" : "x = 1e+308", "accepted coordinates [-1e+150, 1e+150]"});
    }
  }
  // A pose that far out is refused by every query, naming the value and the limit (the last
  // line of stderr: fly logs its progress before it).
  write_placed_part(folder, "1e6");
  ASSERT_EQ(test::run_cli_in(folder, "preprocess far.json -o near.tpi", 120).status, 0);
  std::ofstream(folder / "far.csv") << "tx,ty,tz,qw,qx,qy,qz\n0,0,0,1,0,0,0\n0,-1e160,0,1,0,0,0\n";
  for (const std::string query : {"", " --query contacts", " --query distance", " --query toi"}) {
    SCOPED_TRACE(query);
    const std::string answers = query.empty() ? "" : " --answers a.csv";
    const test::CliResult run = test::run_cli_in(
        folder, "fly near.tpi --object tetra.obj --path far.csv" + query + answers, 120);
    EXPECT_NE(run.status, 0);
    EXPECT_NE(run.status, 124) << "timed out";
    std::string last = run.err.substr(0, run.err.size() - 1);
    last = last.substr(last.rfind('\n') + 1);
    EXPECT_NE(last.find("-1e+160"), std::string::npos) << run.err;
    EXPECT_NE(last.find("beyond 1e+150"), std::string::npos) << run.err;
  }
  fs::remove(folder / "near.tpi");
  fs::remove(folder / "a.csv");
  // Within them, but so far out that rounding flattens the part: once accepted with the part
  // flattened, or "the 9 sites span no volume" after ingesting.
  write_placed_part(folder, "1e149");
  expect_one_line_refusal(test::run_cli_in(folder, "preprocess far.json -o far.tpi", 120),
                          {"far.json", "instance 'bolt#1'", "1e+149", "loses its shape to rounding",
                           "2^36 times the part's size"});
  EXPECT_FALSE(has_leftovers(folder));
}

}  // namespace
}  // namespace tetrapage
