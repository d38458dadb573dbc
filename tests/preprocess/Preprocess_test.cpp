// The preprocess pipeline end to end: every tet's triangle set equals brute force (CGAL's
// exact-construction kernel as the independent oracle, through validate's audit), stored
// coordinates keep the promised rounding, a run that spills to disk under a small budget
// writes the same index as one in memory, and bad input leaves nothing behind.

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/polygon_soup_io.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <thread>

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include "../FileSizeLimit.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/index/IndexReader.h"
#include "tetrapage/formats/mesh/Manifest.h"
#include "tetrapage/formats/mesh/MeshReader.h"
#include "tetrapage/formats/mesh/MeshWriter.h"
#include "tetrapage/preprocess/Preprocess.h"
#include "tetrapage/runtime/paging/Shard.h"
#include "tetrapage/tools/IndexAudit.h"
#include "tetrapage/tools/MeshLibrary.h"
#include "tetrapage/tools/Random.h"
#include "tetrapage/tools/SceneGenerator.h"
#include "tetrapage/tools/TetrasGenerator.h"

namespace tetrapage {
namespace {

namespace fs = std::filesystem;

fs::path test_folder(const std::string& name) {
  const fs::path folder = fs::path(TETRAPAGE_TEST_TMP) / "preprocess" / name;
  fs::remove_all(folder);
  fs::create_directories(folder);
  return folder;
}

fs::path make_scene(const fs::path& folder, std::uint64_t triangles, std::uint64_t seed) {
  const fs::path path = folder / "scene.ply";
  static const MeshLibrary library = MeshLibrary::load_default();
  SceneOptions options;
  options.triangles = triangles;
  options.seed = seed;
  MeshWriter writer(path);
  generate_scene(library, options, writer);
  writer.commit();
  return path;
}

fs::path make_tetras(const fs::path& folder, std::uint64_t count, std::uint64_t seed) {
  const fs::path path = folder / "tetras.ply";
  TetrasOptions options;
  options.triangles = 4 * count;
  options.seed = seed;
  MeshWriter writer(path);
  generate_tetras(options, writer);
  writer.commit();
  return path;
}

// Each tet's shard holds exactly the triangles that meet the tet (validate's audit: CGAL's
// exact do_intersect over the model, tools/IndexAudit.h), with their input ids and parts, and
// stored coordinates within the recorded rounding distance of the input (equal in double
// precision).
void expect_tets_match_brute_force(const fs::path& input, const fs::path& index_path, bool exact_coordinates) {
  const TriangleSoup soup = read_mesh(input);
  const IndexReader index(index_path);
  const TetMesh mesh = index.read_mesh();
  EXPECT_EQ(index.header().input_triangles, soup.triangle_count());
  const double rounding = index.header().max_rounding_distance;
  if (exact_coordinates) {
    EXPECT_EQ(rounding, 0.0);
  }
  std::vector<std::uint32_t> tets(mesh.tet_count());
  for (std::uint32_t t = 0; t < tets.size(); ++t) tets[t] = t;
  AuditFindings findings;
  audit_binning(index, input_pieces({input}), tets, findings);
  EXPECT_EQ(findings.tets_checked, mesh.tet_count());
  EXPECT_EQ(findings.mismatches, 0u) << index_path;
  for (std::size_t p = 0; p < std::min<std::size_t>(findings.problems.size(), 4); ++p)
    ADD_FAILURE() << findings.problems[p];

  std::uint64_t stored = 0;
  const auto component_part = index.read_table_uint32("component_part");
  for (std::uint32_t s = 0; s < index.shard_count(); ++s) {
    const Shard shard = Shard::decode(index.read_shard(s));
    for (std::uint32_t local = 0; local < shard.triangle_count(); ++local) {
      const std::uint64_t id = shard.triangle_id(local);
      ASSERT_LT(id, soup.triangle_count());
      ASSERT_LT(shard.component_id(local), component_part.size());
      EXPECT_EQ(component_part[shard.component_id(local)], soup.part_of.empty() ? 0u : soup.part_of[id]);
      // Stored vertices: the same triangle up to the recorded rounding (as a set of corners: a
      // shard may start a triangle at another corner).
      const auto input_corners = soup.corners(id);
      for (const auto& p : shard.triangle(local)) {
        double best = 1e300;
        for (const auto& q : input_corners)
          best = std::min(best, std::hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]));
        EXPECT_LE(best, rounding * (1 + 1e-12)) << "shard " << s << " triangle " << id;  // hypot vs sqrt: an ulp
      }
    }
    stored += shard.triangle_count();
  }
  EXPECT_EQ(stored, index.header().stored_triangles);
}

TEST(Preprocess, SceneTetsHoldExactlyTheTrianglesTheyMeet) {
  const fs::path folder = test_folder("scene");
  const fs::path input = make_scene(folder, 6000, 3);
  PreprocessOptions options;
  options.region_triangles = 300;
  options.precision = StoredPrecision::float64;
  const PreprocessSummary summary = preprocess({input}, folder / "scene.tpi", options);
  EXPECT_GT(summary.regions, 20u);
  EXPECT_GT(summary.empty_regions, 0u);  // the enlarged box's corners make empty tets
  EXPECT_GE(summary.duplication_factor, 1.0);
  EXPECT_EQ(summary.grid_shards + summary.rtree_shards + summary.empty_regions, summary.regions);
  expect_tets_match_brute_force(input, folder / "scene.tpi", true);
}

TEST(Preprocess, AutomaticRegionSizeKeepsTheCoarseMeshBounded) {
  // 4096 up to 49M triangles, then about 12,000 leaves whatever the size.
  EXPECT_EQ(auto_region_triangles(1), 4096u);
  EXPECT_EQ(auto_region_triangles(10'000'000), 4096u);
  for (const std::uint64_t n : {std::uint64_t(60'000'000), std::uint64_t(100'000'000), std::uint64_t(1'000'000'000)}) {
    const std::size_t size = auto_region_triangles(n);
    EXPECT_GT(size, 4096u) << n;
    EXPECT_LE(double(n) / double(size), 12'000.0) << n;
    EXPECT_GT(double(n) / double(size), 11'999.0) << n;
  }
  // The default asks for the automatic size, and the summary says which it used.
  const fs::path folder = test_folder("auto-region");
  const fs::path input = make_scene(folder, 3000, 5);
  const PreprocessSummary summary = preprocess({input}, folder / "scene.tpi", PreprocessOptions{});
  EXPECT_EQ(summary.region_triangles, 4096u);
  EXPECT_GE(summary.regions, 1u);
}

TEST(Preprocess, TetrasWithFloatStorageAndForcedKinds) {
  const fs::path folder = test_folder("tetras");
  const fs::path input = make_tetras(folder, 400, 5);
  for (const ShardChoice choice : {ShardChoice::grid, ShardChoice::rtree}) {
    PreprocessOptions options;
    options.region_triangles = 100;
    options.shard = choice;
    options.precision = StoredPrecision::float32;
    const fs::path output = folder / (choice == ShardChoice::grid ? "grid.tpi" : "rtree.tpi");
    const PreprocessSummary summary = preprocess({input}, output, options);
    EXPECT_EQ(choice == ShardChoice::grid ? summary.rtree_shards : summary.grid_shards, 0u);
    EXPECT_GT(summary.max_rounding_distance, 0.0);  // float storage rounds
    EXPECT_LT(summary.max_rounding_distance, 1e-6);
    expect_tets_match_brute_force(input, output, false);
  }
}

// Issue 4's extreme: a model around 1e9 with detail at 1e-3. Double storage keeps every
// coordinate (the tets hold exactly what brute force finds, the stored corners equal the
// input's); float storage rounds, and says by how much.
TEST(Preprocess, AModelAt1e9WithDetailAt1e3) {
  const fs::path folder = test_folder("far");
  TriangleSoup soup = read_mesh(make_tetras(folder, 300, 8));
  for (auto& v : soup.vertices)
    for (auto& c : v) c = 1e9 + 0.02 * c;  // tetras of about 1e-3 in a box of 0.02 at 1e9
  double shortest = 1e300;
  for (std::size_t t = 0; t < soup.triangle_count(); ++t) {
    const auto c = soup.corners(t);
    for (int e = 0; e < 3; ++e)
      shortest = std::min(shortest, std::hypot(c[e][0] - c[(e + 1) % 3][0], c[e][1] - c[(e + 1) % 3][1],
                                               c[e][2] - c[(e + 1) % 3][2]));
  }
  EXPECT_LT(shortest, 2e-3);
  EXPECT_GT(shortest, 1e-5);
  const fs::path input = folder / "far.ply";
  write_mesh(input, soup);
  PreprocessOptions options;
  options.region_triangles = 100;
  options.precision = StoredPrecision::float64;
  const PreprocessSummary exact = preprocess({input}, folder / "double.tpi", options);
  EXPECT_EQ(exact.max_rounding_distance, 0.0);
  expect_tets_match_brute_force(input, folder / "double.tpi", true);
  options.precision = StoredPrecision::float32;
  const PreprocessSummary rounded = preprocess({input}, folder / "float.tpi", options);
  EXPECT_GT(rounded.max_rounding_distance, 0.0) << "float cannot hold 1e9 + detail exactly";
  EXPECT_LT(rounded.max_rounding_distance, 1e-6) << "relative to each shard's origin, it keeps the detail";
  EXPECT_NE(rounded.to_text().find("rounded to floats"), std::string::npos) << rounded.to_text();
  expect_tets_match_brute_force(input, folder / "float.tpi", false);
  // The default keeps the input. These doubles lie within 0.02 of 1e9, on its grid of 2^-23:
  // relative to an origin near them they need 18 bits, so 4-byte floats hold them exactly.
  options.precision = PreprocessOptions{}.precision;
  const PreprocessSummary as_read = preprocess({input}, folder / "exact.tpi", options);
  EXPECT_EQ(as_read.precision, "exact");
  EXPECT_EQ(as_read.max_rounding_distance, 0.0);
  EXPECT_EQ(as_read.float_shards, as_read.grid_shards + as_read.rtree_shards);
  expect_tets_match_brute_force(input, folder / "exact.tpi", true);
  // Doubles with all 53 bits in use (near 0.5, where the grid is 2^-54) keep 8 bytes.
  TriangleSoup fine = soup;
  Random random(3);
  for (auto& v : fine.vertices)
    for (auto& c : v) c = (c - 1e9) + 0.5 + random.uniform(0.0, 1e-3);
  write_mesh(folder / "fine.ply", fine);
  const PreprocessSummary fine_read = preprocess({folder / "fine.ply"}, folder / "fine.tpi", options);
  EXPECT_EQ(fine_read.max_rounding_distance, 0.0);
  EXPECT_LT(fine_read.float_shards, (fine_read.grid_shards + fine_read.rtree_shards) / 10);
  expect_tets_match_brute_force(folder / "fine.ply", folder / "fine.tpi", true);
}

// Input whose coordinates are floats (an STL, or a float PLY such as most CAD exports write):
// the default stores 4-byte floats that decode to exactly the coordinates read, so the index
// is as small as the rounded one and answers for the input, near the origin and far from it.
TEST(Preprocess, FloatInputIsStoredExactlyInFloats) {
  const fs::path folder = test_folder("float-input");
  for (const double offset : {0.0, 1e4, -3e6}) {
    TriangleSoup soup = read_mesh(make_tetras(folder, 300, 9));
    for (auto& v : soup.vertices)
      for (auto& c : v) c = double(float(offset + c));
    const fs::path input = folder / "tetras.stl";  // binary STL: float coordinates
    write_mesh(input, soup);
    PreprocessOptions options;
    options.region_triangles = 100;
    const PreprocessSummary summary = preprocess({input}, folder / "exact.tpi", options);
    EXPECT_EQ(summary.max_rounding_distance, 0.0) << offset;
    EXPECT_EQ(summary.float_shards, summary.grid_shards + summary.rtree_shards) << offset;
    expect_tets_match_brute_force(input, folder / "exact.tpi", true);
    options.precision = StoredPrecision::float64;
    const PreprocessSummary doubles = preprocess({input}, folder / "double.tpi", options);
    EXPECT_LT(summary.shard_payload_bytes, doubles.shard_payload_bytes) << offset;
  }
}

// --memory bounds the stages' data; what comes on top (the process, the file being read) is
// reported: the summary says by how much the peak exceeded the budget, or nothing when it held.
TEST(Preprocess, ABudgetIsKeptOrTheExcessIsSaid) {
  const fs::path folder = test_folder("budget");
  const fs::path input = make_tetras(folder, 50'000, 4);
  PreprocessOptions options;
  options.memory_bytes = std::uint64_t(16) << 20;
  const PreprocessSummary tight = preprocess({input}, folder / "tight.tpi", options);
  EXPECT_GT(tight.resident_at_start_bytes, 0u);
  const auto report = nlohmann::json::parse(tight.to_json());
  const std::uint64_t excess = report.at("budget_exceeded_bytes").get<std::uint64_t>();
  EXPECT_EQ(excess, tight.peak_resident_bytes > tight.memory_budget_bytes ? tight.peak_resident_bytes - tight.memory_budget_bytes : 0);
  EXPECT_EQ(tight.to_text().find("budget exceeded by") != std::string::npos, excess > 0) << tight.to_text();
  options.memory_bytes = std::uint64_t(16) << 30;
  const PreprocessSummary roomy = preprocess({input}, folder / "roomy.tpi", options);
  EXPECT_LT(roomy.peak_resident_bytes, roomy.memory_budget_bytes);
  EXPECT_EQ(roomy.to_text().find("budget exceeded"), std::string::npos) << roomy.to_text();
}

// The budget forces spill files and several buckets; the index must be the same as in memory.
TEST(Preprocess, SpillingUnderASmallBudgetWritesTheSameIndex) {
  const fs::path folder = test_folder("spill");
  // Under 87,381 triangles the sample (memory / 192 B) holds every centroid, so all runs build
  // the same coarse mesh. Under 16 MiB the triangles' copies (7 MB as records) exceed a third of
  // the budget: several buckets, held as (id, tet) pairs while the soups are in memory, or
  // spilled to disk with the soups when forced.
  const fs::path input = make_scene(folder, 80000, 7);
  PreprocessOptions in_memory;
  in_memory.region_triangles = 4000;
  in_memory.shard = ShardChoice::rtree;
  const PreprocessSummary a = preprocess({input}, folder / "memory.tpi", in_memory);
  EXPECT_FALSE(a.spilled);
  EXPECT_EQ(a.buckets, 1u);
  PreprocessOptions small = in_memory;
  small.memory_bytes = 16 << 20;
  const PreprocessSummary c = preprocess({input}, folder / "buckets.tpi", small);
  EXPECT_FALSE(c.spilled);
  EXPECT_GT(c.buckets, 1u);
  small.force_spill = true;
  const PreprocessSummary b = preprocess({input}, folder / "spilled.tpi", small);
  EXPECT_TRUE(b.spilled);
  EXPECT_GT(b.buckets, 1u);
  // No spill file is left behind.
  for (const auto& entry : fs::directory_iterator(folder))
    EXPECT_EQ(entry.path().filename().string().find(".tetrapage-spill"), std::string::npos) << entry.path();

  const IndexReader ra(folder / "memory.tpi");
  for (const char* other : {"buckets.tpi", "spilled.tpi"}) {
    const IndexReader rb(folder / other);
    ASSERT_EQ(ra.shard_count(), rb.shard_count()) << other;
    EXPECT_EQ(ra.read_table_uint32("tet_shard"), rb.read_table_uint32("tet_shard")) << other;
    for (std::uint32_t s = 0; s < ra.shard_count(); ++s)
      ASSERT_EQ(ra.read_shard(s), rb.read_shard(s)) << other << " shard " << s;
  }
}

// Two indexes of one model hold the same tables (parts, components, interiors when `interiors`
// says they are stored) and shards.
void expect_same_index(const fs::path& a, const fs::path& b, bool interiors = true) {
  const IndexReader ra(a), rb(b);
  for (const std::string_view table : {"tet_shard", "component_part"})
    EXPECT_EQ(ra.read_table_uint32(table), rb.read_table_uint32(table)) << table;
  if (interiors) {
    EXPECT_EQ(ra.read_table_uint32("interior_components"), rb.read_table_uint32("interior_components"));
    EXPECT_EQ(ra.read_table_uint64("interior_offsets"), rb.read_table_uint64("interior_offsets"));
  }
  EXPECT_EQ(ra.read_table_uint8("component_closed"), rb.read_table_uint8("component_closed"));
  EXPECT_EQ(ra.read_table_double("component_bounds"), rb.read_table_double("component_bounds"));
  EXPECT_EQ(ra.read_table_uint64("part_triangles"), rb.read_table_uint64("part_triangles"));
  EXPECT_EQ(ra.read_table_uint8("part_path_bytes"), rb.read_table_uint8("part_path_bytes"));
  ASSERT_EQ(ra.shard_count(), rb.shard_count());
  for (std::uint32_t s = 0; s < ra.shard_count(); ++s)
    ASSERT_EQ(ra.read_shard(s), rb.read_shard(s)) << "shard " << s;
}

// `input` preprocessed twice, read whole and (forced) in chunks, into whole.tpi and
// chunked.tpi of `folder`, with interiors and regions of `region_triangles`.
std::pair<PreprocessSummary, PreprocessSummary> preprocess_whole_and_in_chunks(
    const fs::path& input, const fs::path& folder, std::uint32_t region_triangles) {
  PreprocessOptions whole;
  whole.region_triangles = region_triangles;
  whole.interiors = true;
  const PreprocessSummary a = preprocess({input}, folder / "whole.tpi", whole);
  EXPECT_EQ(a.files_read_in_chunks, 0u);
  PreprocessOptions chunked = whole;
  chunked.force_spill = true;
  return {a, preprocess({input}, folder / "chunked.tpi", chunked)};
}

// A file read in chunks (as one too large for the budget is) makes the index it makes read
// whole: the same parts, components (closed or not), interiors and shards. CGAL's meshes,
// closed and open, some overlapping, written by CGAL as one soup in PLY, STL and OBJ; about
// 100,000 triangles, so that components cross the chunks' seams.
TEST(Preprocess, AFileReadInChunksWritesTheSameIndex) {
  using Point = CGAL::Exact_predicates_inexact_constructions_kernel::Point_3;
  const fs::path folder = test_folder("chunks");
  std::vector<Point> points;
  std::vector<std::vector<std::size_t>> polygons;
  int copies = 0;
  for (const char* name : {"elephant.off", "knot1.off", "mech-holes-shark.off", "fandisk.off"}) {
    const fs::path path = fs::path(TETRAPAGE_MESH_DIR) / name;
    if (!fs::exists(path)) continue;
    std::vector<Point> mesh_points;
    std::vector<std::vector<std::size_t>> mesh_polygons;
    ASSERT_TRUE(CGAL::IO::read_polygon_soup(path.string(), mesh_points, mesh_polygons)) << name;
    for (int copy = 0; copy < 3; ++copy, ++copies) {
      const std::size_t base = points.size();
      const double shift = 0.37 * copies;  // copies overlap their neighbours
      for (const Point& p : mesh_points) points.emplace_back(p.x() + shift, p.y(), p.z() - shift);
      for (auto polygon : mesh_polygons) {
        for (std::size_t& v : polygon) v += base;
        polygons.push_back(polygon);
      }
    }
  }
  ASSERT_GT(copies, 0) << "no real mesh found under " << TETRAPAGE_MESH_DIR;
  // A manifest in mm placing the PLY once, turned and moved, in cm, beside a part placed three
  // times (read three times in chunks, or once whole and placed in batches).
  const fs::path small = fs::path(TETRAPAGE_MESH_DIR) / "cube-shuffled.off";
  std::ofstream(folder / "assembly.json") << nlohmann::json{
      {"units", "mm"},
      {"parts",
       {{{"name", "soup"}, {"file", "soup.ply"}, {"units", "cm"},
         {"instances", {{{"rotation", {0.9, 0.1, 0.3, 0.2}}, {"translation", {1e3, -2.5, 7.0}}}}}},
        {{"name", "cube"}, {"file", small.string()},
         {"instances", {{{"translation", {0.0, 0.0, 0.0}}}, {{"translation", {10.0, 0.0, 0.0}}},
                        {{"translation", {0.0, 10.0, 0.0}}}}}}}}};
  for (const char* extension : {".ply", ".stl", ".obj", ".json"}) {
    SCOPED_TRACE(extension);
    const fs::path input = folder / (std::string(extension) == ".json" ? std::string("assembly.json")
                                                                        : std::string("soup") + extension);
    if (std::string(extension) != ".json") {
      ASSERT_TRUE(CGAL::IO::write_polygon_soup(input.string(), points, polygons,
                                               CGAL::parameters::use_binary_mode(true)));
    }
    const auto [a, b] = preprocess_whole_and_in_chunks(input, folder, 4000);
    const bool assembly = std::string(extension) == ".json";
    EXPECT_EQ(b.files_read_in_chunks, assembly ? 2u : 1u);
    EXPECT_EQ(a.parts, b.parts);
    EXPECT_EQ(a.degenerate_dropped, b.degenerate_dropped);
    EXPECT_NE(b.to_json().find(assembly ? "\"files_read_in_chunks\": 2" : "\"files_read_in_chunks\": 1"),
              std::string::npos);
    EXPECT_GT(b.triangles_read, 3u * 32768);
    EXPECT_EQ(a.triangles_read, b.triangles_read);
    EXPECT_EQ(a.components, b.components);
    for (const auto& entry : fs::directory_iterator(folder))
      EXPECT_EQ(entry.path().filename().string().find(".tetrapage-spill"), std::string::npos) << entry.path();

    expect_same_index(folder / "whole.tpi", folder / "chunked.tpi");
    const std::vector<std::uint8_t> closed =
        IndexReader(folder / "chunked.tpi").read_table_uint8("component_closed");
    EXPECT_GT(std::count(closed.begin(), closed.end(), 1), 0);
    EXPECT_GT(std::count(closed.begin(), closed.end(), 0), 0);
  }
}

// STEP and IGES files read in chunks (as an assembly too large to hold placed is: each instance
// placed a chunk at a time from its shape's one tessellation) make the index they make read
// whole. OCCT's samples, closed and open, and a manifest in cm placing one (in the mm its reader
// states) three times, turned and scaled: the unit and the deflection come from the file.
TEST(Preprocess, ACadFileReadInChunksWritesTheSameIndex) {
  const fs::path occt = "/usr/share/opencascade/data";
  const fs::path folder = test_folder("cad-chunks");
  const fs::path screw = occt / "step" / "screw.step";
  ASSERT_TRUE(fs::exists(screw)) << "occt-misc (make deps) holds OpenCASCADE's samples";
  std::ofstream(folder / "screws.json") << nlohmann::json{
      {"units", "cm"},
      {"parts",
       {{{"name", "screw"}, {"file", screw.string()},
         {"instances", {{{"translation", {0.0, 0.0, 0.0}}},
                        {{"rotation", {0.9, 0.1, 0.3, 0.2}}, {"translation", {5.0, 0.0, 0.0}}},
                        {{"scale", 2.0}, {"translation", {0.0, 5.0, 0.0}}}}}}}}};
  for (const fs::path& input :
       {occt / "step" / "linkrods.step", occt / "iges" / "bearing.iges", folder / "screws.json"}) {
    SCOPED_TRACE(input.string());
    const auto [a, b] = preprocess_whole_and_in_chunks(input, folder, 2000);
    EXPECT_EQ(b.files_read_in_chunks, 1u);
    EXPECT_EQ(a.parts, b.parts);
    EXPECT_EQ(a.triangles_read, b.triangles_read);
    EXPECT_EQ(a.degenerate_dropped, b.degenerate_dropped);
    EXPECT_EQ(a.components, b.components);
    EXPECT_EQ(a.closed_components, b.closed_components);
    EXPECT_EQ(a.length_unit, b.length_unit);
    EXPECT_EQ(a.tessellation_deflection, b.tessellation_deflection);
    EXPECT_EQ(a.interiors, b.interiors);
    expect_same_index(folder / "whole.tpi", folder / "chunked.tpi", a.interiors.starts_with("stored"));
  }
}

TEST(Preprocess, UncompressedChunksHoldTheSameShards) {
  const fs::path folder = test_folder("compression");
  const fs::path input = make_scene(folder, 20000, 5);
  PreprocessOptions options;
  options.region_triangles = 1000;
  const PreprocessSummary lz4 = preprocess({input}, folder / "lz4.tpi", options);
  options.compression = ChunkCompression::none;
  const PreprocessSummary none = preprocess({input}, folder / "none.tpi", options);
  EXPECT_EQ(lz4.compression, "lz4");
  EXPECT_EQ(none.compression, "none");
  EXPECT_NE(none.to_json().find("\"compression\": \"none\""), std::string::npos);
  const IndexReader a(folder / "lz4.tpi"), b(folder / "none.tpi");
  ASSERT_EQ(a.shard_count(), b.shard_count());
  std::uint64_t stored_lz4 = 0, stored_none = 0, payload = 0;
  for (std::uint32_t s = 0; s < a.shard_count(); ++s) {
    ASSERT_EQ(a.read_shard(s), b.read_shard(s)) << "shard " << s;
    stored_lz4 += a.stored_shard_size(s);
    stored_none += b.stored_shard_size(s);
    payload += b.shard_size(s);
  }
  // As they are, the shards take about their payload (not whole padded chunks), and more than
  // compressed.
  EXPECT_GT(stored_none, stored_lz4);
  EXPECT_LT(stored_none, payload + 1024 * std::uint64_t(b.shard_count()));
  EXPECT_EQ(b.validate(), std::vector<std::string>{});
}

TEST(Preprocess, DeterministicBytes) {
  // A single file, and an assembly of many part files (the ingest parses several at once).
  const fs::path folder = test_folder("deterministic");
  const fs::path assembly = folder / "scene.json";
  {
    static const MeshLibrary library = MeshLibrary::load_default();
    SceneOptions scene;
    scene.triangles = 20000;
    scene.seed = 12;
    MeshWriter writer(assembly);
    generate_scene(library, scene, writer);
    writer.commit();
  }
  for (const fs::path& input : {make_scene(folder, 5000, 11), assembly}) {
    PreprocessOptions options;
    options.region_triangles = 500;
    options.interiors = true;
    const PreprocessSummary all_threads = preprocess({input}, folder / "a.tpi", options);
    options.threads = 1;
    const PreprocessSummary one_thread = preprocess({input}, folder / "b.tpi", options);
    EXPECT_EQ(all_threads.parts, one_thread.parts);
    if (input == assembly) {
      EXPECT_GT(all_threads.parts, 3u);
    }
    EXPECT_EQ(all_threads.closed_components, one_thread.closed_components);
    const IndexReader a(folder / "a.tpi"), b(folder / "b.tpi");
    ASSERT_EQ(a.shard_count(), b.shard_count()) << input;
    for (std::uint32_t s = 0; s < a.shard_count(); ++s) ASSERT_EQ(a.read_shard(s), b.read_shard(s)) << input;
    for (const char* table : {"tet_shard", "interior_components"})
      EXPECT_EQ(a.read_table_uint32(table), b.read_table_uint32(table)) << input << " " << table;
    EXPECT_EQ(a.read_table_uint64("interior_offsets"), b.read_table_uint64("interior_offsets")) << input;
  }
}

std::vector<std::string> listing(const fs::path& folder) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(folder)) names.push_back(entry.path().filename().string());
  return names;
}

TEST(Preprocess, AFullDiskOrAMissingFolderIsAClearErrorAndLeavesNothingBehind) {
  const fs::path folder = test_folder("full-disk");
  fs::create_directories(folder / "in");
  fs::create_directories(folder / "out");
  const fs::path input = make_scene(folder / "in", 80000, 7);
  PreprocessOptions options;
  options.precision = StoredPrecision::float64;  // an index of about 2 MB
  options.memory_bytes = 16 << 20;
  // 64 KiB: the spill files fail first (forced); 1 MiB: the index's temporary file fails.
  for (const rlim_t limit : {rlim_t(64) << 10, rlim_t(1) << 20}) {
    options.force_spill = limit < (rlim_t(1) << 20);
    {
      test::FileSizeLimit full(limit);
      try {
        preprocess({input}, folder / "out" / "model.tpi", options);
        ADD_FAILURE() << "a " << limit << "-byte disk held the index";
      } catch (const IoError& error) {
        EXPECT_NE(std::string(error.what()).find(folder.string()), std::string::npos) << error.what();
      } catch (const Error& error) {
        EXPECT_NE(std::string(error.what()).find("model.tpi"), std::string::npos) << error.what();
      }
    }
    EXPECT_EQ(listing(folder / "out"), std::vector<std::string>{}) << "limit " << limit;
  }
  // The output's folder is missing, or is a file.
  EXPECT_THROW(preprocess({input}, folder / "missing" / "model.tpi", {}), Error);
  EXPECT_THROW(preprocess({input}, input / "model.tpi", {}), Error);
  EXPECT_FALSE(fs::exists(folder / "missing"));
  EXPECT_EQ(listing(folder / "in"), std::vector<std::string>{"scene.ply"});
}

TEST(PreprocessCommand, KilledMidRunLeavesNoIndexUnderTheOutputName) {
  const fs::path folder = test_folder("killed");
  const fs::path input = make_scene(folder, 150000, 3);
  const fs::path output = folder / "model.tpi";
  int killed_while_running = 0;
  // Preprocess of this scene takes about 0.1 s on the development machine.
  for (const int milliseconds : {20, 40, 70, 100, 250, 500}) {
    fs::remove(output);
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      const int null = ::open("/dev/null", O_WRONLY);
      ::dup2(null, 1);
      ::dup2(null, 2);
      ::execl(TETRAPAGE_CLI, "tetrapage", "preprocess", input.c_str(), "-o", output.c_str(), "--memory", "16M",
              static_cast<char*>(nullptr));
      ::_exit(127);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(milliseconds));
    ::kill(child, SIGKILL);
    int status = 0;
    ::waitpid(child, &status, 0);
    if (WIFSIGNALED(status)) {
      ++killed_while_running;
      EXPECT_FALSE(fs::exists(output)) << "killed after " << milliseconds << " ms";
    } else {
      // It finished first: then the index is whole.
      EXPECT_EQ(IndexReader(output).validate(), std::vector<std::string>{}) << milliseconds << " ms";
    }
  }
  EXPECT_GT(killed_while_running, 1) << "the kills must land while preprocess runs";
}

TEST(Preprocess, BadInputLeavesNothingBehind) {
  const fs::path folder = test_folder("bad");
  {
    std::ofstream obj(folder / "nan.obj");
    obj << "v 0 0 0\nv 1 0 0\nv 0 nan 1\nf 1 2 3\n";
  }
  {
    std::ofstream obj(folder / "empty.obj");
    obj << "# nothing\n";
  }
  {
    std::ofstream obj(folder / "degenerate.obj");  // collinear corners, a repeated corner
    obj << "v 0 0 0\nv 1 1 1\nv 2 2 2\nv 0 1 0\nf 1 2 3\nf 1 4 4\n";
  }
  EXPECT_THROW(preprocess({folder / "missing.ply"}, folder / "out.tpi", {}), IoError);
  EXPECT_THROW(preprocess({folder / "nan.obj"}, folder / "out.tpi", {}), Error);
  EXPECT_THROW(preprocess({folder / "empty.obj"}, folder / "out.tpi", {}), Error);
  try {
    preprocess({folder / "degenerate.obj"}, folder / "out.tpi", {});
    ADD_FAILURE() << "an all-degenerate model preprocessed";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("degenerate"), std::string::npos) << error.what();
  }
  PreprocessOptions tiny;
  tiny.memory_bytes = 1000;
  EXPECT_THROW(preprocess({folder / "nan.obj"}, folder / "out.tpi", tiny), InputError);
  for (const auto& entry : fs::directory_iterator(folder)) {
    const std::string name = entry.path().filename().string();
    EXPECT_TRUE(name == "nan.obj" || name == "empty.obj" || name == "degenerate.obj") << "left behind: " << name;
  }
}

}  // namespace
}  // namespace tetrapage
