// validate's checks against brute force (IndexAudit.h): they pass on a good index, sampled and
// in full, and catch a tet that lost a triangle it meets, a model that is not the index's, and
// a shard whose query misses a triangle; `tetrapage validate` runs them.

#include "tetrapage/tools/IndexAudit.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>

#include "RunCli.h"
#include "tetrapage/formats/index/IndexWriter.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/preprocess/Preprocess.h"
#include "tetrapage/preprocess/ShardBuilder.h"
#include "tetrapage/tools/MeshLibrary.h"
#include "tetrapage/tools/Random.h"
#include "tetrapage/tools/SceneGenerator.h"

namespace tetrapage {
namespace {

namespace fs = std::filesystem;

struct Indexed {
  fs::path folder, scene, index;
};

const Indexed& indexed() {
  static const Indexed model = [] {
    Indexed m;
    m.folder = fs::path(TETRAPAGE_TEST_TMP) / ("audit-" + std::to_string(::getpid()));
    fs::remove_all(m.folder);
    fs::create_directories(m.folder);
    m.scene = m.folder / "scene.ply";
    SceneOptions options;
    options.triangles = 5000;
    options.seed = 9;
    MeshWriter writer(m.scene);
    generate_scene(MeshLibrary::load_default(), options, writer);
    writer.commit();
    m.index = m.folder / "scene.tpi";
    PreprocessOptions preprocess_options;
    preprocess_options.region_triangles = 200;
    preprocess(std::vector<fs::path>{m.scene}, m.index, preprocess_options);
    return m;
  }();
  return model;
}

std::vector<std::uint32_t> all_below(std::uint32_t n) {
  std::vector<std::uint32_t> all(n);
  for (std::uint32_t i = 0; i < n; ++i) all[i] = i;
  return all;
}

TEST(IndexAudit, AGoodIndexPassesInFull) {
  const IndexReader reader(indexed().index);
  const TetMesh mesh = reader.read_mesh();
  ASSERT_GT(mesh.tet_count(), 30u);
  AuditFindings findings;
  audit_binning(reader, input_pieces({indexed().scene}), all_below(std::uint32_t(mesh.tet_count())), findings);
  audit_shard_queries(reader, all_below(reader.shard_count()), 24, 3, findings);
  EXPECT_EQ(findings.mismatches, 0u);
  for (const auto& p : findings.problems) ADD_FAILURE() << p;
  EXPECT_EQ(findings.tets_checked, mesh.tet_count());
  EXPECT_EQ(findings.triangles_read, reader.header().input_triangles);
  EXPECT_EQ(findings.shards_checked, reader.shard_count());
  EXPECT_EQ(findings.boxes_checked, 24u * reader.shard_count());
}

TEST(IndexAudit, ATetThatLostATriangleAndAForeignModelAreFound) {
  const IndexReader reader(indexed().index);
  const TetMesh mesh = reader.read_mesh();
  const auto tet_shard = reader.read_table_uint32("tet_shard");
  std::uint32_t victim = 0;
  while (tet_shard[victim] == TetMesh::no_neighbour) ++victim;
  const StoredIds stored = [&](std::uint32_t tet) {
    std::vector<std::uint64_t> ids;
    if (tet_shard[tet] == TetMesh::no_neighbour) return ids;
    const Shard shard = Shard::decode(reader.read_shard(tet_shard[tet]));
    for (std::uint32_t local = 0; local < shard.triangle_count(); ++local) ids.push_back(shard.triangle_id(local));
    if (tet == victim) ids.pop_back();
    return ids;
  };
  const auto tets = all_below(std::uint32_t(mesh.tet_count()));
  AuditFindings findings;
  audit_binning(mesh, tets, stored, reader.header().input_triangles, input_pieces({indexed().scene}), findings);
  ASSERT_EQ(findings.mismatches, 1u);
  EXPECT_EQ(findings.problems.at(0).rfind("tet " + std::to_string(victim) + " holds ", 0), 0u) << findings.problems[0];

  AuditFindings foreign;
  audit_binning(mesh, tets, stored, reader.header().input_triangles + 1, input_pieces({indexed().scene}), foreign);
  ASSERT_GE(foreign.problems.size(), 1u);
  EXPECT_NE(foreign.problems[0].find("not its model"), std::string::npos) << foreign.problems[0];
}

TEST(IndexAudit, AGridThatLostAReferenceIsFound) {
  // 300 small random triangles in a grid shard; one triangle's only reference is made to point
  // at another triangle, so no query can find it (the payload still decodes).
  Random random(4);
  std::vector<geometry::Triangle> triangles;
  std::vector<std::uint64_t> ids;
  std::vector<std::uint32_t> parts;
  for (std::uint64_t i = 0; i < 300; ++i) {
    geometry::Point c{random.uniform(), random.uniform(), random.uniform()};
    geometry::Triangle t;
    for (auto& p : t)
      for (int k = 0; k < 3; ++k) p[k] = c[k] + random.uniform(-0.01, 0.01);
    triangles.push_back(t);
    ids.push_back(i);
    parts.push_back(0);
  }
  std::vector<std::byte> payload =
      build_shard({triangles, ids, parts}, ShardKind::grid, StoredPrecision::float64).payload;
  const Shard good = Shard::decode(payload);
  AuditFindings clean;
  audit_shard_queries(good, "good", 64, 1, clean);
  EXPECT_EQ(clean.mismatches, 0u);

  // The references section (section 6: its offset is at byte 128 + 8 * 6; 2 bytes each here).
  std::uint64_t begin = 0, end = 0;
  std::memcpy(&begin, payload.data() + 128 + 8 * 6, 8);
  std::memcpy(&end, payload.data() + 128 + 8 * 7, 8);
  ASSERT_LT(good.triangle_count(), 65536u);
  std::vector<std::uint32_t> uses(good.triangle_count(), 0);
  const std::size_t references = good.grid_reference_count();
  ASSERT_LE(begin + 2 * references, end);
  auto reference = [&](std::size_t r) {
    std::uint16_t v = 0;
    std::memcpy(&v, payload.data() + begin + 2 * r, 2);
    return v;
  };
  for (std::size_t r = 0; r < references; ++r) ++uses[reference(r)];
  std::size_t lone = references;
  for (std::size_t r = 0; r < references && lone == references; ++r)
    if (uses[reference(r)] == 1) lone = r;
  ASSERT_LT(lone, references) << "some triangle must sit in one cell only";
  const std::uint16_t other = std::uint16_t((reference(lone) + 1) % good.triangle_count());
  std::memcpy(payload.data() + begin + 2 * lone, &other, 2);
  const Shard broken = Shard::decode(payload);  // still a valid payload
  AuditFindings findings;
  audit_shard_queries(broken, "broken", 400, 1, findings);
  ASSERT_GT(findings.mismatches, 0u);
  EXPECT_EQ(findings.problems.at(0).rfind("broken: the query of box", 0), 0u) << findings.problems[0];
  EXPECT_NE(findings.problems[0].find("misses 1 and adds 0"), std::string::npos) << findings.problems[0];
}

TEST(ValidateCommand, ChecksAgainstBruteForceSampledAndInFull) {
  const Indexed& m = indexed();
  std::string out;
  ASSERT_EQ(test::run_cli("validate " + m.index.string() + " --sample 20 --boxes 4", out), 0) << out;
  EXPECT_NE(out.find("shard queries: 20 shards x 4 random boxes"), std::string::npos) << out;
  EXPECT_NE(out.find("binning: 20 tets against the model's"), std::string::npos) << out;
  EXPECT_NE(out.find(": valid ("), std::string::npos) << out;
  ASSERT_EQ(test::run_cli("validate " + m.index.string() + " --full --boxes 2", out), 0) << out;
  EXPECT_NE(out.find("all equal"), std::string::npos) << out;
  // The wrong model: the check fails and says why.
  const fs::path other = m.folder / "other.ply";
  {
    SceneOptions options;
    options.triangles = 3000;
    options.seed = 10;
    MeshWriter writer(other);
    generate_scene(MeshLibrary::load_default(), options, writer);
    writer.commit();
  }
  EXPECT_NE(test::run_cli("validate " + m.index.string() + " " + other.string() + " --sample 20", out), 0);
  EXPECT_NE(out.find("not its model"), std::string::npos) << out;
}

// A copy of the good index, written again with shard 0's payload replaced by bytes that pass
// the chunk checksums but are no shard, and shard 1's triangle count in /tables/shard_triangles
// off by one: validate decodes every shard as it checks the chunks and must name both.
TEST(ValidateCommand, AShardThatDoesNotDecodeAndATableThatDisagreesAreNamed) {
  const Indexed& m = indexed();
  const IndexReader good(m.index);
  ASSERT_GE(good.shard_count(), 2u);
  const fs::path broken = m.folder / "broken-shards.tpi";
  {
    IndexWriter writer(broken);
    writer.write_mesh(good.read_mesh());
    for (const std::string& name : good.table_names()) {
      // Each table by the one reader that accepts its type.
      try {
        auto values = good.read_table_uint32(name);
        if (name == "shard_triangles") values[1] += 1;
        writer.write_table(name, std::span<const std::uint32_t>(values));
        continue;
      } catch (const FormatError&) {
      }
      try {
        const auto values = good.read_table_double(name);
        writer.write_table(name, std::span<const double>(values));
        continue;
      } catch (const FormatError&) {
      }
      try {
        const auto values = good.read_table_uint64(name);
        writer.write_table(name, std::span<const std::uint64_t>(values));
        continue;
      } catch (const FormatError&) {
      }
      const auto values = good.read_table_uint8(name);
      writer.write_table(name, std::span<const std::uint8_t>(values));
    }
    const std::vector<std::byte> not_a_shard(256, std::byte{0x5a});
    writer.append_shard(not_a_shard);
    for (std::uint32_t s = 1; s < good.shard_count(); ++s) writer.append_shard(good.read_shard(s));
    IndexHeader header = good.header();
    header.stored_triangles += 1;  // agrees with the table, so that the index opens
    writer.commit(header);
  }
  std::string out;
  EXPECT_NE(test::run_cli("validate " + broken.string() + " --sample 4 --boxes 1", out), 0) << out;
  EXPECT_NE(out.find("problem: shard 0: "), std::string::npos) << out;
  EXPECT_NE(out.find("magic"), std::string::npos) << out;
  EXPECT_NE(out.find("problem: shard 1 holds "), std::string::npos) << out;
  EXPECT_EQ(out.find("problem: shard 2"), std::string::npos) << out;
}

TEST(ValidateCommand, WithoutTheModelTheBinningCheckIsSkippedAndSaid) {
  const Indexed& m = indexed();
  const fs::path moved = m.folder / "moved";
  fs::create_directories(moved);
  fs::copy_file(m.index, moved / "copy.tpi", fs::copy_options::overwrite_existing);
  fs::rename(m.scene, m.folder / "scene-away.ply");
  std::string out, full_out;
  const int status = test::run_cli("validate " + (moved / "copy.tpi").string() + " --sample 10 --boxes 2", out);
  const int full = test::run_cli("validate " + (moved / "copy.tpi").string() + " --full --boxes 1", full_out);
  fs::rename(m.folder / "scene-away.ply", m.scene);
  EXPECT_EQ(status, 0) << out;
  EXPECT_NE(out.find("binning: not checked, input '" + m.scene.string() + "' not found"), std::string::npos) << out;
  EXPECT_NE(full, 0) << "--full needs the model: " << full_out;
}

}  // namespace
}  // namespace tetrapage
