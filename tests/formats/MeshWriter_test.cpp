// The mesh writers: round trips through our readers (bit-exact where the format stores
// doubles), CGAL's reader as an independent check of what we write, determinism, and the
// guarantee that a failed or abandoned write leaves nothing under the output name.

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/polygon_soup_io.h>

#include <fstream>
#include <map>

#include <nlohmann/json.hpp>

#include "../FileSizeLimit.h"
#include "TestSupport.h"
#include "tetrapage/formats/mesh/Manifest.h"
#include "tetrapage/formats/mesh/MeshWriter.h"

namespace tetrapage::test {
namespace {

bool is_float_format(const std::string& extension) {
  return extension == ".stl" || extension == ".gltf" || extension == ".glb";
}

class WriterRoundTrip : public ::testing::TestWithParam<std::string> {};

TEST_P(WriterRoundTrip, RandomSoupsReadBackEqual) {
  const std::string extension = GetParam();
  const auto folder = scratch_folder("round_trip" + extension);
  for (std::uint64_t seed : {1u, 2u, 3u, 4u, 5u}) {
    const int parts = 1 + static_cast<int>(seed % 3);
    const TriangleSoup soup = random_soup(seed, parts, 50 + 40 * static_cast<int>(seed));
    const auto path = folder / ("mesh" + extension);
    write_mesh(path, soup);
    ReadReport report;
    const TriangleSoup back = read_mesh(path, &report);
    ASSERT_EQ(back.triangle_count(), soup.triangle_count()) << "seed " << seed;
    EXPECT_EQ(report.degenerate_dropped, 0u) << "seed " << seed;
    // Triangles come back in part order, corners in order.
    for (std::size_t t = 0; t < soup.triangle_count(); ++t) {
      auto expected = soup.corners(t);
      if (is_float_format(extension))
        for (auto& corner : expected) corner = to_float(corner);
      ASSERT_EQ(back.corners(t), expected) << "seed " << seed << " triangle " << t;
    }
    if (mesh_format_keeps_parts(path)) {
      ASSERT_EQ(back.part_count(), soup.part_count()) << "seed " << seed;
      for (std::size_t t = 0; t < soup.triangle_count(); ++t)
        EXPECT_EQ(back.part_of[t], soup.part_of[t]) << "seed " << seed;
      // OBJ and PLY keep the names; Assimp names glTF nodes "stem/node" when there are several.
      for (std::size_t p = 0; p < soup.part_count(); ++p) {
        const bool assimp = extension == ".gltf" || extension == ".glb";
        EXPECT_EQ(back.part_names[p], !assimp                  ? soup.part_names[p]
                                      : soup.part_count() == 1 ? std::string("mesh")
                                                               : "mesh/" + soup.part_names[p]);
      }
    } else {
      EXPECT_EQ(back.part_names, std::vector<std::string>{"mesh"});
    }
    if (soup.part_count() == 1 && !is_float_format(extension)) {
      // A single part is written as it is: same vertex list (unused vertices too), same indices.
      EXPECT_EQ(back.vertices, soup.vertices) << "seed " << seed;
      EXPECT_EQ(back.triangles, soup.triangles) << "seed " << seed;
    }
  }
  EXPECT_EQ(folder_listing(folder), std::vector<std::string>{"mesh" + extension});
}

INSTANTIATE_TEST_SUITE_P(Formats, WriterRoundTrip,
                         ::testing::Values(".obj", ".ply", ".off", ".stl", ".gltf", ".glb"),
                         [](const auto& param_info) { return param_info.param.substr(1); });

TEST(MeshWriter, LargeSoupsSpanManyReadBlocks) {
  // Files of several MiB: lines and records straddle the readers' 4 MiB blocks.
  const auto folder = scratch_folder("round_trip_large");
  const TriangleSoup soup = random_soup(12, 1, 200000);
  for (const std::string extension : {".obj", ".ply", ".off", ".stl"}) {
    const auto path = folder / ("large" + extension);
    write_mesh(path, soup);
    EXPECT_GT(std::filesystem::file_size(path), 4u << 20) << extension;  // > one block
    const TriangleSoup back = read_mesh(path);
    ASSERT_EQ(back.triangle_count(), soup.triangle_count()) << extension;
    if (extension == ".stl") {
      for (std::size_t t = 0; t < soup.triangle_count(); ++t) {
        auto expected = soup.corners(t);
        for (auto& corner : expected) corner = to_float(corner);
        ASSERT_EQ(back.corners(t), expected) << "seed 12 triangle " << t;
      }
    } else {
      ASSERT_EQ(back.vertices, soup.vertices) << extension << " seed 12";
      ASSERT_EQ(back.triangles, soup.triangles) << extension << " seed 12";
    }
    std::filesystem::remove(path);
  }
}

TEST(MeshWriter, CgalReadsWhatWeWrite) {
  using Point = CGAL::Exact_predicates_inexact_constructions_kernel::Point_3;
  const auto folder = scratch_folder("cgal_reads");
  const TriangleSoup soup = random_soup(77, 2, 120);
  for (const std::string extension : {".obj", ".ply", ".off", ".stl"}) {
    const auto path = folder / ("mesh" + extension);
    write_mesh(path, soup);
    std::vector<Point> points;
    std::vector<std::vector<std::size_t>> polygons;
    ASSERT_TRUE(CGAL::IO::read_polygon_soup(path.string(), points, polygons)) << extension;
    ASSERT_EQ(polygons.size(), soup.triangle_count()) << extension;
    for (std::size_t t = 0; t < polygons.size(); ++t) {
      ASSERT_EQ(polygons[t].size(), 3u);
      const auto expected = soup.corners(t);
      for (int k = 0; k < 3; ++k) {
        const Point& p = points[polygons[t][k]];
        const Vec3 corner{p.x(), p.y(), p.z()};
        ASSERT_EQ(corner, extension == ".stl" ? to_float(expected[k]) : expected[k])
            << extension << " triangle " << t << " corner " << k;
      }
    }
  }
}

TEST(MeshWriter, SameInputSameBytes) {
  const auto folder = scratch_folder("deterministic");
  const TriangleSoup soup = random_soup(9, 2, 80);
  for (const std::string extension : {".obj", ".ply", ".off", ".stl", ".gltf", ".glb"}) {
    write_mesh(folder / ("a" + extension), soup);
    write_mesh(folder / ("b" + extension), soup);
    const std::string a = read_file(folder / ("a" + extension));
    EXPECT_FALSE(a.empty());
    EXPECT_EQ(a, read_file(folder / ("b" + extension))) << extension;
  }
}

TEST(MeshWriter, StreamsPartsWithGlobalIndicesAndCounts) {
  const auto folder = scratch_folder("parts");
  const std::vector<Vec3> square = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  const std::vector<TriangleIndices> two = {{0, 1, 2}, {0, 2, 3}};
  const std::vector<Vec3> lifted = {{0, 0, 5}, {1, 0, 5}, {0, 1, 5}};
  const std::vector<TriangleIndices> one = {{0, 1, 2}};
  for (const std::string extension : {".obj", ".ply", ".off"}) {
    const auto path = folder / ("p" + extension);
    MeshWriter writer(path);
    writer.add_part(square, two);
    writer.add_part(lifted, one);
    EXPECT_EQ(writer.triangles_written(), 3u);
    EXPECT_EQ(writer.vertices_written(), 7u);
    EXPECT_FALSE(std::filesystem::exists(path)) << "visible before commit";
    writer.commit();
    writer.commit();  // a second commit does nothing
    ASSERT_TRUE(std::filesystem::exists(path));
    const TriangleSoup back = read_mesh(path);
    EXPECT_EQ(back.triangles, (std::vector<TriangleIndices>{{0, 1, 2}, {0, 2, 3}, {4, 5, 6}}))
        << extension;
    EXPECT_EQ(back.vertices[6], (Vec3{0, 1, 5}));
    expect_error<InputError>([&] { writer.add_part(lifted, one); }, {path.string(), "commit"});
  }
  EXPECT_EQ(folder_listing(folder), (std::vector<std::string>{"p.obj", "p.off", "p.ply"}));
}

TEST(MeshWriter, AManifestHoldsOnePlyPerPartAndReadsBackAsTheAssembly) {
  const auto folder = scratch_folder("manifest");
  const TriangleSoup first = random_soup(5, 1, 30), second = random_soup(6, 1, 20);
  const auto path = folder / "assembly.json";
  {
    MeshWriter abandoned(path);
    abandoned.add_part(first.vertices, first.triangles);
  }
  EXPECT_TRUE(folder_listing(folder).empty()) << "an abandoned manifest leaves no part file";
  MeshWriter writer(path);
  writer.add_part(first.vertices, first.triangles);
  writer.add_part(second.vertices, second.triangles);
  EXPECT_FALSE(std::filesystem::exists(path));
  writer.commit();
  EXPECT_EQ(folder_listing(folder), (std::vector<std::string>{"assembly.json", "assembly.parts"}));
  EXPECT_EQ(folder_listing(folder / "assembly.parts"), (std::vector<std::string>{"part-000000.ply", "part-000001.ply"}));
  const TriangleSoup back = load_assembly(read_manifest(path));
  ASSERT_EQ(back.part_count(), 2u);
  ASSERT_EQ(back.triangle_count(), first.triangle_count() + second.triangle_count());
  for (std::size_t t = 0; t < first.triangle_count(); ++t) EXPECT_EQ(back.corners(t), first.corners(t));
  for (std::size_t t = 0; t < second.triangle_count(); ++t)
    EXPECT_EQ(back.corners(first.triangle_count() + t), second.corners(t));
  EXPECT_EQ(back.part_of.back(), 1u);
}

// Names and instance paths through the formats that hold parts: OBJ (o/g lines), PLY (the part
// table), manifests (the names listed are the paths, unique); STL and OFF hold one part.
TEST(MeshWriter, PartNamesAndPathsSurvive) {
  const auto folder = scratch_folder("part_names");
  TriangleSoup soup = random_soup(21, 6, 12);
  soup.part_names = {"frame", "U7", "U7", "bolt", "a b", "frame"};
  soup.part_paths = {"frame", "rack/board#3/U7", "rack/board#4/U7", "kit", "a b", "spare/frame"};
  for (const std::string extension : {".obj", ".ply", ".stl", ".off", ".json"}) {
    SCOPED_TRACE(extension);
    const auto path = folder / ("parts" + extension);
    write_mesh(path, soup);
    if (extension == ".json") {
      std::ifstream in(path);
      const auto manifest = nlohmann::json::parse(in);
      ASSERT_EQ(manifest.at("parts").size(), soup.part_count());
      for (std::size_t p = 0; p < soup.part_count(); ++p)
        EXPECT_EQ(manifest["parts"][p]["name"].get<std::string>(), soup.part_path(p));
      const TriangleSoup back = load_assembly(read_manifest(path));
      EXPECT_EQ(back.part_of, soup.part_of);
      continue;
    }
    const TriangleSoup back = read_mesh(path);
    ASSERT_EQ(back.triangle_count(), soup.triangle_count());
    if (!mesh_format_keeps_parts(path)) {
      EXPECT_EQ(back.part_names, std::vector<std::string>{"parts"});
      continue;
    }
    // Another reader skips what it does not know (the part table, o and g lines).
    EXPECT_EQ(read_mesh_with_assimp(path).triangle_count(), soup.triangle_count());
    EXPECT_EQ(back.part_names, soup.part_names);
    EXPECT_EQ(back.part_of, soup.part_of);
    for (std::size_t p = 0; p < soup.part_count(); ++p) {
      // OBJ cannot say that "bolt" sits at "kit": it reads back as "kit/bolt".
      const bool reshaped = extension == ".obj" && soup.part_names[p] == "bolt";
      EXPECT_EQ(back.part_path(p), reshaped ? "kit/bolt" : soup.part_path(p)) << "part " << p;
    }
  }
}

// A part streamed in pieces (extend_part) is one part for every reader; unnamed parts after
// the first are "part<k>", the first takes the file's stem.
TEST(MeshWriter, ExtendPartContinuesThePartAddedLast) {
  const auto folder = scratch_folder("extend_part");
  const TriangleSoup pieces = random_soup(31, 4, 10);  // four pieces of 10 triangles
  const auto piece = [&](std::size_t k) {
    return std::span<const TriangleIndices>(pieces.triangles).subspan(10 * k, 10);
  };
  for (const std::string extension : {".obj", ".ply", ".gltf", ".glb", ".stl", ".off"}) {
    SCOPED_TRACE(extension);
    const auto path = folder / ("streamed" + extension);
    MeshWriter writer(path);
    expect_error<InputError>([&] { writer.extend_part(pieces.vertices, piece(0)); },
                             {path.string(), "before add_part"});
    writer.add_part(pieces.vertices, piece(0));
    writer.extend_part(pieces.vertices, piece(1));
    writer.add_part(pieces.vertices, piece(2));
    writer.extend_part(pieces.vertices, piece(3));
    EXPECT_EQ(writer.parts_written(), 2u);
    writer.commit();
    const TriangleSoup back = read_mesh(path);
    ASSERT_EQ(back.triangle_count(), 40u);
    if (!mesh_format_keeps_parts(path)) {
      EXPECT_EQ(back.part_count(), 1u);
      continue;
    }
    ASSERT_EQ(back.part_count(), 2u);
    for (std::size_t t = 0; t < 40; ++t) EXPECT_EQ(back.part_of[t], t < 20 ? 0u : 1u) << t;
    if (extension == ".obj" || extension == ".ply") {
      EXPECT_EQ(back.part_names, (std::vector<std::string>{"streamed", "part1"}));
    }
  }
}

// An OBJ file that returns to an earlier group: its parts are not consecutive. Written part
// by part, every part keeps its triangles in their order.
TEST(MeshWriter, PartsThatInterleaveAreWrittenPartByPart) {
  const auto folder = scratch_folder("interleaved");
  write_file(folder / "in.obj",
             "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
             "g a\nf 1 2 3\ng b\nf 1 2 4\ng a\nf 1 3 4\ng b\nf 2 3 4\ng a\nf 1 4 2\n");
  const TriangleSoup soup = read_mesh(folder / "in.obj");
  ASSERT_EQ(soup.part_count(), 2u);
  for (const std::string extension : {".obj", ".ply"}) {
    write_mesh(folder / ("out" + extension), soup);
    const TriangleSoup back = read_mesh(folder / ("out" + extension));
    ASSERT_EQ(back.part_names, soup.part_names) << extension;
    for (std::uint32_t p = 0; p < 2; ++p) {
      std::vector<std::array<Vec3, 3>> before, after;
      for (std::size_t t = 0; t < soup.triangle_count(); ++t)
        if (soup.part_of[t] == p) before.push_back(soup.corners(t));
      for (std::size_t t = 0; t < back.triangle_count(); ++t)
        if (back.part_of[t] == p) after.push_back(back.corners(t));
      EXPECT_EQ(after, before) << extension << " part " << p;
    }
    EXPECT_TRUE(std::is_sorted(back.part_of.begin(), back.part_of.end())) << extension;
  }
}

TEST(MeshWriter, EmptyFilesAreValidAndReadAsEmpty) {
  const auto folder = scratch_folder("empty");
  for (const std::string extension : {".obj", ".ply", ".off", ".stl", ".gltf", ".glb"}) {
    const auto path = folder / ("empty" + extension);
    MeshWriter writer(path);
    writer.commit();
    ASSERT_TRUE(std::filesystem::exists(path)) << extension;
    expect_error<InputError>([&] { read_mesh(path); }, {path.string(), "no triangle"});
  }
}

TEST(MeshWriter, AbandonedWriterLeavesNoFile) {
  const auto folder = scratch_folder("abandoned");
  const TriangleSoup soup = random_soup(3, 1, 40);
  for (const std::string extension : {".obj", ".ply", ".off", ".stl", ".gltf", ".glb"}) {
    {
      MeshWriter writer(folder / ("out" + extension));
      writer.add_part(soup.vertices, soup.triangles);
      EXPECT_FALSE(folder_listing(folder).empty());  // the temporaries exist meanwhile
    }
    EXPECT_TRUE(folder_listing(folder).empty()) << extension;
  }
  // An existing file under the output name is untouched by an abandoned write.
  write_file(folder / "keep.obj", "old");
  {
    MeshWriter writer(folder / "keep.obj");
    writer.add_part(soup.vertices, soup.triangles);
  }
  EXPECT_EQ(read_file(folder / "keep.obj"), "old");
}

TEST(MeshWriter, BadArgumentsAndFolders) {
  const auto folder = scratch_folder("writer_errors");
  EXPECT_TRUE(can_write_mesh("a/b.OBJ"));
  EXPECT_TRUE(can_write_mesh("b.glb"));
  EXPECT_FALSE(can_write_mesh("b.3ds"));
  EXPECT_FALSE(can_write_mesh("b"));
  const auto unknown = folder / "out.xyz";
  expect_error<InputError>([&] { MeshWriter writer(unknown); }, {unknown.string(), ".xyz"});
  const auto nowhere = folder / "missing" / "out.obj";
  expect_error<IoError>([&] { MeshWriter writer(nowhere); }, {nowhere.string()});
  MeshWriter writer(folder / "out.ply");
  const std::vector<Vec3> vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const std::vector<TriangleIndices> bad = {{0, 1, 3}};
  expect_error<InputError>([&] { writer.add_part(vertices, bad); }, {"out.ply", "vertex 3"});
  const std::vector<Vec3> nan_vertices = {{0, 0, 0}, {1, std::nan(""), 0}, {0, 1, 0}};
  const std::vector<TriangleIndices> good = {{0, 1, 2}};
  expect_error<InputError>([&] { writer.add_part(nan_vertices, good); }, {"out.ply", "vertex 1"});
  TriangleSoup inconsistent = random_soup(1, 2, 10);
  inconsistent.part_of.pop_back();
  expect_error<InputError>([&] { write_mesh(folder / "x.obj", inconsistent); }, {"x.obj"});
}

TEST(MeshWriter, WriteFailureIsAnIoErrorNamingTheFile) {
  const auto folder = scratch_folder("disk_full");
  const TriangleSoup soup = random_soup(11, 1, 20000);  // well over the limit in every format
  for (const std::string extension : {".obj", ".ply", ".off", ".stl", ".glb"}) {
    const auto path = folder / ("full" + extension);
    {
      test::FileSizeLimit limit(64 * 1024);
      expect_error<IoError>([&] { write_mesh(path, soup); }, {path.string(), "too large"});
    }
    EXPECT_TRUE(folder_listing(folder).empty()) << extension;
  }
}

}  // namespace
}  // namespace tetrapage::test
